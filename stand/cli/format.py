"""A result as text for the operator, and as strict JSON: formatting only.

Everything printed here comes from :func:`stand.solve.result_json.to_json`'s object,
so the text and the JSON of one run agree to the last digit shown.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import Any, TextIO

from stand.report import Display
from stand.solve import json_text
from stand.solve.keys import CONVENTION_WORDS, FITTED_WORDS
from stand.solve.recordings import recording_summary

ANGLE_NOTE = "angles from the reference mark, counted against the direction of rotation"


def print_warnings(warnings: Iterable[Any]) -> None:
    """Warnings (:class:`stand.core.Diagnostic`) to stderr, one line each."""
    for w in warnings:
        print(f"warning: {w.message}", file=sys.stderr)


def dump_json(obj: Any, out: TextIO | None = None) -> None:
    """One line of strict JSON on stdout (or ``out``)."""
    print(json_text(obj), file=out or sys.stdout)


def print_measurement(out: dict[str, Any]) -> None:
    """Speed, unbalance per plane, supports."""
    u = Display.of(out)
    print(f"speed {out['rpm']:.1f} rpm")
    print(
        f"plane  unbalance [{u.unbalance_unit}]    95 % +-   angle [deg]   "
        f"mass [{u.mass_unit}] at radius [{u.length_unit}]"
    )
    for p in out["planes"]:
        print(
            f"  {p['plane']}  {u.number(p['unbalance_g_mm']):>16} "
            f"{u.number(p['uncertainty_g_mm']):>10} {p['angle_deg']:13.2f} "
            f"{u.mass_value(p['mass_g']):10.3f} at {u.length(p['radius_mm']).split()[0]}"
        )
    cal = [p.get("calibration_interval_g_mm") for p in out["planes"]]
    if None not in cal:
        print(
            "the calibration's own 95 % +-: "
            + ", ".join(f"{u.number(c)}" for c in cal)
            + f" {u.unbalance_unit} (what the stand's parameters are known to, [calibration])"
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


def _pieces(w: dict[str, Any], u: Display) -> str:
    """`` (20 + 20 + 5 g)`` when a weight is stacked from stock weights."""
    p = w.get("pieces_g") or []
    if len(p) < 2:
        return ""
    if u.mass_unit == "g":
        return f" ({' + '.join(f'{x:g}' for x in p)} g)"
    return f" ({' + '.join(u.mass(x) for x in p)})"


def weights_text(c: dict[str, Any], u: Display | None = None) -> str:
    """``55.54 g at 30.0 deg (position 2) + ...`` for one plane's correction."""
    u = u or Display()
    return (
        " + ".join(
            f"{u.mass(w['mass_g'])}{_pieces(w, u)} at {w['angle_deg']:.1f} deg"
            + ("" if w["position"] is None else f" (position {w['position']})")
            for w in c["weights"]
        )
        or "nothing"
    )


def _machined(c: dict[str, Any], plane: dict[str, Any], u: Display) -> str:
    """A drilled or milled plane: one line per hole (in drilling order), then the leftover."""
    lines = [u.hole(h) for h in plane.get("holes") or []]
    if plane.get("slot"):
        lines.append(u.slot(plane["slot"]))
    judged = c.get("residual_within_tolerance")
    verdict = "" if judged is None else " (within tolerance)" if judged else " (OVER the tolerance)"
    head = (
        f"  plane {c['plane']}: {u.cuts(plane)}, removing {u.mass(plane['removed_g'])}; "
        f"leaves {u.unbalance(plane['leftover_g_mm'])}{verdict}"
    )
    return "\n".join([head, *(f"    {x}" for x in lines)] if lines else [head])


def _correction_line(c: dict[str, Any], u: Display, plane: dict[str, Any] | None = None) -> str:
    if c.get("within_noise"):
        return (
            f"  plane {c['plane']}: no correction: the unbalance is inside its own 95 % "
            "interval (its angle is undefined)"
        )
    if c.get("within_tolerance"):
        return f"  plane {c['plane']}: within tolerance: no correction needed"
    if plane is not None and "holes" in plane:
        return _machined(c, plane, u)
    left = (
        f"; rounding leaves {u.unbalance(c['residual_g_mm'])}" if c["residual_g_mm"] > 0.05 else ""
    )
    if left and c.get("residual_within_tolerance") is not None:
        left += (
            " (within tolerance)"
            if c["residual_within_tolerance"]
            else " (OVER the tolerance: finer weights are needed)"
        )
    radius = c["weights"][0]["radius_mm"] if c["weights"] else 0
    return (
        f"  plane {c['plane']}: {c['action']} {weights_text(c, u)} at radius "
        f"{u.length(radius)}{left}"
    )


