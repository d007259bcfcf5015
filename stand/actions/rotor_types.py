"""A rotor type's configuration: replaced (a setter loads one, an engineer changes its
tolerance or recalibrates it) with the file it replaces kept in ``.history/``, or found
changed on disk before a run; each journaled in the same transaction."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

from stand.actions.door import Actor, Rights, door
from stand.archive import Archive
from stand.archive.audit import Change, file_sha256, sha256_of
from stand.archive.schema import audit
from stand.config import config_parts
from stand.errors import WriteError


def replace_config(url: str, actor: Actor, path: Path, text: str, *, right: Rights,
                   what: str, reason: str, action: str = "config") -> int:  # fmt: skip
    """Keep the file ``path`` replaces in ``.history/`` beside it (named by the time, UTC),
    write ``text`` in its place and journal it (``action``: ``config``, or
    ``calibration``); the audit entry's id."""
    old = file_sha256(path)
    with door(url, actor, right, what) as p:
        if old is not None:
            stamp = dt.datetime.now(dt.UTC).strftime("%Y%m%dT%H%M%S%fZ")
            kept = path.parent / ".history" / f"{path.stem}-{stamp}.toml"
            try:
                kept.parent.mkdir(exist_ok=True)
            except OSError as exc:
                raise WriteError(f"cannot keep the file it replaces here ({exc.strerror}): "
                                 "nothing changed", path=str(kept.parent)) from exc  # fmt: skip
            p.write(kept, path.read_bytes())
        p.write(path, text.encode("utf-8"), force=True)
        return p.journal(Change(action, path.name, old, sha256_of(text), reason,
                                detail={"file": path.name, **config_parts(text)}))  # fmt: skip


def config_seen(url: str, actor: Actor, path: str | Path) -> int | None:
    """A rotor type's configuration about to be measured with: one ``config`` entry when
    its SHA-256 is not the one the journal last recorded for that file (edited on disk
    since, or first used); the entry's id, or None when nothing changed.  Who edited it
    is not known here: the entry says who found it."""
    import sqlalchemy as sa

    name = Path(path).name
    new = file_sha256(path)
    with Archive(url) as archive, archive.transaction() as conn:
        last = conn.execute(sa.select(audit.c.new_sha256).where(
            audit.c.action.in_(("config", "calibration")), audit.c.subject == name)
            .order_by(audit.c.id.desc()).limit(1)).scalar()  # fmt: skip
    if new is None or last == new:
        return None
    why = "first used" if last is None else "changed on disk since the last entry"
    text = Path(path).read_text(encoding="utf-8", errors="replace")
    with door(url, actor, None, "use a rotor type") as p:
        return p.journal(Change("config", name, last, new,
                                f"{why}; found by {actor.name} before a run",
                                detail={"file": name, **config_parts(text)}))  # fmt: skip
