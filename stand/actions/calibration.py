"""The stand's calibration and the influence matrices it balances with: an engineer's
right (``calibrate``), each file written and journaled in one transaction."""

from __future__ import annotations

from pathlib import Path

from stand.actions.door import Actor, door
from stand.archive.audit import Change, file_sha256, sha256_of
from stand.config import config_parts


def save_calibration(url: str, actor: Actor, path: str | Path, text: str, *, config: str,
                     force: bool, inputs: tuple[str | Path, ...] = (),
                     reason: str | None = None) -> int:  # fmt: skip
    """Write a calibrated configuration to ``path`` and journal it (the SHA-256 before:
    the file replaced, else the config ``config`` it came from); the audit entry."""
    old = file_sha256(path) or file_sha256(config)
    with door(url, actor, "calibrate", "calibrate the stand") as p:
        p.write(path, text.encode("utf-8"), force=force, inputs=inputs)
        name = Path(path).name
        return p.journal(Change("calibration", f"{name} (from {Path(config).name})", old,
                                sha256_of(text), reason,
                                detail={"file": name, **config_parts(text)}))  # fmt: skip


def save_matrix(url: str, actor: Actor, path: str | Path, text: str, *, force: bool,
                inputs: tuple[str | Path, ...] = (), reason: str | None = None) -> int:  # fmt: skip
    """Write an influence matrix to ``path`` and journal it; the audit entry."""
    old = file_sha256(path)
    with door(url, actor, "calibrate", "save an influence matrix") as p:
        p.write(path, text.encode("utf-8"), force=force, inputs=inputs)
        return p.journal(Change("matrix", Path(path).name, old, sha256_of(text), reason,
                                detail={"file": Path(path).name}))  # fmt: skip
