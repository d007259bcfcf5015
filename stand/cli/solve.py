"""Solve a recorded run: the unbalance of both planes, with its 95 % interval."""

from __future__ import annotations

import argparse
import json
import sys
import tomllib
from typing import Any

from stand.cli.common import print_warnings
from stand.errors import ConfigError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run", metavar="RUN", help="run file (.h5) or python-can log")
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration (default: the one stored in the run file)",
    )
    add_measure_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_measure_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--taper",
        action="store_true",
        help="Hann taper against a neighbour close to 1x (costs 1.5x noise variance)",
    )
    p.add_argument(
        "--no-gate",
        action="store_true",
        help="use the whole run, not only its steady, settled part",
    )


def config_for(rec: Any, path: str | None) -> tuple[Any, Any]:
    """The configuration: the file given, else the one the run file carries."""
    from stand.config import config_from_dict, load_config

    if path:
        return load_config(path)
    text = rec.meta.get("config_toml", "")
    if not text:
        raise ConfigError("carries no configuration: give --config CFG", source=rec.path)
    return config_from_dict(tomllib.loads(text), source=f"{rec.path} (stored config)")


def result(m: Any, warnings: list[Any]) -> dict[str, Any]:
    """The result object (g mm, deg, mm at the edge; the seed's phi)."""
    from stand.core import phasor_to_polar, unbalance_to_polar

    q, phi = unbalance_to_polar(m.solution.U_kg_m)
    planes = []
    for i in range(2):
        R = m.radius_m[i]
        planes.append(
            {
                "plane": i + 1,
                "unbalance_g_mm": round(float(q[i]) * 1e6, 3),
                "angle_deg": round(float(phi[i]), 3),
                "mass_g": round(float(q[i]) / R * 1e3, 4),
                "radius_mm": round(R * 1e3, 3),
                "uncertainty_g_mm": round(float(m.radius95_kg_m[i]) * 1e6, 3),
            }
        )
    supports = []
    for i, ph in enumerate(m.supports):
        amp, phase = phasor_to_polar(ph.A_m_s2)
        supports.append(
            {
                "node": i + 1,
                "amplitude_m_s2": round(float(amp), 6),
                "phase_deg": round(float(phase), 4),
                "uncertainty_m_s2": round(ph.radius95_m_s2, 6),
                "revolutions": round(ph.revolutions, 2),
                "samples": ph.samples,
                "noise_m_s2": round(ph.noise_m_s2, 6),
                "noise_cost": round(ph.noise_cost, 4),
            }
        )
    return {
        "rpm": round(m.rpm, 3),
        "planes": planes,
        "supports": supports,
        "condition_number": float(m.solution.condition_number),
        "warnings": [w.message for w in warnings],
    }


def print_result(out: dict[str, Any]) -> None:
    """The result for the operator."""
    print(f"speed {out['rpm']:.1f} rpm")
    print("plane  unbalance [g mm]    95 % +-   angle [deg]   mass [g] at radius [mm]")
    for p in out["planes"]:
        print(
            f"  {p['plane']}  {p['unbalance_g_mm']:16.1f} {p['uncertainty_g_mm']:10.1f} "
            f"{p['angle_deg']:13.2f} {p['mass_g']:10.3f} at {p['radius_mm']:g}"
        )
    print("(angle: the seed's phi, from the reference mark against the direction of rotation)")
    print("support  amplitude [m/s^2]  phase [deg]  95 % +-   revolutions")
    for s in out["supports"]:
        print(
            f"  {s['node']}  {s['amplitude_m_s2']:17.5f} {s['phase_deg']:12.2f} "
            f"{s['uncertainty_m_s2']:9.5f} {s['revolutions']:10.1f}"
        )
    cost = out["supports"][0]["noise_cost"]
    if cost > 1.0:
        print(f"(taper: the noise variance is {cost:.2f} times that of the plain fit)")


def run(args: argparse.Namespace) -> int:
    from drivers.recording import read_recording
    from drivers.streams import rebuild
    from stand.measure import measure

    rec = read_recording(args.run)
    cfg, params = config_for(rec, args.config)
    streams = rebuild(rec.frames)
    m = measure(
        streams,
        params,
        reference_angle_deg=cfg.stand.reference_angle_deg,
        taper=args.taper,
        gate=not args.no_gate,
    )
    warnings = [*streams.warnings, *m.warnings]
    out = result(m, warnings)
    if args.json:
        json.dump(out, sys.stdout)
        print()
    else:
        print_result(out)
        print_warnings(warnings)
    return 0
