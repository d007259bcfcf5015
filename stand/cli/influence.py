"""Influence coefficients (the field method): the stand measured by trial runs, not modelled."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Annotated, Any

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.actions import save_matrix
from stand.archive import url_for
from stand.calib.influence import (
    TRIAL_CHANGE,
    Trial,
    influence_covariance,
    influence_matrix,
    phasors,
    suggested_trials,
)
from stand.cli.common import (
    actor_of,
    add_actor_arguments,
    add_archive_argument,
    add_force_argument,
    add_reason_argument,
    write_text_output,
)
from stand.cli.format import dump_json, print_warnings, show
from stand.config import STRICT, Config, read_toml, validate
from stand.config.matrix import Pair, matrix_document, parse_matrix, read_matrix
from stand.config.tables import Rpm, TrialMass, TrialRadius
from stand.config.typed import positive_float
from stand.core import rad_s_to_rpm
from stand.core.influence import InfluenceMap
from stand.drivers.runs.recording import config_digest
from stand.errors import ConfigError, ModelError, UsageError
from stand.field import field_from_runs, influence_runs, solve_initial_run
from stand.field.planes import field_json
from stand.solve import SolveOptions, json_text, solve_recording, to_json

PLANES = 2
"""The planes of the stand's own answer (a run solved through the matrix)."""
MAX_PLANES = 16
"""The most correction planes a runs file may name."""


class TrialTable(BaseModel):
    model_config = STRICT
    plane: Annotated[int, Field(ge=1, le=MAX_PLANES)]
    mass_g: TrialMass
    angle_deg: Annotated[FiniteFloat, Field(ge=-360.0, le=720.0)]
    radius_mm: TrialRadius | None = None


class RunEntry(BaseModel):
    """One run: readings typed in (``sensors``) or a recorded run (``file``)."""

    model_config = STRICT
    sensors: list[Pair] | None = None
    file: str | Annotated[list[str], Field(min_length=1)] | None = None
    speeds_rpm: list[Rpm] | None = None
    trial: TrialTable | None = None
    trial_left_on: bool = False


