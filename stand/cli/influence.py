"""Influence coefficients (the field method): the stand measured by trial runs, not modelled."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Annotated, Any

from pydantic import BaseModel, Field, FiniteFloat, PositiveFloat

from stand.cli.common import add_force_argument, print_warnings, write_text_output
from stand.cli.format import dump_json, show
from stand.config import STRICT
from stand.errors import ConfigError, ModelError, UsageError
from stand.result import json_text

PLANES = 2


class TrialTable(BaseModel):
    model_config = STRICT
    plane: Annotated[int, Field(ge=1, le=PLANES)]
    mass_g: PositiveFloat
    angle_deg: FiniteFloat
    radius_mm: PositiveFloat | None = None


class RunEntry(BaseModel):
    """One run: readings typed in (``sensors``) or a recorded run (``file``)."""

    model_config = STRICT
    sensors: list[Annotated[list[FiniteFloat], Field(min_length=2, max_length=2)]] | None = None
    file: str | None = None
    trial: TrialTable | None = None
    trial_left_on: bool = False


class RunsFile(BaseModel):
    model_config = STRICT
    runs: Annotated[list[RunEntry], Field(min_length=1)]


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
    p.add_argument(
        "--matrix",
        metavar="MATRIX.json",
        help="use a stored influence matrix: only the first run is needed",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _entries(path: str) -> list[Any]:
    """``(file or None, typed readings, Trial, left_on)`` per run of the runs file."""
    from stand.calib.influence import Trial, phasors
    from stand.config import read_toml, validate

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
        run_file = None if e.file is None else str(Path(path).parent / e.file)
        out.append((run_file, typed, trial, e.trial_left_on))
    if any(f is None for f, *_ in out) and any(f is not None for f, *_ in out):
        raise ConfigError(
            "typed-in and recorded runs are mixed: one kind per runs file", source=path
        )
    return out


def run(args: argparse.Namespace) -> int:
    from stand.influence import influence_runs

    entries = _entries(args.runs)
    recorded = entries[0][0] is not None
    runs, cfg, params, text, omega = influence_runs(entries, args.config)
    tried = {r.trial.plane for r in runs[1:] if r.trial is not None}
    if args.matrix:
        from stand.matrix import read_matrix

        matrix = read_matrix(args.matrix)
        matrix.check(None if cfg is None else cfg.rotor.type, live=recorded)
    elif recorded and len(tried) < PLANES and len(runs) == 1 + len(tried) and omega:
        return _suggest(args, runs, params, omega, sorted(set(range(1, PLANES + 1)) - tried))
    else:
        matrix = _measured_matrix(args, runs, cfg, text, entries, omega)
    if recorded:
        return _recorded(args, entries[0][0], runs, matrix)
    return _typed(args, runs, matrix, cfg, params)


def _measured_matrix(
    args: argparse.Namespace,
    runs: list[Any],
    cfg: Any,
    text: str,
    entries: Any,
    omega: float | None,
) -> Any:
    """The matrix the trial runs measure (stored with --save)."""
    from stand.calib.influence import influence_covariance, influence_matrix
    from stand.core.influence import InfluenceMap
    from stand.drivers.recording import config_digest
    from stand.matrix import matrix_document, parse_matrix

    try:
        alpha, notes = influence_matrix(runs)
        imap = InfluenceMap(alpha, influence_covariance(runs))
    except ModelError as exc:
        raise ConfigError(str(exc), source=args.runs) from None
    doc = matrix_document(
        imap,
        readings="typed in" if omega is None else "support acceleration",
        rpm=None if omega is None else omega * 30 / math.pi,
        rotor_type=None if cfg is None else cfg.rotor.type,
        config_sha256=config_digest(text) if text else None,
        runs=[str(f) for f, *_ in entries if f],
    )
    doc_text = json_text(doc)
    if args.save:
        write_text_output(args.save, doc_text, force=args.force, inputs=[args.runs, *doc["runs"]])
    print_warnings(notes)
    return parse_matrix(doc_text, args.save or "(the trial runs)")


def _recorded(args: argparse.Namespace, first: str, runs: list[Any], matrix: Any) -> int:
    """The initial run solved through the matrix: the same result as any run."""
    from stand.influence import solve_initial_run
    from stand.pipeline import SolveOptions, solve_recording
    from stand.result import to_json

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
    from stand.calib.influence import TRIAL_CHANGE, suggested_trials

    if args.save:
        raise UsageError("--save: no trial run yet, so no matrix to store")
    sizes = suggested_trials(params, omega, runs[0].readings)
    R = (params.R1, params.R2)
    out: dict[str, Any] = {
        "rpm": round(omega * 30 / math.pi, 3),
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


def _weight(w: Any) -> dict[str, Any]:
    return {
        "mass_g": round(w.mass_kg * 1e3, 4),
        "angle_deg": round(w.angle_deg, 2),
        "position": None if w.position is None else w.position + 1,
    }


def _typed(args: argparse.Namespace, runs: list[Any], matrix: Any, cfg: Any, params: Any) -> int:
    """Typed-in readings: the unbalance through the matrix, corrected as the config says."""
    from stand.core.balance import correction
    from stand.core.influence import solve_influence
    from stand.core.model import unbalance_to_polar
    from stand.pipeline import tolerance_of

    sol = solve_influence(matrix.imap, runs[0].readings)
    c = None if cfg is None else cfg.correction
    R = (1.0, 1.0) if params is None else (params.R1, params.R2)
    tol = None if cfg is None else tolerance_of(cfg, params)
    planes = []
    for i, U in enumerate(sol.U_kg_m):
        corr = correction(
            complex(U),
            R[i],
            remove=c is not None and c.mode == "remove",
            positions=0 if c is None else c.positions,
            position0_deg=0.0 if c is None else c.position0_deg,
            steps_kg=[] if c is None else [w * 1e-3 for w in c.weights_g],
            step_kg=0.0 if c is None else c.weight_step_g * 1e-3,
        )
        (q,), (phi,) = unbalance_to_polar([U])
        per = None if tol is None else tol.per_plane_kg_m[i]
        planes.append(
            {
                "plane": i + 1,
                "action": "remove" if corr.remove else "add",
                "weights": [_weight(w) for w in corr.weights],
                "unbalance_mass_g": round(q / R[i] * 1e3, 4),
                "unbalance_angle_deg": round(float(phi), 2),
                "within_tolerance": None if per is None else bool(q <= per),
            }
        )
    out: dict[str, Any] = {
        "planes": planes,
        "radius": "the trial radius" if params is None else "each plane's correction radius",
        "influence_per_g": [  # in the instrument's own convention (conjugated back)
            [
                [round(z.real * 1e-3 * R[j], 6), -round(z.imag * 1e-3 * R[j], 6)]
                for j, z in enumerate(row)
            ]
            for row in matrix.imap.alpha
        ],
        "condition_number": round(sol.condition_number, 4),
        "warnings": [w.message for w in sol.diagnostics],
    }
    if args.json:
        dump_json(out)
        return 0
    print(
        f"correction, at {out['radius']} (angles in the same sense and from the same zero as "
        "the trial angles):"
    )
    for p in planes:
        ws = " + ".join(
            f"{w['mass_g']:.3f} g at {w['angle_deg']:.1f} deg"
            + ("" if w["position"] is None else f" (position {w['position']})")
            for w in p["weights"]
        )
        verdict = {None: "", True: " (within tolerance: no correction needed)", False: ""}
        print(f"  plane {p['plane']}: {p['action']} {ws}{verdict[p['within_tolerance']]}")
    print(f"influence matrix condition number {out['condition_number']:.3g}")
    if args.save:
        print(f"influence matrix stored in {args.save}")
    print_warnings(sol.diagnostics)
    return 0
