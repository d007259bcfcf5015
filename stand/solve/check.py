"""The check run: the run before a correction against the run after it, with the URR.

A check compares like with like: the run before must be of the same stand
and rotor (its stored config's physical values) and at the same speed
(within :data:`stand.config.matrix.SAME_SPEED`), unless the operator says
otherwise; it is solved with the config (and influence matrix) of the check
run itself.  A plane whose unbalance grew says so, and what to suspect.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from stand.config import SAME_SPEED, Config, config_toml
from stand.core import Diagnostic, StandParameters, rad_s_to_rpm
from stand.errors import UsageError
from stand.i18n.words import said
from stand.measuring import Measurement
from stand.solve.pipeline import (
    ConfigText,
    SolveOptions,
    measure_streams,
)
from stand.solve.recordings import named_errors, read_run, solve_recording
from stand.solve.result import Check, Result


def check_against(
    previous: str,
    cfg: Config,
    params: StandParameters,
    after: Measurement,
    *,
    strict: bool = True,
    matrix: Any = None,
) -> Check:
    """The run before the correction, measured with the same stand (this config).

    ``strict``: refuse a previous run of another rotor or stand (its stored
    config) or of another speed (beyond :data:`stand.config.matrix.SAME_SPEED`): its URR
    would compare two different things.  ``matrix``: the influence matrix the
    check run was solved with, if any (the run before is solved with it too).

    Raises
    ------
    UsageError
        The previous run is of another rotor, stand or speed (and ``strict``).
    """

    own = read_run(previous, None, fallback=ConfigText(config_toml(cfg), "the check run's config"))
    rec, streams = own.rec, own.streams  # decoded by its own family (its stored config)
    if strict and rec.meta.get("config_toml"):
        _same_rotor_and_stand(previous, own.cfg, cfg)
    with named_errors(previous):
        before = measure_streams(streams, cfg, params, SolveOptions(matrix=matrix))
    if strict and abs(before.omega_rad_s / after.omega_rad_s - 1) > SAME_SPEED:
        raise UsageError(
            f"--check {previous}: that run turned at {rad_s_to_rpm(before.omega_rad_s):.0f} rpm, "
            f"this one at {rad_s_to_rpm(after.omega_rad_s):.0f} rpm: check at the same speed "
            "(or say --check-any)"
        )
    b, a = before.solution.U_kg_m, after.solution.U_kg_m
    notes = tuple(
        replace(
            w, message=said("the run before ({run}): {message}", run=previous, message=w.message)
        )
        for w in (*rec.warnings, *streams.warnings)
    )
    return Check(previous, (complex(b[0]), complex(b[1])), (complex(a[0]), complex(a[1])), notes)


SAME_STAND = ("M1", "M2", "C1", "C2", "H1", "H2")
SAME_ROTOR = ("M3", "J3", "a", "b", "c", "d", "R1", "R2")
"""What makes a check run's stand and rotor the same as the run before (names, dates and
the sensors' calibration may change between them)."""


def _same_rotor_and_stand(previous: str, theirs: Any, ours: Any) -> None:
    """Refuse a previous run whose stored rotor (or rotor type) or stand differs from this
    config's."""
    t, o = theirs.rotor.type, ours.rotor.type
    if t and o and t != o:
        raise UsageError(
            f"--check {previous}: that run is of rotor type {t!r}, this one {o!r} "
            "(or say --check-any)"
        )
    for table in ("rotor", "stand"):
        a, b = getattr(theirs, table).model_dump(), getattr(ours, table).model_dump()
        keys = SAME_STAND if table == "stand" else SAME_ROTOR
        diff = [k for k in keys if not math.isclose(a.get(k, 0.0), b[k], rel_tol=1e-9)]
        if diff:
            k = diff[0]
            raise UsageError(
                f"--check {previous}: that run is of another {table} ({k} = {a.get(k):g} there, "
                f"{b[k]:g} here): its unbalance is not this rotor's before the correction "
                "(or say --check-any)"
            )


def check_notes(check: Check, radius95_kg_m: Any = (0.0, 0.0)) -> list[Diagnostic]:
    """What a check says beyond its numbers: a correction that made a plane worse, by more
    than the two readings' noise (``radius95``: the check run's 95 % radii [kg m]; the run
    before, on the same stand, reads about as precisely, so a growth within twice it is
    noise: a plane left alone reads a little more or less each run)."""
    pairs = zip(check.after_kg_m, check.before_kg_m, radius95_kg_m, strict=True)
    grew = [abs(a) - abs(b) > 2 * float(r) for a, b, r in pairs]
    return [
        Diagnostic(
            "correction_made_worse",
            said(
                "plane {plane}: the unbalance grew after the correction (URR {urr} %): was "
                "it added where material should have come off (or the other way round), at "
                "the mirrored angle (the angle counts against the direction of rotation), or "
                "in the other plane?",
                plane=i + 1,
                urr=f"{100 * u:.0f}",
            ),
            float(u),
        )
        for i, u in enumerate(check.urr)
        if u is not None and u < 0 and grew[i]
    ]


def with_check(
    result: Result,
    previous: str,
    cfg: Config,
    params: StandParameters,
    *,
    strict: bool = True,
    matrix: Any = None,
) -> Result:
    """``result`` as the check of ``previous``: before and after, URR, and what a worse
    plane suggests (:func:`check_against`, :func:`check_notes`)."""
    check = check_against(previous, cfg, params, result.measurement, strict=strict, matrix=matrix)
    return replace(
        result,
        check=check,
        warnings=(
            *result.warnings,
            *check.warnings,
            *check_notes(check, result.measurement.radius95_kg_m),
        ),
    )


def solve_check(
    run: str,
    previous: str,
    config: str | ConfigText | None = None,
    options: SolveOptions = SolveOptions(),
    *,
    strict: bool = True,
) -> Result:
    """A recorded check run solved (:func:`~stand.solve.recordings.solve_recording`) and
    checked against ``previous`` (:func:`with_check`) with the same config: the given one,
    else the check run's stored one."""
    result = solve_recording(run, config, options)
    prov = result.provenance  # the config it was solved with, without reading the run again
    cfg, params, _ = ConfigText(prov.config_toml, prov.config_source).load()
    return with_check(result, previous, cfg, params, strict=strict, matrix=options.matrix)
