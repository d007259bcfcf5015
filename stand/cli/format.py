"""A result as text for the operator, and as strict JSON: formatting only.

Everything printed here comes from :func:`stand.result.to_json`'s object,
so the text and the JSON of one run agree to the last digit shown.
"""

from __future__ import annotations

import json
import math
import sys
from typing import Any, TextIO

from stand.errors import ModelError

ANGLE_NOTE = "angles from the reference mark, counted against the direction of rotation"


def finite(obj: Any, where: str = "") -> Any:
    """``obj`` if every number in it is finite; else :class:`ModelError` naming the key.

    A NaN or an infinity in an answer means the inputs carry no physics (a speed
    of 1e300 rpm, NaN timestamps): it is refused, never printed.
    """
    if isinstance(obj, float) and not math.isfinite(obj):
        raise ModelError(f"the answer is not a finite number at {where or 'the top'} ({obj}): "
                         "the inputs make no physical sense")  # fmt: skip
    if isinstance(obj, dict):
        for k, v in obj.items():
            finite(v, f"{where}.{k}" if where else str(k))
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            finite(v, f"{where}[{i}]")
    return obj


def json_text(obj: Any, **kwargs: Any) -> str:
    """Strict JSON (no NaN or Infinity: :func:`finite` refuses them first)."""
    return json.dumps(finite(obj), allow_nan=False, **kwargs)


def dump_json(obj: Any, out: TextIO | None = None) -> None:
    """One line of strict JSON on stdout (or ``out``)."""
    print(json_text(obj), file=out or sys.stdout)


def print_measurement(out: dict[str, Any]) -> None:
    """Speed, unbalance per plane, supports."""
    print(f"speed {out['rpm']:.1f} rpm")
    print("plane  unbalance [g mm]    95 % +-   angle [deg]   mass [g] at radius [mm]")
    for p in out["planes"]:
        print(
            f"  {p['plane']}  {p['unbalance_g_mm']:16.1f} {p['uncertainty_g_mm']:10.1f} "
            f"{p['angle_deg']:13.2f} {p['mass_g']:10.3f} at {p['radius_mm']:g}"
        )
    print(f"({ANGLE_NOTE})")
    print("support  amplitude [m/s^2]  phase [deg]  95 % +-   revolutions")
    for s in out["supports"]:
        print(
            f"  {s['node']}  {s['amplitude_m_s2']:17.5f} {s['phase_deg']:12.2f} "
            f"{s['uncertainty_m_s2']:9.5f} {s['revolutions']:10.1f}"
        )
    cost = out["supports"][0]["noise_cost"]
    if cost > 1.0:
        print(f"(taper: the noise variance is {cost:.2f} times that of the plain fit)")


def _pieces(w: dict[str, Any]) -> str:
    """`` (20 + 20 + 5 g)`` when a weight is stacked from stock weights."""
    p = w.get("pieces_g") or []
    return f" ({' + '.join(f'{x:g}' for x in p)} g)" if len(p) > 1 else ""


def weights_text(c: dict[str, Any]) -> str:
    """``55.54 g at 30.0 deg (position 2) + ...`` for one plane's correction."""
    return (
        " + ".join(
            f"{w['mass_g']:.2f} g{_pieces(w)} at {w['angle_deg']:.1f} deg"
            + ("" if w["position"] is None else f" (position {w['position']})")
            for w in c["weights"]
        )
        or "nothing"
    )


