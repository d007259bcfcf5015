"""A stored influence matrix: its one schema, how it is written and read back.

``stand influence RUNS.toml --save M.json`` stores the matrix measured by
trial runs (permanent calibration of a rotor type); ``stand balance
--matrix M.json`` (and ``solve``, ``measure``, ``influence``) use it in place
of the stand model.  The file says what the matrix is good for: the speed
it was measured at, the rotor type, when, with which configuration, from
which runs; used at another speed it draws a warning, for another rotor
type it is refused.
"""

from __future__ import annotations

import datetime as dt
import json
from dataclasses import dataclass, field
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, Field, FiniteFloat

from stand.config.schema import STRICT, validate
from stand.config.tables import Reading, Rpm
from stand.core import Diagnostic, rad_s_to_rpm
from stand.core.influence import InfluenceMap
from stand.drivers.runs.recording import MATRIX_ATTR
from stand.errors import ConfigError, ModelError, RecordingError
from stand.files import check_input
from stand.i18n.words import said

KIND = "stand influence matrix"
SAME_SPEED = 0.05
"""Two runs within 5 % of each other's speed are at the same speed: a check run and the run
it checks, an influence matrix and the run it solves.  The unbalance is the same at any
speed, but the stand's response (each influence coefficient, about as the speed's square
on a soft-bearing stand) and its errors are not."""

Pair = Annotated[list[Reading], Field(min_length=2, max_length=2)]


class StoredMatrix(BaseModel):
    """The JSON file (``alpha`` as ``[re, im]`` pairs, supports x planes)."""

    model_config = STRICT

    kind: Literal["stand influence matrix"]
    version: Literal[1]
    readings: Literal["support acceleration", "typed in"]
    """Support acceleration [m/s^2]: usable on the stand; typed in: another instrument's units."""
    alpha_per_kg_m: Annotated[list[list[Pair]], Field(min_length=1)]
    """``dA / dU`` [reading per kg m], ``U = q R e^{-i phi}``."""
    cov_alpha: list[list[Annotated[FiniteFloat, Field(ge=-1e24, le=1e24)]]] | None = None
    rpm: Rpm | None = None
    speeds_rpm: list[Rpm | None] | None = None
    """Each row's speed, for a matrix of readings at several speeds (``stand influence`` in
    N planes); None: one speed (``rpm``)."""
    rotor_type: str | None = None
    created: str
    config_sha256: str | None = None
    runs: list[str] = []


def matrix_document(
    imap: InfluenceMap,
    *,
    readings: str,
    rpm: float | None,
    rotor_type: str | None,
    config_sha256: str | None,
    runs: list[str],
) -> dict[str, Any]:
    """The JSON object that stores ``imap`` and what it is good for."""
    alpha = np.asarray(imap.alpha)
    return {
        "kind": KIND,
        "version": 1,
        "readings": readings,
        "alpha_per_kg_m": [[[float(z.real), float(z.imag)] for z in row] for row in alpha],
        "cov_alpha": None if imap.cov_alpha is None else np.asarray(imap.cov_alpha).tolist(),
        "rpm": rpm,
        "rotor_type": rotor_type,
        "created": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        "config_sha256": config_sha256,
        "runs": runs,
    }


@dataclass(frozen=True)
class LoadedMatrix:
    """A stored matrix read back: the map the inverse uses, what the file says, where."""

    imap: InfluenceMap
    stored: StoredMatrix
    path: str
    text: str = field(repr=False, default="")

    def check(self, rotor_type: str | None, *, live: bool) -> None:
        """Refuse it for another rotor type, typed-in readings on the stand, or a matrix of
        readings at several speeds (it serves the stand's answer at one)."""
        stored, path = self.stored, self.path
        if stored.speeds_rpm and len(set(stored.speeds_rpm)) > 1:
            raise ConfigError(
                "a matrix of readings at several speeds: it serves stand influence's runs "
                "file, not one run's two-plane answer",
                source=path,
                key="speeds_rpm",
            )
        if live and stored.readings != "support acceleration":
            raise ConfigError(
                "made from typed-in readings (another instrument's units): the stand's own "
                "runs need a matrix made from recorded runs",
                source=path,
                key="readings",
            )
        if stored.rotor_type and rotor_type and stored.rotor_type != rotor_type:
            raise ConfigError(
                f"measured on rotor type {stored.rotor_type!r}, the config's is {rotor_type!r}",
                source=path,
                key="rotor_type",
            )

    def speed_note(self, omega_rad_s: float) -> Diagnostic | None:
        """A warning when used more than ``SAME_SPEED`` away from the speed it was measured at."""
        if self.stored.rpm is None:
            return None
        rpm = float(rad_s_to_rpm(omega_rad_s))
        off = rpm / self.stored.rpm - 1
        if abs(off) <= SAME_SPEED:
            return None
        return Diagnostic(
            "matrix_speed",
            said(
                "the influence matrix {path} was measured at {rpm_then} rpm, this run is at "
                "{rpm} rpm ({off} %): the stand answers differently at another speed, so the "
                "correction may be off; run at the matrix's speed or make trial runs at this "
                "one",
                path=self.path,
                rpm_then=f"{self.stored.rpm:.0f}",
                rpm=f"{rpm:.0f}",
                off=f"{100 * off:+.0f}",
            ),
            off,
        )

    def run_attrs(self) -> dict[str, str]:
        """What a run solved with it stores, so that it is reprocessed with it."""

        return {MATRIX_ATTR: self.text}


def read_matrix(path: str) -> LoadedMatrix:
    """A stored matrix (:class:`ConfigError` naming the file and key if it is not one)."""

    try:
        check_input(path)
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError, RecordingError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise ConfigError(f"cannot read the influence matrix ({reason})", source=path) from None
    return parse_matrix(text, path)


def parse_matrix(text: str, path: str) -> LoadedMatrix:
    """A matrix from its JSON text; ``path`` names it in errors and warnings."""
    try:
        data = json.loads(text)
    except ValueError as exc:
        reason = getattr(exc, "message", None) or str(exc)
        raise ConfigError(f"not a stored influence matrix ({reason})", source=path) from None
    except RecursionError:
        raise ConfigError("nested too deep to be an influence matrix", source=path) from None
    if not isinstance(data, dict):
        raise ConfigError("not a stored influence matrix (not a JSON object)", source=path)
    if "influence" in data and "kind" not in data:
        raise ConfigError(
            "an influence matrix from an earlier version of this software: make it again "
            "with stand influence RUNS.toml --save",
            source=path,
        )
    m = validate(StoredMatrix, data, path)
    rows = {len(r) for r in m.alpha_per_kg_m}
    if len(rows) != 1:
        raise ConfigError("rows of different lengths", source=path, key="alpha_per_kg_m")
    alpha = np.array([[complex(re, im) for re, im in row] for row in m.alpha_per_kg_m])
    cov = None if m.cov_alpha is None else np.array(m.cov_alpha, dtype=float)
    try:
        return LoadedMatrix(InfluenceMap(alpha, cov), m, path, text)
    except (ModelError, ValueError) as exc:
        raise ConfigError(str(exc), source=path, key="alpha_per_kg_m") from None