VERBS = {"remove": "remove material", "add": "add weights", "drill": "drill holes",
         "mill": "mill a slot"}  # fmt: skip


def print_corrections(out: dict[str, Any]) -> None:
    """The corrections, static and couple parts, and the tolerance verdict."""
    u = Display.of(out)
    verb = VERBS.get(out["correction_mode"], "add weights")
    print(f"correction ({verb}; {ANGLE_NOTE}):")
    for c, plane in zip(out["corrections"], out["planes"], strict=True):
        print(_correction_line(c, u, plane))
    s, cp = out["static"], out["couple"]
    print(
        f"  static part {u.unbalance(s['unbalance_g_mm'])} at {s['angle_deg']:.1f} deg; couple "
        f"part +-{u.unbalance(cp['unbalance_g_mm'])} at {cp['angle_deg']:.1f} deg "
        "(plane 1 / plane 2)"
    )
    for k in out.get("keys") or []:
        print(
            f"key at {k['angle_deg']:g} deg ({u.mass(k['mass_g'])}): balanced with "
            f"{CONVENTION_WORDS[k['convention']]}, {FITTED_WORDS[k['fitted']]} fitted "
            "(ISO 21940-32); "
            f"mark the part {k['marking']}"
        )
    t = out.get("tolerance")
    if t is None:
        print("tolerance: none set (add a [tolerance] table: docs/tolerance.md)")
        return
    per = f": U_per {u.unbalance(t['permissible_g_mm'])}" if "permissible_g_mm" in t else ""
    print(f"tolerance: {t['source']} ({FORM_WORDS[t['form']]} form){per}")
    print(f"  judged in {t['judged_in']}")
    print(f"  rule: {t['rule']}")
    for c in t["criteria"]:
        print("  " + criterion_text(c, u, out))
    print(f"verdict: {VERDICT_WORDS[t['verdict']]}")
    stuck = [c for c in t["criteria"] if c["verdict"] == "undecided"]
    if stuck and all(c.get("limited_by") == "calibration" for c in stuck):
        print("  a longer run will not decide it: the calibration's own interval limits it")


FORM_WORDS = {"grade": "grade", "per_plane": "per plane", "static_couple": "resultant and moment",
              "api": "API"}  # fmt: skip
VERDICT_WORDS = {
    "pass": "PASS",
    "fail": "FAIL",
    "undecided": "UNDECIDED: the interval straddles the limit; measure longer to decide",
    "none": "none (no tolerance)",
}
"""The one verdict in the operator's words."""


def criterion_text(c: dict[str, Any], u: Display, out: dict[str, Any]) -> str:
    """One judged criterion: value +- its combined error against the limit, and its state."""
    if "value_g_mm2" in c:
        val = f"{u.number(c['value_g_mm2'])} +- {u.number(c['error_g_mm2'])} g mm^2"
        lim, margin = f"{u.number(c['permissible_g_mm2'])} g mm^2", c["margin_g_mm2"]
        gap = f"{u.number(abs(margin))} g mm^2"
    else:
        val = f"{u.unbalance(c['value_g_mm'])} +- {u.number(c['error_g_mm'])}"
        lim, margin = u.unbalance(c["permissible_g_mm"]), c["margin_g_mm"]
        gap = u.unbalance(abs(margin))
    how = "margin" if margin >= 0 else "over by"
    note = ""
    cal = (
        None
        if c["plane"] is None
        else out["planes"][c["plane"] - 1].get("calibration_interval_g_mm")
    )
    if c.get("limited_by") == "calibration" and cal is not None and c["verdict"] == "undecided":
        note = f"; the calibration's own +-{u.number(cal)} limits it"
    state = c["verdict"].upper() if c["verdict"] != "pass" else "pass"
    return f"{c['name']}: {val} against {lim}: {state} ({how} {gap}){note}"


