"""A result as text for the operator, and as strict JSON: formatting only.

Everything printed here comes from :func:`stand.solve.result_json.to_json`'s object,
so the text and the JSON of one run agree to the last digit shown.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import Any, TextIO

from stand.i18n import Display
from stand.i18n.language import ENGLISH, N_, Language
from stand.report.units import ACTIONS, cycle_sentence, verdict_word
from stand.solve import json_text
from stand.solve.keys import CONVENTION_WORDS, FITTED_WORDS
from stand.solve.recordings import recording_summary

ANGLE_NOTE = N_("angles from the reference mark, counted against the direction of rotation")


def print_warnings(warnings: Iterable[Any], _: Language = ENGLISH) -> None:
    """Warnings (:class:`stand.core.Diagnostic`) to stderr, one line each."""
    for w in warnings:
        print(_("warning: {message}").format(message=_(w.message)), file=sys.stderr)


def dump_json(obj: Any, out: TextIO | None = None) -> None:
    """One line of strict JSON on stdout (or ``out``)."""
    print(json_text(obj), file=out or sys.stdout)


def print_measurement(out: dict[str, Any], _: Language = ENGLISH) -> None:
    """Speed, unbalance per plane, supports."""
    u = Display.of(out, _)
    print(_("speed {rpm} rpm").format(rpm=u.decimals(f"{out['rpm']:.1f}")))
    print(_("plane  unbalance [{unit}]    95 % +-   angle [deg]   mass [{mass}] at radius "
            "[{length}]").format(unit=u.unbalance_unit, mass=u.symbol(u.mass_unit),
                                 length=u.symbol(u.length_unit)))  # fmt: skip
    for p in out["planes"]:
        angle = f"{'-':>13}" if p.get("within_noise") else f"{p['angle_deg']:13.2f}"
        figures = f"{angle} {u.mass_value(p['mass_g']):10.3f}"
        print(
            f"  {p['plane']}  {u.number(p['unbalance_g_mm']):>16} "
            f"{u.number(p['uncertainty_g_mm']):>10} {u.decimals(figures)} {_('at')} "
            f"{u.length(p['radius_mm']).split()[0]}"
        )
    cal = [p.get("calibration_interval_g_mm") for p in out["planes"]]
    if None not in cal:
        print(_("the calibration's own 95 % +-: {values} {unit} (what the stand's parameters "
                "are known to, [calibration])").format(
            values=", ".join(f"{u.number(c)}" for c in cal), unit=u.unbalance_unit))  # fmt: skip
    print(f"({_(ANGLE_NOTE)})")
    print(_("support  amplitude [m/s^2]  phase [deg]  95 % +-   revolutions"))
    for s in out["supports"]:
        line = (f"  {s['node']}  {s['amplitude_m_s2']:17.5f} {s['phase_deg']:12.2f} "
                f"{s['uncertainty_m_s2']:9.5f} {s['revolutions']:10.1f}")  # fmt: skip
        print(u.decimals(line))
    cost = out["supports"][0]["noise_cost"]
    if cost > 1.0:
        print(_("(taper: the noise variance is {k} times that of the plain fit)").format(
            k=u.decimals(f"{cost:.2f}")))  # fmt: skip


def _pieces(w: dict[str, Any], u: Display) -> str:
    """`` (20 + 20 + 5 g)`` when a weight is stacked from stock weights."""
    p = w.get("pieces_g") or []
    if len(p) < 2:
        return ""
    if u.mass_unit == "g":
        return f" ({' + '.join(u.decimals(f'{x:g}') for x in p)} g)"
    return f" ({' + '.join(u.mass(x) for x in p)})"


def weights_text(c: dict[str, Any], u: Display | None = None, _: Language = ENGLISH) -> str:
    """``55.54 g at 30.0 deg (position 2) + ...`` for one plane's correction."""
    u = u or Display()
    return (
        " + ".join(
            _("{mass} at {angle} deg").format(mass=f"{u.mass(w['mass_g'])}{_pieces(w, u)}",
                                              angle=u.decimals(f"{w['angle_deg']:.1f}"))
            + ("" if w["position"] is None
               else " " + _("(position {n})").format(n=w["position"]))
            for w in c["weights"]
        )
        or _("nothing")
    )  # fmt: skip


