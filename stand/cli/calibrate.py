"""Identify the stand (M, C, H per support, sensor gains and delays, reference angle) from runs."""

from __future__ import annotations

import argparse
import datetime as dt
import math
from pathlib import Path
from typing import Annotated, Any

from pydantic import BaseModel, Field, FiniteFloat, PositiveFloat

from stand.cli.common import add_force_argument, write_text_output
from stand.cli.format import dump_json
from stand.config import STRICT
from stand.errors import ConfigError


class MassTable(BaseModel):
    model_config = STRICT
    plane: Annotated[int, Field(ge=1, le=2)]
    mass_g: PositiveFloat
    angle_deg: FiniteFloat


class CalibRun(BaseModel):
    model_config = STRICT
    file: str
    masses: list[MassTable] = []


class CalibFile(BaseModel):
    model_config = STRICT
    runs: Annotated[list[CalibRun], Field(min_length=1)]


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "runs",
        metavar="RUNS.toml",
        help="[[runs]] file = RUN, masses = [{plane, mass_g, angle_deg}, ...] (the test "
        "masses on the proving rotor in that run; angles from the reference mark, "
        "against the direction of rotation)",
    )
    p.add_argument(
        "--config",
        required=True,
        metavar="CFG",
        help="the stand's configuration: M3, J3 and the geometry of the proving rotor "
        "are taken as known, M/C/H as the starting point",
    )
    p.add_argument(
        "--out",
        required=True,
        metavar="CALIBRATED.toml",
        help="the calibrated configuration to write",
    )
    add_force_argument(p, "--out")
    p.add_argument(
        "--rotor",
        action="store_true",
        help="a new rotor type on an identified stand (the config's): identify its "
        "M3, J3 and centre of mass instead of the stand",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from stand.calib.identify import NAMES, CalibrationRun, identify
    from stand.config import load_config, read_toml, validate
    from stand.drivers.files import check_output
    from stand.errors import ModelError, UsageError
    from stand.pipeline import measure_recording

    check_output(args.out, force=args.force, inputs=[args.config, args.runs])  # before the work
    cfg, params = load_config(args.config)
    _, data = read_toml(args.runs)
    spec = validate(CalibFile, data, args.runs)
    R = (params.R1, params.R2)
    runs = []
    for entry in spec.runs:
        # raw readings: the configured reference angle, no sensor correction
        m, _, _, _ = measure_recording(
            str(Path(args.runs).parent / entry.file), args.config, raw_sensors=True
        )
        T = np.zeros(2, complex)
        for mass in entry.masses:
            i = mass.plane - 1
            T[i] += mass.mass_g * 1e-3 * R[i] * np.exp(-1j * math.radians(mass.angle_deg))
        runs.append(CalibrationRun(m.omega_rad_s, np.array([ph.A_m_s2 for ph in m.supports]), T))
    if args.rotor:
        if cfg.rotor.shaft is not None:
            raise UsageError(
                f"{args.config}: [rotor.shaft] describes the rotor already (its mass, inertia "
                "and geometry follow from it): nothing to identify with --rotor"
            )
        return _rotor(args, cfg, params, runs)
    try:
        res = identify(params, runs, beam=cfg.rotor.beam())
    except ModelError as exc:
        raise ConfigError(str(exc), source=args.runs) from None
    v, se = res.values, res.std_errors
    stand = cfg.stand.model_copy(
        update={
            "M1": v["M1"],
            "M2": v["M2"],
            "C1": v["C1"],
            "C2": v["C2"],
            "H1": v["H1"],
            "H2": v["H2"],
            "reference_angle_deg": cfg.stand.reference_angle_deg
            + math.degrees(v["reference_angle_error_rad"]),
            "calibrated": dt.date.today().isoformat(),
        }
    )
    sensors = cfg.sensors.model_copy(
        update={"gain": [v["gain1"], v["gain2"]], "delay_s": [v["delay1_s"], v["delay2_s"]]}
    )
    new = cfg.model_copy(update={"stand": stand, "sensors": sensors})
    header = _write(
        args,
        f"calibrated by stand calibrate from {len(runs)} runs ({args.runs})",
        res,
        [n for n in NAMES if not n.startswith("U_res")],
        "proving rotor's",
        new,
    )
    out = {
        "values": v,
        "std_errors": se,
        "residual_rms_m_s2": res.residual_rms_m_s2,
        "runs": res.runs,
        "config": args.out,
        "reference_angle_deg": stand.reference_angle_deg,
    }
    if args.json:
        dump_json(out)
    else:
        print("\n".join(line[2:] for line in header))
        print(f"wrote {args.out}")
    return 0


def _rotor(args: argparse.Namespace, cfg: Any, params: Any, runs: list[Any]) -> int:
    """``--rotor``: M3, J3 and the centre of mass on the configured (identified) stand."""

    from stand.calib.identify import ROTOR_NAMES, identify_rotor
    from stand.errors import ModelError

    try:
        res = identify_rotor(params, runs, tuple(cfg.sensors.gain), tuple(cfg.sensors.delay_s))
    except ModelError as exc:
        raise ConfigError(str(exc), source=args.runs) from None
    v, se = res.values, res.std_errors
    q = res.params
    rotor = cfg.rotor.model_copy(update={"M3": q.M3, "J3": q.J3, "b": q.b, "c": q.c})
    new = cfg.model_copy(update={"rotor": rotor})
    header = _write(
        args,
        f"rotor identified by stand calibrate --rotor from {len(runs)} runs ({args.runs})",
        res,
        list(ROTOR_NAMES[:3]),
        "the rotor's",
        new,
    )
    if args.json:
        dump_json(
            {
                "values": v,
                "std_errors": se,
                "residual_rms_m_s2": res.residual_rms_m_s2,
                "runs": res.runs,
                "config": args.out,
            }
        )
    else:
        print("\n".join(line[2:] for line in header))
        print(f"wrote {args.out}")
    return 0


def _estimate_line(name: str, value: float, error: float) -> str:
    """``#   C1 = 45000 +- 120``; an angle in degrees, as the config takes it."""
    if name.endswith("_rad"):
        name, value, error = name[:-4] + "_deg", math.degrees(value), math.degrees(error)
    return f"#   {name} = {value:.6g} +- {error:.2g}"


def _write(
    args: argparse.Namespace, title: str, res: Any, names: list[str], whose: str, cfg: Any
) -> list[str]:
    """The calibrated configuration, its fit and standard errors as comments on top."""
    import numpy as np

    from stand.config import read_toml, updated_toml

    v, se = res.values, res.std_errors
    header = [
        f"# {title};",
        f"# rms misfit of the phasors {res.residual_rms_m_s2:.3g} m/s^2; standard errors:",
    ]
    header += [_estimate_line(name, v[name], se[name]) for name in names]
    U = res.residual_unbalance_kg_m
    header.append(
        f"# {whose} own unbalance: "
        + ", ".join(
            f"plane {i + 1} {abs(U[i]) * 1e6:.1f} g mm at "
            f"{-math.degrees(np.angle(U[i])) % 360:.1f} deg"
            for i in range(2)
        )
    )
    original, _ = read_toml(args.config)  # the user's file: its comments are kept
    write_text_output(
        args.out,
        "\n".join(header) + "\n" + updated_toml(original, cfg),
        force=args.force,
        inputs=[args.config, args.runs],
    )
    return header
