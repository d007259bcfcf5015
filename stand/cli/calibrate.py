"""Identify the stand (M, C, H per support, sensor gains and delays, reference angle) from runs."""

from __future__ import annotations

import argparse
import datetime as dt
import difflib
import math
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, Field, FiniteFloat, PositiveFloat

from stand.actions import save_calibration
from stand.archive import correction_rows, url_for
from stand.archive.query import serials_by_digest
from stand.calib.identify import NAMES, ROTOR_NAMES, CalibrationRun, identify, identify_rotor
from stand.cli.common import (
    actor_of,
    add_actor_arguments,
    add_archive_argument,
    add_force_argument,
    add_reason_argument,
    write_text_output,
)
from stand.cli.format import dump_json
from stand.config import Config
from stand.config.edit import updated_toml
from stand.config.schema import STRICT, load_config, read_toml, validate
from stand.errors import ConfigError, ModelError, UsageError
from stand.files import check_output
from stand.health.monitor import answers, refit
from stand.health.recalibrate import fits_json, kept_line, refitted_config, significant
from stand.solve import measure_recording


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
        nargs="?",
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
        metavar="CALIBRATED.toml",
        help="the calibrated configuration to write (with --from-archive, default: beside "
        "the config, CFG-recalibrated.toml; never the config itself without --force)",
    )
    add_force_argument(p, "--out")
    p.add_argument(
        "--rotor",
        action="store_true",
        help="a new rotor type on an identified stand (the config's): identify its "
        "M3, J3 and centre of mass instead of the stand",
    )
    g = p.add_argument_group("recalibration from production (stand health)")
    g.add_argument(
        "--from-archive",
        action="store_true",
        help="re-identify the stand from the corrected and checked rotors in the archive "
        "(the data since the change stand health found) instead of trial runs",
    )
    g.add_argument(
        "--fit",
        metavar="NAMES",
        help="with --from-archive: the parameters to fit, e.g. C1 or C1,C2 (C1 C2 M1 M2 "
        "gain1 gain2; default: what stand health says moved)",
    )
    g.add_argument(
        "--stand", metavar="ID", help="with --from-archive: the config's stand id (checked)"
    )
    g.add_argument(
        "--rotor-type", metavar="TYPE", help="with --from-archive: the config's type (checked)"
    )
    add_archive_argument(g)
    add_reason_argument(p)
    add_actor_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:

    if args.from_archive:
        return _from_archive(args)
    if not args.runs or not args.out:
        raise UsageError("stand calibrate: give RUNS.toml and --out (or --from-archive)")

    check_output(args.out, force=args.force, inputs=[args.config, args.runs])  # before the work
    cfg, params = load_config(args.config)
    runs = _calibration_runs(args, params)
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
    new = _identified_config(cfg, v)
    stand = new.stand
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


def _identified_config(cfg: Config, v: dict[str, float]) -> Any:
    """The config with the identified stand: masses, stiffnesses, damping, the reference
    angle, the sensors' gains and delays, today's date."""
    stand = cfg.stand.model_copy(
        update={
            **{k: v[k] for k in ("M1", "M2", "C1", "C2", "H1", "H2")},
            "reference_angle_deg": cfg.stand.reference_angle_deg
            + math.degrees(v["reference_angle_error_rad"]),
            "calibrated": dt.date.today().isoformat(),
        }
    )
    sensors = cfg.sensors.model_copy(
        update={"gain": [v["gain1"], v["gain2"]], "delay_s": [v["delay1_s"], v["delay2_s"]]}
    )
    return cfg.model_copy(update={"stand": stand, "sensors": sensors})


def _calibration_runs(args: argparse.Namespace, params: Any) -> list[Any]:
    """The runs file's runs, measured raw (the configured reference angle, no sensor
    correction), each with the test masses it carried as unbalance per plane [kg m]."""

    _, data = read_toml(args.runs)
    spec = validate(CalibFile, data, args.runs)
    R = (params.R1, params.R2)
    runs = []
    for entry in spec.runs:
        m, _, _, _ = measure_recording(
            str(Path(args.runs).parent / entry.file), args.config, raw_sensors=True
        )
        T = np.zeros(2, complex)
        for mass in entry.masses:
            i = mass.plane - 1
            T[i] += mass.mass_g * 1e-3 * R[i] * np.exp(-1j * math.radians(mass.angle_deg))
        runs.append(CalibrationRun(m.omega_rad_s, np.array([ph.A_m_s2 for ph in m.supports]), T))
    return runs


def _rotor(args: argparse.Namespace, cfg: Config, params: Any, runs: list[Any]) -> int:
    """``--rotor``: M3, J3 and the centre of mass on the configured (identified) stand."""

    try:
        g, d = cfg.sensors.gain, cfg.sensors.delay_s
        res = identify_rotor(params, runs, (g[0], g[1]), (d[0], d[1]))
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
    args: argparse.Namespace, title: str, res: Any, names: list[str], whose: str, cfg: Config
) -> list[str]:
    """The calibrated configuration, its fit and standard errors as comments on top."""

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
    text = "\n".join(header) + "\n" + updated_toml(original, cfg)
    _journaled(args, cfg, args.out, text, [args.config, args.runs])
    return header