def _judged(judged: bool | None, over: str, _: Language) -> str:
    """`` (within tolerance)``, `` (OVER the tolerance...)`` or nothing."""
    if judged is None:
        return ""
    return " " + (_("(within tolerance)") if judged else _(over))


def _machined(c: dict[str, Any], plane: dict[str, Any], u: Display, _: Language) -> str:
    """A drilled or milled plane: one line per hole (in drilling order), then the leftover."""
    lines = [u.hole(h, _) for h in plane.get("holes") or []]
    if plane.get("slot"):
        lines.append(u.slot(plane["slot"], _))
    verdict = _judged(c.get("residual_within_tolerance"), N_("(OVER the tolerance)"), _)
    head = "  " + _("plane {plane}: {cuts}, removing {mass}; leaves {left}").format(
        plane=c["plane"], cuts=u.cuts(plane, _), mass=u.mass(plane["removed_g"]),
        left=u.unbalance(plane["leftover_g_mm"])) + verdict  # fmt: skip
    return "\n".join([head, *(f"    {x}" for x in lines)] if lines else [head])


def _correction_line(
    c: dict[str, Any], u: Display, plane: dict[str, Any] | None = None, _: Language = ENGLISH
) -> str:
    if c.get("within_noise"):
        return "  " + _("plane {plane}: no correction: the unbalance is inside its own 95 % "
                        "interval (its angle is undefined)").format(plane=c["plane"])  # fmt: skip
    if c.get("within_tolerance"):
        return "  " + _("plane {plane}: within tolerance: no correction needed").format(
            plane=c["plane"])  # fmt: skip
    if plane is not None and "holes" in plane:
        return _machined(c, plane, u, _)
    left = ""
    if c["residual_g_mm"] > 0.05:
        left = "; " + _("rounding leaves {left}").format(left=u.unbalance(c["residual_g_mm"]))
        left += _judged(c.get("residual_within_tolerance"),
                        N_("(OVER the tolerance: finer weights are needed)"), _)  # fmt: skip
    radius = c["weights"][0]["radius_mm"] if c["weights"] else 0
    return "  " + _("plane {plane}: {action} {weights} at radius {radius}").format(
        plane=c["plane"], action=_(ACTIONS.get(c["action"], c["action"])),
        weights=weights_text(c, u, _), radius=u.length(radius)) + left  # fmt: skip


VERBS = {"remove": N_("remove material"), "add": N_("add weights"), "drill": N_("drill holes"),
         "mill": N_("mill a slot")}  # fmt: skip


def print_corrections(out: dict[str, Any], _: Language = ENGLISH) -> None:
    """The corrections, static and couple parts, and the tolerance verdict."""
    u = Display.of(out, _)
    verb = VERBS.get(out["correction_mode"], VERBS["add"])
    print(_("correction ({verb}; {note}):").format(verb=_(verb), note=_(ANGLE_NOTE)))
    for c, plane in zip(out["corrections"], out["planes"], strict=True):
        print(_correction_line(c, u, plane, _))
    s, cp = out["static"], out["couple"]
    print("  " + _("static part {static} at {a1} deg; couple part +-{couple} at {a2} deg "
                   "(plane 1 / plane 2)").format(
        static=u.unbalance(s["unbalance_g_mm"]), a1=u.decimals(f"{s['angle_deg']:.1f}"),
        couple=u.unbalance(cp["unbalance_g_mm"]),
        a2=u.decimals(f"{cp['angle_deg']:.1f}")))  # fmt: skip
    for k in out.get("keys") or []:
        print(_("key at {angle} deg ({mass}): balanced with {convention}, {fitted} fitted "
                "(ISO 21940-32); mark the part {marking}").format(
            angle=u.decimals(f"{k['angle_deg']:g}"), mass=u.mass(k["mass_g"]),
            convention=_(CONVENTION_WORDS[k["convention"]]), fitted=_(FITTED_WORDS[k["fitted"]]),
            marking=k["marking"]))  # fmt: skip
    print_tolerance(out, u, _)


