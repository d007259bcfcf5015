"""``stand runup RUN``: a recorded run-up or coast-down read as the stand's frequency
response: each support's order-tracked 1x and 2x, the resonances (speed, damping by half-power and
by circle fit, amplification factor) against the model's modes, the balancing speed's
separation margin (API 684), the Bode, polar and waterfall plots and a page of it all."""

from __future__ import annotations

import argparse
import cmath
import math
from typing import Any

from stand.cli.common import add_force_argument, write_text_output
from stand.cli.format import dump_json
from stand.errors import MeasurementError
from stand.field.runup import RunupAnalysis, SecondOrder, analyse_runup
from stand.files import check_output
from stand.solve.recordings import read_run

RPM = 30 / math.pi


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run", metavar="RUN", help="the run file (.h5) of a run-up or coast-down")
    p.add_argument("--config", metavar="CFG", help="the configuration (default: the run's own)")
    p.add_argument("--rpm", type=float, metavar="RPM",
                   help="the balancing speed whose margins are asked (default: the run's top "
                   "speed)")  # fmt: skip
    p.add_argument("--vold-kalman", type=float, metavar="HZ", dest="vk_hz",
                   help="track the 1x with a Vold-Kalman filter of this half-power bandwidth "
                   "[Hz] (for a sweep too fast for revolution blocks; default: blocks of one "
                   "revolution)")  # fmt: skip
    p.add_argument("--plots", metavar="DIR",
                   help="write bode.png, polar.png and waterfall.png into DIR")  # fmt: skip
    p.add_argument("--report", metavar="PAGE.html",
                   help="write the run-up's page: the modes, the supports' peaks and 2x, "
                   "what was said, the plots inline")  # fmt: skip
    add_force_argument(p, "the plots and the page")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    from stand.errors import UsageError

    if args.rpm is not None and not (math.isfinite(args.rpm) and 1.0 <= args.rpm <= 1e6):
        raise UsageError(f"--rpm must be within 1 to 1e6, got {args.rpm}")
    if args.vk_hz is not None and not (math.isfinite(args.vk_hz) and 0.01 <= args.vk_hz <= 1e3):
        raise UsageError(f"--vold-kalman must be within 0.01 to 1000 Hz, got {args.vk_hz}")
    if args.report:  # refused before anything is read or written
        check_output(args.report, force=args.force, inputs=[args.run])
    got = read_run(args.run, args.config)
    try:
        a = analyse_runup(got.streams, got.cfg, got.params, args.rpm, args.vk_hz)
    except MeasurementError as exc:  # named with the run it is about
        raise MeasurementError(f"{args.run}: {exc}") from exc
    plots: list[str] = []
    if args.plots:
        from stand.report.runup_plot import runup_plots

        plots = runup_plots(a, args.plots, args.force)
    out = as_json(a)
    out["plots"] = plots
    if args.report:
        from stand.report.runup_page import render_runup

        page = render_runup(out, a, args.run)
        write_text_output(args.report, page, force=args.force, inputs=[args.run])
        out["report"] = args.report
    if args.json:
        dump_json(out)
    else:
        _print(a, plots, out)
    return 0


def _peak(r: Any) -> dict[str, Any]:
    """One peak of a support's shape: half-power and circle fit, both."""
    return {
        "rpm": round(r.omega_rad_s * RPM, 2),
        "half_power_rpm": [round(r.omega_1_rad_s * RPM, 2), round(r.omega_2_rad_s * RPM, 2)],
        "zeta_half_power": round(r.zeta, 5),
        "amplification_factor": round(r.amplification, 3),
        "circle_fit_rpm": None if r.circle_omega_rad_s is None else round(
            r.circle_omega_rad_s * RPM, 2),
        "zeta_circle_fit": None if r.circle_zeta is None else round(r.circle_zeta, 5),
        "points_in_band": r.points,
    }  # fmt: skip


def _x2(x: SecondOrder) -> dict[str, Any]:
    """A support's 2x: its largest, and at the balancing speed against the 1x there."""
    at = x.at_balancing_m_s2
    return {
        "peak_m_s2": round(x.peak_m_s2, 6), "peak_radius95_m_s2": round(x.peak_radius95_m_s2, 6),
        "peak_rpm": round(x.peak_omega_rad_s * RPM, 1),
        "at_balancing_m_s2": None if at is None else round(abs(at), 6),
        "at_balancing_phase_deg": None if at is None else round(math.degrees(cmath.phase(at))
                                                                % 360, 2),
        "at_balancing_radius95_m_s2": None if x.at_balancing_radius95_m_s2 is None
        else round(x.at_balancing_radius95_m_s2, 6),
        "share_of_1x_at_balancing_pct": None if at is None or not x.one_x_at_balancing_m_s2
        else round(100 * abs(at) / x.one_x_at_balancing_m_s2, 3),
        "points_at_balancing": x.blocks_at_balancing,
    }  # fmt: skip