def _journaled(args: argparse.Namespace, cfg: Config, path: str, text: str,
               inputs: list[str]) -> None:  # fmt: skip
    """Write the calibration, and one entry in the audit trail in the same transaction
    (:func:`stand.actions.save_calibration`); to stdout (``-``) without either."""
    if path == "-":
        write_text_output(path, text, force=args.force, inputs=inputs)
        return
    url = url_for(args.archive, cfg)
    save_calibration(url, actor_of(args, url), path, text, config=args.config,
                     force=args.force, inputs=tuple(i for i in inputs if i),
                     reason=args.reason)  # fmt: skip


FITTABLE = ("C1", "C2", "M1", "M2", "gain1", "gain2")


def _no_change(r: Any, as_json: bool) -> bool:
    """Say "no significant change" where every fitted change lies inside its own 95 %
    interval (then nothing is written); whether it did."""
    if significant(r):
        return False
    said = kept_line(r) + "; nothing written (--force writes it)"
    if as_json:
        dump_json({"significant": False, "said": said, "config": None, "fits": fits_json(r)})
    else:
        print(said)
    return True


def _own_rows(args: argparse.Namespace, cfg: Config, url: str) -> list[Any]:
    """The corrected rotors that recalibrate ``cfg``: its own stand's, of its own rotor
    type (``--stand`` and ``--rotor-type`` may only name them again: another stand's or
    type's rotors would write their calibration into this config), named on stdout."""
    stand, rotor_type = cfg.stand.stand_id(), cfg.rotor.type
    for flag, given, own in (("--stand", args.stand, stand),
                             ("--rotor-type", args.rotor_type, rotor_type)):  # fmt: skip
        if given is not None and given != own:
            raise UsageError(f"{flag} {given}: {args.config} is {flag[2:]} {own or '(none)'}; "
                             "a calibration is fitted to its own stand's rotors of its own "
                             "type")  # fmt: skip
    rows = [r for r in correction_rows(url, stand) if r["rotor_type"] == rotor_type]
    if not args.json:
        print(f"from the archive: {len(rows)} corrected rotors of stand {stand}, rotor type "
              f"{rotor_type or '(none named)'}")  # fmt: skip
    return rows


def _from_archive(args: argparse.Namespace) -> int:
    """``--from-archive``: the stand re-identified from production data; the new config
    written beside the old (with a diff), the last rotors' answers old and new."""

    out_path = args.out or str(
        Path(args.config).with_name(Path(args.config).stem + "-recalibrated.toml")
    )
    if Path(out_path).resolve() == Path(args.config).resolve() and not args.force:
        raise UsageError("stand calibrate: --out is the config itself: add --force to replace it")
    check_output(out_path, force=args.force, inputs=[])
    names = None
    if args.fit:
        names = [n.strip() for n in args.fit.split(",") if n.strip()]
        bad = [n for n in names if n not in FITTABLE]
        if bad or not names:
            raise UsageError(
                f"--fit: {', '.join(bad) or 'nothing'}: choose from {', '.join(FITTABLE)}"
            )
    cfg, params = load_config(args.config)
    url = url_for(args.archive, cfg)
    r = refit(_own_rows(args, cfg, url), params, names)
    if not args.force and _no_change(r, args.json):
        return 0
    original, _ = read_toml(args.config)
    header, text = refitted_config(cfg, r, original)
    _journaled(args, cfg, out_path, text, [args.config])
    diff = list(
        difflib.unified_diff(
            original.splitlines(), text.splitlines(), args.config, out_path, lineterm="", n=0
        )
    )
    rows = answers(r)
    shown = r.group.rows[-len(rows) :] if rows else []
    serials = serials_by_digest(url, [row["check_sha256"] for row in shown])
    for e, row in zip(rows, shown, strict=True):
        e["serial"] = serials.get(row["check_sha256"])
    if args.json:
        dump_json(
            {
                "significant": significant(r),
                "fits": fits_json(r),
                "data": len(r.group.rows) - r.start,
                "config": out_path,
                "diff": diff,
                "last_rotors": rows,
            }
        )  # fmt: skip
        return 0
    print("\n".join(line[2:] for line in header))
    print("\n".join(diff))
    print("the last rotors' initial unbalance, old -> new calibration [g mm at deg]:")
    for e in rows:
        (o1, o2), (n1, n2) = e["old"], e["new"]
        who = e["serial"] or "run " + e["check_sha256"]
        print(
            f"  {who}: plane 1 {o1[0]:.0f} at {o1[1]:.0f} -> {n1[0]:.0f} at "
            f"{n1[1]:.0f}; plane 2 {o2[0]:.0f} at {o2[1]:.0f} -> {n2[0]:.0f} at {n2[1]:.0f}"
        )
    print(f"wrote {out_path}")
    return 0