def print_uncertainty(out: dict[str, Any]) -> None:
    """The parameter-tolerance spread, if computed."""
    pu = out.get("parameter_uncertainty")
    if pu is None:
        return
    u = Display.of(out)
    t = pu["tolerances"]
    print(
        f"parameter tolerances (uniform): C +-{t['C_pct']:g} %, M and J3 +-{t['M_pct']:g} %, "
        f"lengths +-{u.length(t['length_mm'])}, sensor gains +-{t['gain_pct']:g} %"
    )
    for p in pu["planes"]:
        top = ", ".join(f"{k} {100 * s:.0f} %" for k, s in p["largest_shares"])
        print(
            f"  plane {p['plane']}: 95 % +-{u.unbalance(p['radius95_monte_carlo_g_mm'])} "
            f"(Monte Carlo, {pu['draws']} draws; linearised "
            f"{u.number(p['radius95_linear_g_mm'])}); with the measurement "
            f"+-{u.number(p['combined_g_mm'])}; most from {top}"
        )


def print_check(out: dict[str, Any]) -> None:
    """Before and after a correction, with the unbalance reduction ratio."""
    c = out.get("check")
    if c is None:
        return
    u = Display.of(out)
    print(f"check against the run before the correction ({c['previous_run']}):")
    for p in c["planes"]:
        urr = "-" if p["urr"] is None else f"{100 * p['urr']:.1f} %"
        print(
            f"  plane {p['plane']}: {u.number(p['before_g_mm'])} -> "
            f"{u.unbalance(p['after_g_mm'])} residual, reduction ratio URR {urr}"
        )


def tooling_line(out: dict[str, Any]) -> str | None:
    """``tooling mandrel-A subtracted: ...`` when a tooling compensation was used."""
    t = out.get("tooling")
    if t is None:
        return None
    u = Display.of(out)
    planes = "; ".join(
        f"plane {p['plane']} {u.unbalance(p['unbalance_g_mm'])} at {p['angle_deg']:.1f} deg"
        for p in t["subtracted"]
    )
    return f"tooling {t['name']} subtracted (measured {t['measured'][:10]}): {planes}"


def print_result(out: dict[str, Any]) -> None:
    """The whole result as text (stdout); warnings go to stderr."""
    print_measurement(out)
    if line := tooling_line(out):
        print(line)
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

    out = recording_summary(rec, streams)
    if as_json:
        dump_json(out)
    else:
        print_summary(out)
        print_warnings((*rec.warnings, *streams.warnings))


def print_speeds(out: dict[str, Any]) -> None:
    """A correction across speeds (:func:`stand.field.speeds.speeds_json`): the planes, then per
    speed each measuring plane before and after against its permissible value."""
    print(f"correction in {len(out['planes'])} planes for {len(out['speeds'])} speeds:")
    for p in out["planes"]:
        ws = " + ".join(f"{w['mass_g']:.2f} g at {w['angle_deg']:.1f} deg" for w in p["weights"])
        extra = " (left out: the other planes do what it would)" if p["dependent"] else ""
        if p["at_limit"]:
            extra += " (at the mass limit --max-mass-g: the runs ask for more)"
        print(
            f"  plane {p['plane']} at {p['position_mm']:g} mm: {p['action']} {ws or 'nothing'} "
            f"at radius {p['radius_mm']:g} mm{extra}"
        )
        if not p["dependent"]:
            print(
                f"    its unbalance {p['unbalance_g_mm']:.1f} +- {p['uncertainty_g_mm']:.1f} g mm "
                "(95 %, from the runs' noise)"
            )
    print(f"({ANGLE_NOTE})")
    if out.get("slow_roll"):
        sr = out["slow_roll"]
        um = " and ".join(f"{x:.1f}" for x in sr["runout_um"])
        print(f"slow roll at {sr['rpm']:.0f} rpm taken out first: the journals run out {um} um")
    print("speed [rpm]   plane 1 before -> after [g mm]   plane 2 before -> after   permissible")
    for s in out["speeds"]:
        (b1, b2), (a1, a2) = s["before"], s["after"]
        per = s["permissible_g_mm"]
        verdict = {None: "", True: "  pass", False: "  FAIL"}[s["pass_after"]]
        print(
            f"  {s['rpm']:9.0f}   {b1['unbalance_g_mm']:9.1f} -> {a1['unbalance_g_mm']:8.1f}"
            f"          {b2['unbalance_g_mm']:9.1f} -> {a2['unbalance_g_mm']:8.1f}"
            f"   {'' if per is None else f'{per[0]:.0f} / {per[1]:.0f}'}{verdict}"
        )