def _modes(a: RunupAnalysis) -> list[dict[str, Any]]:
    """The fitted modes, each against the model's nearest and the balancing speed."""
    if a.modes is None:
        return []
    out = []
    for k, (w, z) in enumerate(zip(a.modes.omega_rad_s, a.modes.zeta, strict=True)):
        m = a.margins[k]
        near = min(range(len(a.model_omega_rad_s)), default=None,
                   key=lambda j: abs(a.model_omega_rad_s[j] - w))  # fmt: skip
        out.append({
            "rpm": round(w * RPM, 2), "zeta": round(z, 5),
            "amplification_factor": round(m.amplification, 3),
            "steady_reading_rpm": None if a.steady is None else round(
                a.steady.omega_rad_s[k] * RPM, 2),
            "steady_reading_zeta": None if a.steady is None else round(a.steady.zeta[k], 5),
            "model_rpm": None if near is None else round(a.model_omega_rad_s[near] * RPM, 2),
            "model_zeta": None if near is None else round(a.model_zeta[near], 5),
            "margin_pct": round(100 * m.margin, 2), "required_pct": round(100 * m.required, 2),
            "below_balancing_speed": m.below,
        })  # fmt: skip
    return out


def as_json(a: RunupAnalysis) -> dict[str, Any]:
    """The analysis as one strict JSON object (rpm and deg at the edge)."""
    return {
        "direction": a.direction,
        "sweep_rpm_per_s": round(a.sweep_rad_s2 * RPM, 3),
        "range_rpm": [round(w * RPM, 1) for w in a.omega_range_rad_s],
        "revolutions_per_point": a.revs_per_block,
        "tracking": "revolution blocks" if a.vk_hz is None else "Vold-Kalman",
        "vold_kalman_hz": a.vk_hz,
        "balancing_rpm": round(a.balancing_omega_rad_s * RPM, 1),
        "modes": _modes(a),
        "fit_residual": None if a.modes is None else round(a.modes.chi, 3),
        "supports": [
            {
                "support": c.support,
                "points": len(c.omega_rad_s),
                "peaks": [_peak(r) for r in c.resonances],
                "x2": _x2(x2),
            }
            for c, x2 in zip(a.curves, a.second, strict=True)
        ],
        "warnings": list(a.warnings),
    }


def _print(a: RunupAnalysis, plots: list[str], out: dict[str, Any]) -> None:
    lo, hi = (w * RPM for w in a.omega_range_rad_s)
    if a.direction == "coast-down":  # the speeds in the order the run went through them
        lo, hi = hi, lo
    print(f"{a.direction} from {lo:.0f} to {hi:.0f} rpm at {a.sweep_rad_s2 * RPM:.1f} rpm/s, "
          f"{a.revs_per_block} revolution(s) a point"
          + ("" if a.vk_hz is None else
             f", the 1x by a Vold-Kalman filter of {a.vk_hz:g} Hz"))  # fmt: skip
    print("mode  [rpm]   zeta     AF   model [rpm]  zeta    margin  API 684 asks  (as steady)")
    for k, m in enumerate(_modes(a), 1):
        print(f"  {k}  {m['rpm']:7.1f}  {m['zeta']:.4f}  {m['amplification_factor']:5.1f}"
              f"  {m['model_rpm'] or 0:9.1f}  {m['model_zeta'] or 0:.4f}"
              f"  {m['margin_pct']:5.1f} %  {m['required_pct']:5.1f} %"
              f"       ({m['steady_reading_rpm'] or 0:.1f} rpm)")  # fmt: skip
    for c in a.curves:
        for r in c.resonances:
            circle = "-" if r.circle_zeta is None else f"{r.circle_zeta:.4f}"
            print(f"support {c.support}: a peak at {r.omega_rad_s * RPM:.1f} rpm, zeta "
                  f"{r.zeta:.4f} (half-power), {circle} (circle fit), AF "
                  f"{r.amplification:.1f}")  # fmt: skip
    print(f"balancing speed {a.balancing_omega_rad_s * RPM:.0f} rpm")
    for x in a.second:
        j = _x2(x)
        at = (
            "not reached in the run"
            if j["at_balancing_m_s2"] is None
            else f"{j['at_balancing_m_s2']:.4f} +- {j['at_balancing_radius95_m_s2']:.4f} m/s^2 "
            f"at the balancing speed ({j['share_of_1x_at_balancing_pct']:.1f} % of the 1x)"
        )
        print(f"support {x.support}: 2x {at}; at most {j['peak_m_s2']:.4f} +- "
              f"{j['peak_radius95_m_s2']:.4f} m/s^2 at {j['peak_rpm']:.0f} rpm")  # fmt: skip
    for w in a.warnings:
        print(f"  warning: {w}")
    for p in plots:
        print(f"wrote {p}")
    if out.get("report"):
        print(f"wrote {out['report']}")