def print_tolerance(out: dict[str, Any], u: Display, _: Language = ENGLISH) -> None:
    """The tolerance, its rule, each criterion judged, and the verdict."""
    t = out.get("tolerance")
    if t is None:
        print(_("tolerance: none set (add a [tolerance] table: docs/tolerance.md)"))
        return
    per = (": U_per " + u.unbalance(t["permissible_g_mm"])) if "permissible_g_mm" in t else ""
    print(_("tolerance: {source} ({form} form)").format(
        source=_(t["source"]), form=_(FORM_WORDS[t["form"]])) + per)  # fmt: skip
    print("  " + _("judged in {where}").format(where=_(t["judged_in"])))
    if t.get("allocation"):
        print("  " + _("allocation: {rule}").format(rule=_(t["allocation"])))
    print("  " + _("rule: {rule}").format(rule=_(t["rule"])))
    for c in t["criteria"]:
        print("  " + criterion_text(c, u, out, _))
    print(_("verdict: {verdict}").format(verdict=_(VERDICT_WORDS[t["verdict"]])))
    stuck = [c for c in t["criteria"] if c["verdict"] == "undecided"]
    if stuck and all(c.get("limited_by") == "calibration" for c in stuck):
        print("  " + _("a longer run will not decide it: the calibration's own interval limits "
                       "it"))  # fmt: skip


FORM_WORDS = {"grade": N_("grade"), "per_plane": N_("per plane"),
              "static_couple": N_("resultant and moment"), "api": N_("API")}  # fmt: skip
VERDICT_WORDS = {
    "pass": N_("PASS"),
    "fail": N_("FAIL"),
    "undecided": N_("UNDECIDED: the interval straddles the limit; measure longer to decide"),
    "none": N_("none (no tolerance)"),
}
"""The one verdict in the operator's words."""


def criterion_text(
    c: dict[str, Any], u: Display, out: dict[str, Any], _: Language = ENGLISH
) -> str:
    """One judged criterion: value +- its combined error against the limit, and its state."""
    if "value_g_mm2" in c:
        val = f"{u.number(c['value_g_mm2'])} +- {u.number(c['error_g_mm2'])} g mm^2"
        lim, margin = f"{u.number(c['permissible_g_mm2'])} g mm^2", c["margin_g_mm2"]
        gap = f"{u.number(abs(margin))} g mm^2"
    else:
        val = f"{u.unbalance(c['value_g_mm'])} +- {u.number(c['error_g_mm'])}"
        lim, margin = u.unbalance(c["permissible_g_mm"]), c["margin_g_mm"]
        gap = u.unbalance(abs(margin))
    how = _("margin") if margin >= 0 else _("over by")
    note = ""
    cal = (
        None
        if c["plane"] is None
        else out["planes"][c["plane"] - 1].get("calibration_interval_g_mm")
    )
    if c.get("limited_by") == "calibration" and cal is not None and c["verdict"] == "undecided":
        note = "; " + _("the calibration's own +-{interval} limits it").format(
            interval=u.number(cal))  # fmt: skip
    state = _("pass") if c["verdict"] == "pass" else verdict_word(c["verdict"], _)
    return _("{name}: {value} against {limit}: {state} ({how} {gap})").format(
        name=_(c["name"]), value=val, limit=lim, state=state, how=how, gap=gap) + note  # fmt: skip


