"""Influence coefficients (field balancing): correction masses from trial runs, no model."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Annotated, Any

from pydantic import BaseModel, Field, FiniteFloat, PositiveFloat

from stand.cli.common import add_force_argument, print_warnings, write_text_output
from stand.cli.format import dump_json, json_text
from stand.config import STRICT
from stand.errors import ConfigError, UsageError


class TrialTable(BaseModel):
    model_config = STRICT
    plane: Annotated[int, Field(ge=1)]
    mass_g: PositiveFloat
    angle_deg: FiniteFloat


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
        help="the runs: [[runs]] with sensors = [[amplitude, phase_deg], ...] or "
        "file = RUN, and trial = {plane, mass_g, angle_deg}",
    )
    p.add_argument(
        "--config", metavar="CFG", help="configuration for recorded runs that carry none"
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


def _readings(entry: RunEntry, k: int, source: str, config: str | None) -> list[complex]:
    from stand.calib.influence import phasors

    if (entry.sensors is None) == (entry.file is None):
        raise ConfigError(
            "give sensors = [[amplitude, phase_deg], ...] or file = RUN (one of them)",
            source=source,
            key=f"runs[{k}]",
        )
    if entry.sensors is not None:
        if not entry.sensors:
            raise ConfigError("no sensor readings", source=source, key=f"runs[{k}].sensors")
        amp, ph = zip(*entry.sensors, strict=True)
        if min(amp) < 0:
            raise ConfigError("an amplitude is negative", source=source, key=f"runs[{k}].sensors")
        return [complex(z) for z in phasors(amp, ph)]
    from stand.pipeline import measure_recording

    m, _, _ = measure_recording(str(Path(source).parent / str(entry.file)), config)
    # conj: our phasors follow U = q R e^{-i phi}; conjugated, a trial at angle phi (from the
    # reference mark, against the direction of rotation) acts as e^{+i phi}, so trial and
    # correction angles are both counted that way
    return [complex(ph.A_m_s2).conjugate() for ph in m.supports]


def load_runs(path: str, config: str | None) -> list[Any]:
    """The runs of a runs file (ConfigError naming the file and the run if bad)."""
    from stand.calib.influence import InfluenceRun, Trial
    from stand.config import read_toml, validate

    _, data = read_toml(path)
    spec = validate(RunsFile, data, path)
    runs = []
    for k, entry in enumerate(spec.runs):
        trial = None
        if entry.trial is not None:
            t = entry.trial
            trial = Trial(t.plane, t.mass_g * 1e-3, t.angle_deg)
        import numpy as np

        runs.append(
            InfluenceRun(np.array(_readings(entry, k, path, config)), trial, entry.trial_left_on)
        )
    return runs


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from stand.calib.influence import correct, influence_matrix
    from stand.errors import ModelError

    runs = load_runs(args.runs, args.config)
    notes: list[Any] = []
    try:
        if args.matrix:
            stored = json.loads(Path(args.matrix).read_text())
            alpha = np.array([[complex(re, im) for re, im in row] for row in stored["influence"]])
        else:
            alpha, notes = influence_matrix(runs)
        if alpha.shape[0] != len(runs[0].readings):
            raise ModelError(
                f"the matrix has {alpha.shape[0]} sensors, the initial run {len(runs[0].readings)}"
            )
    except (OSError, KeyError, ValueError, TypeError) as exc:
        if isinstance(exc, ModelError):
            raise ConfigError(str(exc), source=args.runs) from None
        raise UsageError(f"--matrix {args.matrix}: not a stored influence matrix ({exc})") from None
    res = correct(alpha, runs[0].readings)
    warnings = [*notes, *res.diagnostics]
    out: dict[str, Any] = {
        "planes": [
            {
                "plane": j + 1,
                "mass_g": round(abs(w) * 1e3, 4),
                "angle_deg": round(math.degrees(math.atan2(w.imag, w.real)) % 360, 2),
            }
            for j, w in enumerate(res.correction)
        ],
        "influence": [
            [[round(z.real * 1e-3, 6), round(z.imag * 1e-3, 6)] for z in row] for row in res.alpha
        ],
        "influence_units": "reading per gram",
        "condition_number": round(res.condition_number, 4),
        "expected": [
            [round(abs(z), 4), round(math.degrees(math.atan2(z.imag, z.real)) % 360, 2)]
            for z in res.expected
        ],
        "warnings": [w.message for w in warnings],
    }
    if args.save:
        saved = {
            "influence": [[[z.real, z.imag] for z in row] for row in res.alpha],
            "units": "reading per kg",
            "sensors": alpha.shape[0],
            "planes": alpha.shape[1],
        }
        write_text_output(
            args.save, json_text(saved), force=args.force, inputs=[args.runs, args.matrix]
        )
    if args.json:
        dump_json(out)
        return 0
    print("correction to ADD (to the rotor as in the first run, every trial mass off);")
    print("angles in the same sense and from the same zero as the trial angles:")
    for p in out["planes"]:
        print(f"  plane {p['plane']}: {p['mass_g']:.3f} g at {p['angle_deg']:.1f} deg")
    print(f"influence matrix condition number {out['condition_number']:.3g}")
    if len(out["expected"]) > len(out["planes"]):
        print(
            "readings expected after the correction (least squares): "
            + ", ".join(f"{a:.3g} at {d:.0f} deg" for a, d in out["expected"])
        )
    if args.save:
        print(f"influence matrix stored in {args.save}")
    print_warnings(warnings)
    return 0
