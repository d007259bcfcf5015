"""Solve a recorded run: the unbalance of both planes, with its 95 % interval."""

from __future__ import annotations

import argparse
import json
import sys
import tomllib
from typing import Any

from stand.cli.common import UsageError
from stand.errors import ConfigError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("runs", nargs="+", metavar="RUN", help="run files (.h5) or python-can logs")
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration (default: the one stored in the run file)",
    )
    add_measure_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object (one run)")
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        metavar="N",
        help="solve several runs in N processes (default 1)",
    )
    p.add_argument("--summary", metavar="FILE", help="write a summary of all runs: .csv or .json")
    add_uncertainty_arguments(p)


def add_uncertainty_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("parameter tolerances (--uncertainty)")
    g.add_argument(
        "--uncertainty",
        action="store_true",
        help="add the spread the parameter tolerances cause (linearised and Monte Carlo)",
    )
    g.add_argument("--tol-c", type=float, default=5.0, metavar="PCT", help="C1, C2 (default 5)")
    g.add_argument(
        "--tol-m", type=float, default=2.0, metavar="PCT", help="M1, M2, M3, J3 (default 2)"
    )
    g.add_argument(
        "--tol-length-mm", type=float, default=1.0, metavar="MM", help="a, b, c, d (default 1)"
    )
    g.add_argument(
        "--tol-gain",
        type=float,
        default=1.0,
        metavar="PCT",
        help="sensor sensitivities (default 1)",
    )
    g.add_argument("--draws", type=int, default=1000, help="Monte Carlo draws (default 1000)")


