"""Tooling compensation (index balancing): the tooling's unbalance, measured once, subtracted
from every later run of that tooling.

A rotor that sits on an adapter, a mandrel or a drive coupling carries the tooling's
unbalance into every answer.  Two runs separate them (:func:`stand.core.balance.index_split`):
the rotor on its tooling as usual, then turned 180 deg on it.  The tooling's unbalance is
kept per tooling (``[tooling] name``) as a small JSON file, with its date, the config's
digest and both runs; every run whose config names the tooling has it subtracted, its
covariance added to the run's (the 95 % intervals hold both).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from stand.config import data_folder
from stand.core.model import MAX_SPEED_RPM, rpm_to_rad_s
from stand.errors import ConfigError, RecordingError
from stand.files import output, strict_json
from stand.measuring import with_unbalance_covariance

TOOLING_VERSION = 1
"""Version of the stored tooling file."""
TOOLING_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")
"""What a tooling may be called (its file's name): the config's ``[tooling] name`` rule."""


@dataclass(frozen=True)
class Tooling:
    """A tooling's unbalance [kg m] per plane (at index 0), its covariance (real 4 x 4),
    when it was measured (ISO 8601, UTC), the config's SHA-256, the two runs, the speed
    [rad/s] and where it is kept."""

    name: str
    U_kg_m: tuple[complex, complex]
    cov_U: np.ndarray
    measured: str
    config_sha256: str
    runs: tuple[str, str]
    omega_rad_s: float
    path: str = ""

    def to_json(self) -> dict[str, Any]:
        """The stored form (SI units, complex numbers as ``[re, im]``)."""
        return {
            "tooling_version": TOOLING_VERSION,
            "name": self.name,
            "measured": self.measured,
            "config_sha256": self.config_sha256,
            "runs": list(self.runs),
            "omega_rad_s": self.omega_rad_s,
            "unbalance_kg_m": [[u.real, u.imag] for u in self.U_kg_m],
            "cov_U": np.asarray(self.cov_U, dtype=float).tolist(),
        }


def folder(table: Any | None) -> Path:
    """Where a ``[tooling]`` table's measurements are kept (no table: the data folder's
    ``tooling``)."""
    if table is not None and table.folder:
        return Path(table.folder)
    return data_folder() / "tooling"


def tooling_file(name: str, where: Path) -> Path:
    """The file of the tooling ``name`` in ``where``."""
    return where / f"{name}.json"


MAX_FILE_BYTES = 1 << 20
"""A tooling file is under 4 kB; one over 1 MiB is not read."""
MAX_TOOLING_KG_M = 1.0
"""No tooling (a mandrel, an adapter) carries 1 kg m of unbalance: 1 kg at 1 m."""


def _bounded(U: list[complex], cov: np.ndarray, omega_rad_s: float) -> None:
    """Refuse values no measured tooling has (ValueError, said as "not a tooling file")."""
    if not all(abs(u) <= MAX_TOOLING_KG_M for u in U):
        raise ValueError(f"an unbalance beyond {MAX_TOOLING_KG_M:g} kg m")
    if not (np.allclose(cov, cov.T) and np.all(np.diag(cov) >= 0) and np.all(np.abs(cov) <= 1)):
        raise ValueError("its covariance is not one (symmetric, variances >= 0, <= 1 kg^2 m^2)")
    if not 0 < omega_rad_s <= float(rpm_to_rad_s(MAX_SPEED_RPM)):
        raise ValueError(f"a speed of {omega_rad_s!r} rad/s")


def load_tooling(name: str, where: Path) -> Tooling:
    """The stored tooling ``name`` (ConfigError, naming ``[tooling.name]``, when it has not
    been measured; RecordingError when its file is not a tooling)."""
    path = tooling_file(name, where)
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise ValueError(f"{path.stat().st_size} bytes; one is under 4 kB")
        data = strict_json(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(
            f"the tooling {name!r} has not been measured (no {path}): run `stand tooling "
            "measure RUN_0 RUN_180` first",
            key="tooling.name",
        ) from None
    except (OSError, ValueError) as exc:  # unreadable, not UTF-8, not strict JSON, too large
        raise RecordingError(f"not a tooling file ({exc})", path=str(path)) from None
    try:
        if data["tooling_version"] != TOOLING_VERSION or data["name"] != name:
            raise ValueError("another version or another tooling's name")
        U = [complex(float(re), float(im)) for re, im in data["unbalance_kg_m"]]
        cov = np.asarray(data["cov_U"], dtype=float)
        if len(U) != 2 or cov.shape != (4, 4) or not np.all(np.isfinite(cov)):
            raise ValueError("two planes and a 4 x 4 covariance expected")
        _bounded(U, cov, float(data["omega_rad_s"]))
        return Tooling(
            name,
            (U[0], U[1]),
            cov,
            str(data["measured"]),
            str(data["config_sha256"]),
            (str(data["runs"][0]), str(data["runs"][1])),
            float(data["omega_rad_s"]),
            str(path),
        )
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise RecordingError(f"not a tooling file ({exc})", path=str(path)) from None


def compensate(m: Any, t: Tooling) -> Any:
    """The measurement ``m`` (:class:`stand.measuring.measure.Measurement`) with the tooling's
    unbalance subtracted and its covariance added (the 95 % radii follow)."""
    U = np.asarray(m.solution.U_kg_m) - np.asarray(t.U_kg_m)
    cov = np.asarray(m.solution.cov_U).real + t.cov_U
    sol = replace(m.solution, U_kg_m=U, static_kg_m=complex(U[0] + U[1]))
    return replace(with_unbalance_covariance(replace(m, solution=sol), cov), tooling=t)


def save_tooling(t: Tooling, where: Path, *, force: bool = False) -> Path:
    """Keep the tooling's measurement (written safely; an existing one only with ``force``)."""

    path = tooling_file(t.name, where)
    where.mkdir(parents=True, exist_ok=True)
    with output(path, force=force) as tmp:
        tmp.write_text(json.dumps(t.to_json(), indent=1, allow_nan=False) + "\n")
    return path


def stored_toolings(where: Path) -> list[Tooling]:
    """Every tooling kept in ``where`` (files that are not one are skipped)."""
    found = []
    for p in sorted(where.glob("*.json")) if where.is_dir() else []:
        try:
            found.append(load_tooling(p.stem, where))
        except (ConfigError, RecordingError):
            continue
    return found
