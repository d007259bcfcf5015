"""Support accelerations for given unbalances (steady state) and the natural frequencies."""

from __future__ import annotations

import argparse
import math

import numpy as np

from stand.cli.format import dump_json, print_warnings
from stand.config import load_config
from stand.config.typed import parse_rpm, parse_unbalance
from stand.core import (
    forward,
    natural_frequencies,
    phasor_to_polar,
    rpm_to_rad_s,
    unbalance_from_polar,
)
from stand.core.beam import forward_beam, natural_frequencies_beam, solve_beam
from stand.core.inverse import speed_diagnostics
from stand.errors import UsageError
from stand.solve.pipeline import rigid_note


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", required=True, metavar="CFG", help="stand configuration (TOML)")
    p.add_argument("--rpm", required=True, type=parse_rpm, help="shaft speed [rpm]")
    p.add_argument(
        "--unbalance",
        action="append",
        type=parse_unbalance,
        required=True,
        metavar="G_MM@DEG",
        help="unbalance q R [g mm] @ angle [deg] from the reference mark, against the direction "
        "of rotation; give it twice: plane 1, then plane 2",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    if len(args.unbalance) != 2:
        n = len(args.unbalance)
        raise UsageError(f"stand forward: expected --unbalance twice (plane 1, plane 2), got {n}")
    cfg, params = load_config(args.config)
    g_mm = np.array([u[0] for u in args.unbalance])
    U = unbalance_from_polar(g_mm * 1e-6, [u[1] for u in args.unbalance])
    omega = float(rpm_to_rad_s(args.rpm))
    beam = cfg.rotor.beam()
    if beam is None:  # the rigid rotor
        A = forward(params, omega, U)
        fn_hz = natural_frequencies(params) / (2 * math.pi)
        warnings = speed_diagnostics(params, omega)
        bends = rigid_note(cfg, params, omega)
        if bends is not None:
            warnings.append(bends)
    else:  # [rotor.shaft]: the rotor bends
        A = forward_beam(beam, params, omega, U)
        fn_hz = natural_frequencies_beam(beam, params, 3) / (2 * math.pi)
        warnings = solve_beam(beam, params, omega, A).diagnostics
    amp, phase = phasor_to_polar(A)
    if args.json:
        dump_json(
            {
                "rpm": args.rpm,
                "supports": [
                    {
                        "node": i + 1,
                        "amplitude_m_s2": float(amp[i]),
                        "phase_deg": float(phase[i]),
                    }
                    for i in range(2)
                ],
                "natural_frequencies_hz": [float(f) for f in fn_hz],
                "warnings": [{"code": w.code, "message": w.message} for w in warnings],
            }
        )
        return 0
    print(f"speed {args.rpm:g} rpm ({omega / (2 * math.pi):.4g} Hz)")
    print("support  amplitude [m/s^2]  phase [deg]   (a = amplitude cos(theta + phase))")
    for i in range(2):
        print(f"{i + 1:>7}  {amp[i]:>17.6g}  {phase[i]:>11.2f}")
    print(
        "natural frequencies of stand + rotor: "
        + ", ".join(f"{f:.4g} Hz ({f * 60:.0f} rpm)" for f in fn_hz)
    )
    print_warnings(warnings)
    return 0