def uncertainty(m: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    """The parameter-tolerance part of the result."""
    import math

    import numpy as np

    from calib.tolerance import Tolerances, parameter_uncertainty

    for name in ("tol_c", "tol_m", "tol_length_mm", "tol_gain"):
        if getattr(args, name) < 0:
            flag = "--" + name.replace("_", "-")
            raise UsageError(f"stand solve: {flag} must be >= 0, got {getattr(args, name)}")
    if args.draws < 10:
        raise UsageError(f"stand solve: --draws must be >= 10, got {args.draws}")
    tol = Tolerances(
        C_rel=args.tol_c / 100,
        M_rel=args.tol_m / 100,
        length_m=args.tol_length_mm / 1000,
        gain_rel=args.tol_gain / 100,
    )
    omega = m.rpm * 2 * math.pi / 60
    A = np.array([ph.A_m_s2 for ph in m.supports])
    r = parameter_uncertainty(params, omega, A, tol, draws=args.draws)
    planes = []
    for i in range(2):
        top = sorted(r.shares.items(), key=lambda kv: -kv[1][i])[:3]
        lin, mc = float(r.radius95_linear[i]), float(r.radius95_monte_carlo[i])
        planes.append(
            {
                "plane": i + 1,
                "radius95_linear_g_mm": round(lin * 1e6, 3),
                "radius95_monte_carlo_g_mm": round(mc * 1e6, 3),
                "combined_g_mm": round(math.hypot(mc, float(m.radius95_kg_m[i])) * 1e6, 3),
                "largest_shares": [[k, round(v[i], 4)] for k, v in top],
            }
        )
    return {
        "parameter_uncertainty": {
            "tolerances": {
                "C_pct": args.tol_c,
                "M_pct": args.tol_m,
                "length_mm": args.tol_length_mm,
                "gain_pct": args.tol_gain,
                "distribution": "uniform within +-tolerance",
            },
            "draws": r.draws,
            "planes": planes,
        }
    }


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


def solve_recording(
    path: str,
    config: str | None,
    taper: bool = False,
    gate: bool = True,
    tolerances: argparse.Namespace | None = None,
) -> tuple[dict[str, Any], Any, Any, Any]:
    """Solve one run: the result, and the recording, streams and config it came from."""
    from drivers.recording import read_recording
    from drivers.streams import rebuild
    from stand.measure import measure

    rec = read_recording(path)
    cfg, params = config_for(rec, config)
    streams = rebuild(rec.frames)
    m = measure(streams, params, **cfg.measure_options(), taper=taper, gate=gate)
    out = result(m, [*streams.warnings, *m.warnings])
    out.update(corrections(m, cfg, params))
    if tolerances is not None and tolerances.uncertainty:
        out.update(uncertainty(m, params, tolerances))
    return out, rec, streams, cfg


def solve_one(
    path: str,
    config: str | None,
    taper: bool = False,
    gate: bool = True,
    tolerances: argparse.Namespace | None = None,
) -> dict[str, Any]:
    """The whole result of one run (raises :class:`StandError` on bad input)."""
    return solve_recording(path, config, taper, gate, tolerances)[0]


def run(args: argparse.Namespace) -> int:
    if args.jobs < 1:
        raise UsageError(f"stand solve: --jobs must be >= 1, got {args.jobs}")
    if args.summary and not args.summary.lower().endswith((".csv", ".json")):
        raise UsageError(f"stand solve: --summary must end in .csv or .json, got {args.summary!r}")
    if len(args.runs) > 1 or args.summary:
        from stand.cli.solve_batch import run_batch

        return run_batch(args)
    out = solve_one(args.runs[0], args.config, args.taper, not args.no_gate, args)
    if show(out, args.json):
        for w in out["warnings"]:
            print(f"warning: {w}", file=sys.stderr)
    return 0


def corrections(m: Any, cfg: Any, params: Any) -> dict[str, Any]:
    """Corrections, static and couple parts, and the ISO 21940-11 tolerance, for the result."""
    import math

    from stand.core import unbalance_to_polar
    from stand.core.balance import (
        correction,
        permissible_unbalance,
        plane_tolerances,
        static_couple,
    )

    c = cfg.correction
    out: dict[str, Any] = {"correction_mode": c.mode, "corrections": []}
    for i, U in enumerate(m.solution.U_kg_m):
        R = m.radius_m[i]
        corr = correction(
            complex(U),
            R,
            remove=c.mode == "remove",
            positions=c.positions,
            position0_deg=c.position0_deg,
            steps_kg=[w * 1e-3 for w in c.weights_g],
            step_kg=c.weight_step_g * 1e-3,
        )
        out["corrections"].append(
            {
                "plane": i + 1,
                "action": c.mode,
                "weights": [
                    {
                        "mass_g": round(w.mass_kg * 1e3, 4),
                        "angle_deg": round(w.angle_deg, 3),
                        "position": w.position,
                        "radius_mm": round(R * 1e3, 3),
                    }
                    for w in corr.weights
                ],
                "residual_g_mm": round(abs(corr.residual_kg_m) * 1e6, 3),
            }
        )
    static, couple = static_couple(params, m.solution.U_kg_m)
    (qs, qc), (ps, pc) = unbalance_to_polar([static, couple])
    out["static"] = {"unbalance_g_mm": round(float(qs) * 1e6, 3), "angle_deg": round(float(ps), 3)}
    out["couple"] = {"unbalance_g_mm": round(float(qc) * 1e6, 3), "angle_deg": round(float(pc), 3)}
    t = cfg.tolerance
    if t is not None:
        U_per = permissible_unbalance(
            params.M3, t.grade_mm_s * 1e-3, t.max_speed_rpm * 2 * math.pi / 60
        )
        per = plane_tolerances(params, U_per)
        planes = []
        for i in range(2):
            u, r = abs(m.solution.U_kg_m[i]), float(m.radius95_kg_m[i])
            planes.append(
                {
                    "plane": i + 1,
                    "permissible_g_mm": round(per[i] * 1e6, 3),
                    "residual_g_mm": round(u * 1e6, 3),
                    "pass": bool(u <= per[i]),
                    "margin_g_mm": round((per[i] - u) * 1e6, 3),
                    "pass_with_uncertainty": bool(u + r <= per[i]),
                }
            )
        out["tolerance"] = {
            "standard": "ISO 21940-11",
            "grade_mm_s": t.grade_mm_s,
            "max_speed_rpm": t.max_speed_rpm,
            "permissible_g_mm": round(U_per * 1e6, 3),
            "planes": planes,
        }
    return out


def print_corrections(out: dict[str, Any]) -> None:
    """The corrections and the tolerance, for the operator."""
    verb = "remove material" if out["correction_mode"] == "remove" else "add weights"
    print(
        f"correction ({verb}; angles from the reference mark, counted against the "
        "direction of rotation):"
    )
    for c in out["corrections"]:
        what = (
            " + ".join(
                f"{w['mass_g']:.2f} g at {w['angle_deg']:.1f} deg"
                + ("" if w["position"] is None else f" (position {w['position']})")
                for w in c["weights"]
            )
            or "nothing"
        )
        left = (
            f"; rounding leaves {c['residual_g_mm']:.1f} g mm" if c["residual_g_mm"] > 0.05 else ""
        )
        print(
            f"  plane {c['plane']}: {c['action']} {what} at radius "
            f"{c['weights'][0]['radius_mm'] if c['weights'] else 0:g} mm{left}"
        )
    s, cp = out["static"], out["couple"]
    print(
        f"  static part {s['unbalance_g_mm']:.1f} g mm at {s['angle_deg']:.1f} deg; couple part "
        f"+-{cp['unbalance_g_mm']:.1f} g mm at {cp['angle_deg']:.1f} deg (plane 1 / plane 2)"
    )
    t = out.get("tolerance")
    if t is None:
        print("tolerance: none set (add a [tolerance] table: grade_mm_s, max_speed_rpm)")
        return
    print(
        f"tolerance {t['standard']} G {t['grade_mm_s']:g} at {t['max_speed_rpm']:g} rpm: "
        f"U_per {t['permissible_g_mm']:.1f} g mm"
    )
    for p in t["planes"]:
        verdict = "pass" if p["pass"] else "FAIL"
        how = f"margin {p['margin_g_mm']:.1f}" if p["pass"] else f"over by {-p['margin_g_mm']:.1f}"
        print(
            f"  plane {p['plane']}: {p['residual_g_mm']:.1f} g mm against "
            f"{p['permissible_g_mm']:.1f} permissible: {verdict} ({how} g mm)"
        )


def show(out: dict[str, Any], as_json: bool) -> bool:
    """Print a result: one JSON object, or the tables (then True: the caller adds its lines)."""
    if as_json:
        json.dump(out, sys.stdout)
        print()
        return False
    print_result(out)
    print_corrections(out)
    print_uncertainty(out)
    return True


def print_uncertainty(out: dict[str, Any]) -> None:
    """The parameter-tolerance spread, if computed."""
    pu = out.get("parameter_uncertainty")
    if pu is None:
        return
    t = pu["tolerances"]
    print(
        f"parameter tolerances (uniform): C +-{t['C_pct']:g} %, M and J3 +-{t['M_pct']:g} %, "
        f"lengths +-{t['length_mm']:g} mm, sensor gains +-{t['gain_pct']:g} %"
    )
    for p in pu["planes"]:
        top = ", ".join(f"{k} {100 * s:.0f} %" for k, s in p["largest_shares"])
        print(
            f"  plane {p['plane']}: 95 % +-{p['radius95_monte_carlo_g_mm']:.1f} g mm "
            f"(Monte Carlo, {pu['draws']} draws; linearised {p['radius95_linear_g_mm']:.1f}); "
            f"with the measurement +-{p['combined_g_mm']:.1f}; most from {top}"
        )