def print_corrections(out: dict[str, Any]) -> None:
    """The corrections, static and couple parts, and the tolerance verdict."""
    verb = "remove material" if out["correction_mode"] == "remove" else "add weights"
    print(f"correction ({verb}; {ANGLE_NOTE}):")
    for c in out["corrections"]:
        if c.get("within_noise"):
            print(
                f"  plane {c['plane']}: no correction: the unbalance is inside its own 95 % "
                "interval (its angle is undefined)"
            )
            continue
        if c.get("within_tolerance"):
            print(f"  plane {c['plane']}: within tolerance: no correction needed")
            continue
        left = (
            f"; rounding leaves {c['residual_g_mm']:.1f} g mm" if c["residual_g_mm"] > 0.05 else ""
        )
        if left and c.get("residual_within_tolerance") is not None:
            left += (
                " (within tolerance)"
                if c["residual_within_tolerance"]
                else " (OVER the tolerance: finer weights are needed)"
            )
        radius = c["weights"][0]["radius_mm"] if c["weights"] else 0
        print(
            f"  plane {c['plane']}: {c['action']} {weights_text(c)} at radius {radius:g} mm{left}"
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


def print_check(out: dict[str, Any]) -> None:
    """Before and after a correction, with the unbalance reduction ratio."""
    c = out.get("check")
    if c is None:
        return
    print(f"check against the run before the correction ({c['previous_run']}):")
    for p in c["planes"]:
        urr = "-" if p["urr"] is None else f"{100 * p['urr']:.1f} %"
        print(
            f"  plane {p['plane']}: {p['before_g_mm']:.1f} -> {p['after_g_mm']:.1f} g mm "
            f"residual, reduction ratio URR {urr}"
        )


def print_result(out: dict[str, Any]) -> None:
    """The whole result as text (stdout); warnings go to stderr."""
    print_measurement(out)
    print_corrections(out)
    print_uncertainty(out)
    if "stopped_by" in out:
        print(
            f"stopped by: {out['stopped_by']} after {out['elapsed_s']:.1f} s; "
            f"recorded in {out['run_file']}"
        )
    print_check(out)
    for w in out["warnings"]:
        print(f"warning: {w}", file=sys.stderr)


def show(out: dict[str, Any], as_json: bool) -> None:
    """Print a result: one strict JSON object, or the text."""
    if as_json:
        dump_json(out)
    else:
        print_result(out)


def progress_line(p: Any) -> str:
    """One line of the live display."""
    from stand.core import rad_s_to_rpm

    m = p.measurement
    planes = "  ".join(
        f"plane {i + 1}: {abs(m.solution.U_kg_m[i]) * 1e6:.1f} "
        f"+- {m.radius95_kg_m[i] * 1e6:.1f} g mm (precision goal +- {p.targets_kg_m[i] * 1e6:.1f})"
        for i in range(2)
    )
    amps = " ".join(f"{abs(ph.A_m_s2):.3f}" for ph in m.supports)
    rpm = float(rad_s_to_rpm(m.omega_rad_s))
    return f"  {p.elapsed_s:5.1f} s  {rpm:7.1f} rpm  1x {amps} m/s2  {planes}"


def print_summary(out: dict[str, Any]) -> None:
    """The inspect object as a short table (stdout), warnings on stderr."""
    print(
        f"{out['file']}: {out['frames']} frames over {out['duration_s']:.3f} s, "
        f"{out['unknown_frames']} with other ids, {out['bad_frames']} malformed"
    )
    if out["run"]:
        r = out["run"]
        print(
            f"  recorded {r.get('start_time', '?')} by {r.get('software', '?')} from "
            f"{r.get('source', '?')}{'' if r.get('complete', True) else ' (cut short)'}"
        )
    head = (
        f"  {'node':>4} {'frames':>8} {'samples':>9} {'lost':>6} {'invalid':>7} {'marks':>6} "
        f"{'rate Hz':>8} {'µm/s²':>6} {'rpm':>10}  flags"
    )
    print(head)
    for n in out["nodes"]:
        rpm = "-" if n["rpm"] is None else f"{n['rpm']:.2f}"
        rate = "-" if n["rate_hz"] is None else f"{n['rate_hz']:g}"
        scale = "-" if n["scale_um_s2"] is None else f"{n['scale_um_s2']:g}"
        print(
            f"  {n['node']:>4} {n['frames']:>8} {n['samples']:>9} {n['lost_frames']:>6} "
            f"{n['invalid_samples']:>7} {n['marks']:>6} {rate:>8} {scale:>6} {rpm:>10}  "
            f"{','.join(n['flags']) or '-'}"
        )


def print_recording(rec: Any, streams: Any, *, as_json: bool) -> None:
    """What a recording holds: one JSON object, or the table (and the warnings on stderr)."""
    from stand.cli.common import print_warnings
    from stand.pipeline import recording_summary

    out = recording_summary(rec, streams)
    if as_json:
        dump_json(out)
    else:
        print_summary(out)
        print_warnings((*rec.warnings, *streams.warnings))