def print_uncertainty(out: dict[str, Any], _: Language = ENGLISH) -> None:
    """The parameter-tolerance spread, if computed."""
    pu = out.get("parameter_uncertainty")
    if pu is None:
        return
    u = Display.of(out, _)
    t = pu["tolerances"]
    print(_("parameter tolerances (uniform): C +-{c} %, M and J3 +-{m} %, lengths +-{length}, "
            "sensor gains +-{gain} %").format(
        c=u.decimals(f"{t['C_pct']:g}"), m=u.decimals(f"{t['M_pct']:g}"),
        length=u.length(t["length_mm"]),
        gain=u.decimals(f"{t['gain_pct']:g}")))  # fmt: skip
    for p in pu["planes"]:
        top = ", ".join(f"{k} {100 * s:.0f} %" for k, s in p["largest_shares"])
        print("  " + _("plane {plane}: 95 % +-{mc} (Monte Carlo, {draws} draws; linearised "
                       "{linear}); with the measurement +-{combined}; most from {top}").format(
            plane=p["plane"], mc=u.unbalance(p["radius95_monte_carlo_g_mm"]), draws=pu["draws"],
            linear=u.number(p["radius95_linear_g_mm"]), combined=u.number(p["combined_g_mm"]),
            top=top))  # fmt: skip


def print_check(out: dict[str, Any], _: Language = ENGLISH) -> None:
    """Before and after a correction, with the unbalance reduction ratio."""
    c = out.get("check")
    if c is None:
        return
    u = Display.of(out, _)
    print(_("check against the run before the correction ({run}):").format(
        run=c["previous_run"]))  # fmt: skip
    for p in c["planes"]:
        urr = "-" if p["urr"] is None else u.decimals(f"{100 * p['urr']:.1f}") + " %"
        print("  " + _("plane {plane}: {before} -> {after} residual, reduction ratio URR "
                       "{urr}").format(plane=p["plane"], before=u.number(p["before_g_mm"]),
                                       after=u.unbalance(p["after_g_mm"]), urr=urr))  # fmt: skip


def tooling_line(out: dict[str, Any], _: Language = ENGLISH) -> str | None:
    """``tooling mandrel-A subtracted: ...`` when a tooling compensation was used."""
    t = out.get("tooling")
    if t is None:
        return None
    u = Display.of(out, _)
    planes = "; ".join(
        _("plane {plane} {unbalance} at {angle} deg").format(
            plane=p["plane"], unbalance=u.unbalance(p["unbalance_g_mm"]),
            angle=u.decimals(f"{p['angle_deg']:.1f}"))
        for p in t["subtracted"]
    )  # fmt: skip
    return _("tooling {name} subtracted (measured {date}): {planes}").format(
        name=t["name"], date=t["measured"][:10], planes=planes)  # fmt: skip


def print_result(out: dict[str, Any], _: Language = ENGLISH) -> None:
    """The whole result as text (stdout) in the language ``_``; warnings go to stderr."""
    print_measurement(out, _)
    if line := tooling_line(out, _):
        print(line)
    print_corrections(out, _)
    print_uncertainty(out, _)
    if "stopped_by" in out:
        print(_("stopped by: {why} after {seconds} s; recorded in {run}").format(
            why=_(out["stopped_by"]),
            seconds=Display.of(out, _).decimals(f"{out['elapsed_s']:.1f}"),
            run=out["run_file"]))  # fmt: skip
    if line := cycle_sentence(out, _):
        print(line)
    print_check(out, _)
    for w in out["warnings"]:
        print(_("warning: {message}").format(message=_(w)), file=sys.stderr)


def show(out: dict[str, Any], as_json: bool, _: Language = ENGLISH) -> None:
    """Print a result: one strict JSON object (English, whatever ``_``), or the text."""
    if as_json:
        dump_json(out)
    else:
        print_result(out, _)


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