class RunsFile(BaseModel):
    model_config = STRICT
    runs: Annotated[list[RunEntry], Field(min_length=1)]
    matrix: (
        Annotated[list[Annotated[list[Pair], Field(min_length=1)]], Field(min_length=1)] | None
    ) = None
    """Influence coefficients typed in: a row per reading, ``[amplitude, phase_deg]`` per
    plane (reading per g at the trial radius)."""
    weights: list[Annotated[FiniteFloat, Field(gt=0.0, le=1e12)]] | None = None
    """Per reading, for ``--method wls`` (and ``minmax``)."""

    @model_validator(mode="after")
    def _amplitudes(self) -> RunsFile:
        for i, row in enumerate(self.matrix or []):
            for j, (amplitude, _) in enumerate(row):
                if amplitude < 0:
                    raise ValueError(f"matrix[{i}][{j}]: an amplitude is negative "
                                     f"({amplitude:g}): [amplitude, phase_deg]")  # fmt: skip
        return self


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "runs",
        metavar="RUNS.toml",
        help="the runs: [[runs]] with file = RUN (recorded) or sensors = [[amplitude, "
        "phase_deg], ...] (typed in), and trial = {plane, mass_g, angle_deg[, radius_mm]}",
    )
    p.add_argument(
        "--config", metavar="CFG", help="configuration (default: the first recorded run's)"
    )
    p.add_argument(
        "--save",
        metavar="MATRIX.json",
        help="store the influence matrix (permanent calibration of a rotor type)",
    )
    add_force_argument(p, "--save")
    add_reason_argument(p)
    add_archive_argument(p)
    add_actor_arguments(p)
    p.add_argument(
        "--matrix",
        metavar="MATRIX.json",
        help="use a stored influence matrix: only the first run is needed",
    )
    p.add_argument(
        "--method",
        choices=("ls", "wls", "minmax"),
        default="ls",
        help="least squares (default), weighted least squares (weights = [...] per reading in "
        "the runs file, or each recorded reading's noise), or min-max (the smallest worst "
        "reading)",
    )
    p.add_argument(
        "--max-mass-g",
        type=positive_float,
        metavar="G",
        help="the largest correction mass in any plane [g] (at its radius)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _entries(path: str) -> tuple[RunsFile, list[Any]]:
    """The runs file and ``(file(s) or None, typed readings, Trial, left_on)`` per run."""

    _, data = read_toml(path)
    spec = validate(RunsFile, data, path)
    out = []
    for k, e in enumerate(spec.runs):
        if (e.sensors is None) == (e.file is None):
            raise ConfigError(
                "give file = RUN or sensors = [[amplitude, phase_deg], ...] (one of them)",
                source=path,
                key=f"runs[{k}]",
            )
        typed = None
        if e.sensors is not None:
            amp, ph = zip(*e.sensors, strict=True) if e.sensors else ((), ())
            if not e.sensors or min(amp) < 0:
                raise ConfigError(
                    "no readings" if not e.sensors else "an amplitude is negative",
                    source=path,
                    key=f"runs[{k}].sensors",
                )
            typed = phasors(amp, ph)
        trial = None
        if e.trial is not None:
            t = e.trial  # no radius: the plane's correction radius (set by influence_runs)
            r = None if t.radius_mm is None else t.radius_mm * 1e-3
            trial = Trial(t.plane, t.mass_g * 1e-3, t.angle_deg, r)
        files = [e.file] if isinstance(e.file, str) else e.file
        run_file = None if files is None else [str(Path(path).parent / f) for f in files]
        out.append((run_file, typed, trial, e.trial_left_on))
    if any(f is None for f, *_ in out) and any(f is not None for f, *_ in out):
        raise ConfigError(
            "typed-in and recorded runs are mixed: one kind per runs file", source=path
        )
    return spec, out


def _is_field(spec: RunsFile, entries: list[Any], args: argparse.Namespace) -> bool:
    """Whether the runs ask for more than the stand's two-plane answer at one speed."""
    planes = {e[2].plane for e in entries if e[2] is not None}
    return bool(
        spec.matrix is not None
        or (planes and max(planes) > PLANES)
        or args.method != "ls"
        or args.max_mass_g is not None
        or any(e.speeds_rpm for e in spec.runs)
        or any(f is not None and len(f) > 1 for f, *_ in entries)
        or entries[0][0] is None
    )


def run(args: argparse.Namespace) -> int:

    spec, entries = _entries(args.runs)
    if _is_field(spec, entries, args):
        if args.matrix:
            raise UsageError(
                "--matrix: a stored matrix serves the stand's two-plane answer at its speed; "
                "for N planes or several speeds put the trial runs (or matrix = ...) in the "
                "runs file"
            )
        return run_field(args, spec, entries)
    entries = [(f[0], typed, trial, on) for f, typed, trial, on in entries]
    runs, cfg, params, text, omega = influence_runs(entries, args.config)
    tried = {r.trial.plane for r in runs[1:] if r.trial is not None}
    if args.matrix:
        matrix = read_matrix(args.matrix)
        matrix.check(None if cfg is None else cfg.rotor.type, live=True)
    elif len(tried) < PLANES and len(runs) == 1 + len(tried) and omega:
        return _suggest(args, runs, params, omega, sorted(set(range(1, PLANES + 1)) - tried))
    else:
        matrix = _measured_matrix(args, runs, cfg, text, entries, omega)
    return _recorded(args, entries[0][0], runs, matrix)


def _measured_matrix(
    args: argparse.Namespace,
    runs: list[Any],
    cfg: Config,
    text: str,
    entries: Any,
    omega: float | None,
) -> Any:
    """The matrix the trial runs measure (stored with --save)."""

    try:
        alpha, notes = influence_matrix(runs)
        imap = InfluenceMap(alpha, influence_covariance(runs))
    except ModelError as exc:
        raise ConfigError(str(exc), source=args.runs) from None
    doc = matrix_document(
        imap,
        readings="typed in" if omega is None else "support acceleration",
        rpm=None if omega is None else float(rad_s_to_rpm(omega)),
        rotor_type=None if cfg is None else cfg.rotor.type,
        config_sha256=config_digest(text) if text else None,
        runs=[str(f) for f, *_ in entries if f],
    )
    doc_text = json_text(doc)
    if args.save:
        _journaled_save(args, cfg, doc_text, [args.runs, *doc["runs"]])
    print_warnings(notes)
    return parse_matrix(doc_text, args.save or "(the trial runs)")


def _recorded(args: argparse.Namespace, first: str, runs: list[Any], matrix: Any) -> int:
    """The initial run solved through the matrix: the same result as any run."""

    if args.matrix:
        result = solve_recording(first, args.config, SolveOptions(matrix=matrix))
    else:
        result = solve_initial_run(first, args.config, runs, matrix)
    out = to_json(result)
    out["influence_per_g_mm"] = _alpha_json(matrix)
    show(out, args.json)
    if not args.json and args.save:
        print(f"influence matrix stored in {args.save}")
    return 0


def _alpha_json(matrix: Any) -> list[list[list[float]]]:
    return [
        [[round(z.real * 1e-6, 9), round(z.imag * 1e-6, 9)] for z in row]
        for row in matrix.imap.alpha
    ]


def _suggest(
    args: argparse.Namespace, runs: list[Any], params: Any, omega: float, planes: list[int]
) -> int:
    """Before a trial run: the trial mass that moves the 1x by about 30 %."""

    if args.save:
        raise UsageError("--save: no trial run yet, so no matrix to store")
    sizes = suggested_trials(params, omega, runs[0].readings)
    R = (params.R1, params.R2)
    out: dict[str, Any] = {
        "rpm": round(float(rad_s_to_rpm(omega)), 3),
        "next_trials": [
            {
                "plane": j,
                "mass_g": round(sizes[j - 1] / R[j - 1] * 1e3, 3),
                "radius_mm": round(R[j - 1] * 1e3, 3),
                "unbalance_g_mm": round(sizes[j - 1] * 1e6, 3),
            }
            for j in planes
        ],
        "change_pct": round(100 * TRIAL_CHANGE, 1),
    }
    if args.json:
        dump_json(out)
        return 0
    print(f"next: a trial run per plane, one at a time (speed {out['rpm']:.0f} rpm):")
    for t in out["next_trials"]:
        print(
            f"  plane {t['plane']}: put about {t['mass_g']:.1f} g at radius {t['radius_mm']:g} mm, "
            "at any angle (say 0 deg from the reference mark, against the direction of rotation)"
        )
    print(
        f"  (it should change the vibration by about {out['change_pct']:g} %); record the run "
        "and add it to the runs file with trial = {plane, mass_g, angle_deg}"
    )
    return 0


def run_field(args: argparse.Namespace, spec: Any, entries: list[Any]) -> int:
    """`stand influence` for N planes, several speeds, another method or a mass cap."""

    result, notes, cfg = field_from_runs(
        spec,
        entries,
        config=args.config,
        method=args.method,
        max_mass_g=args.max_mass_g,
        source=args.runs,
    )
    if args.save:
        _save(args, result, cfg, entries)
    out = field_json(result, cfg)
    out["warnings"] = [n.message for n in [*notes, *result.solution.diagnostics]]
    if args.json:
        dump_json(out)
        return 0
    _print(out)
    print_warnings([*notes, *result.solution.diagnostics])
    return 0


def _save(args: argparse.Namespace, result: Any, cfg: Config, entries: list[Any]) -> None:

    try:
        imap = InfluenceMap(result.alpha)
    except ModelError as exc:
        raise ConfigError(f"--save: {exc}", source=args.runs) from None
    doc = matrix_document(
        imap,
        readings="typed in" if result.typed else "support acceleration",
        rpm=None,
        rotor_type=None if cfg is None else cfg.rotor.type,
        config_sha256=None,
        runs=[f for files, *_ in entries if files for f in files],
    )
    doc["speeds_rpm"] = [r.speed_rpm for r in result.readings]
    _journaled_save(args, cfg, json_text(doc), [args.runs])


def _journaled_save(args: argparse.Namespace, cfg: Config | None, text: str,
                    inputs: list[str]) -> None:  # fmt: skip
    """``--save``: the matrix written, and one entry in the audit trail in the same
    transaction (:func:`stand.actions.save_matrix`); to stdout (``-``) without either."""
    if args.save == "-":
        write_text_output(args.save, text, force=args.force, inputs=inputs)
        return
    url = url_for(args.archive, cfg)
    save_matrix(url, actor_of(args, url), args.save, text, force=args.force,
                inputs=tuple(i for i in inputs if i), reason=args.reason)  # fmt: skip


def _print(out: dict[str, Any]) -> None:
    print(
        f"correction in {len(out['planes'])} planes ({out['method_name']}), at "
        f"{out['radius']} (angles in the same sense and from the same zero as the trial angles):"
    )
    for p in out["planes"]:
        ws = " + ".join(
            f"{w['mass_g']:.3f} g at {w['angle_deg']:.1f} deg"
            + ("" if w["position"] is None else f" (position {w['position']})")
            for w in p["weights"]
        )
        note = "  (left out: not independent)" if p["dependent"] else ""
        note += "  (at the mass limit)" if p["at_limit"] else ""
        print(f"  plane {p['plane']}: {p['action']} {ws or 'nothing'}{note}")
    print(f"readings before -> after ({out['unit']}):")
    for r in out["readings"]:
        speed = "" if r["speed_rpm"] is None else f" at {r['speed_rpm']:g} rpm"
        after = r["after"][0]
        left = (
            "0"
            if after <= 1e-9 * out["worst_before"]
            else f"{after:.4g} at {r['after'][1]:.0f} deg"
        )
        print(f"  sensor {r['sensor']}{speed}: {r['before'][0]:.4g} -> {left}")
    print(
        f"rms {out['rms_before']:.4g} -> {out['rms_after']:.4g}, worst {out['worst_before']:.4g}"
        f" -> {out['worst_after']:.4g}; condition number {out['condition_number']:.3g}"
    )
