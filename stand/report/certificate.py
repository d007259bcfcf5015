"""The balancing certificate: one self-contained HTML document, figures embedded.

Page 1 is what a customer accepts: the job (rotor type, serial, order,
operator, stand, date in local time), the tolerance basis, per plane the
unbalance before and after (with the URR when the run checks a correction)
against its permissible share, the correction still to make and what the
weight rounding leaves, the calibration used, and signature fields.  Page 2
is the measurement behind it: the supports, the spectrum and speed, the
warnings and the configuration.  A print layout (A4) goes with it, and
:mod:`stand.report.printing` turns it into a PDF.  Formatting only: everything
comes from the run's :class:`~stand.solve.result.Result`.
"""

from __future__ import annotations

import html
from typing import Any

from stand.i18n.display import Display
from stand.i18n.language import ENGLISH, N_, Language
from stand.report.appendix import appendix, file_name
from stand.report.plots import polar
from stand.report.units import ACTIONS, cycle_sentence, verdict_word
from stand.solve import Result, to_json
from stand.solve.keys import CONVENTION_WORDS, FITTED_WORDS

CSS = """
body { font-family: "DejaVu Sans", system-ui, sans-serif; margin: 2em auto; max-width: 960px;
       color: #222; font-size: 14px; }
h1 { font-size: 1.6em; margin: 0; } h2 { font-size: 1.1em; margin: 1.2em 0 0.3em; }
header { display: flex; justify-content: space-between; align-items: center;
         border-bottom: 2px solid #222; padding-bottom: 0.4em; }
table { border-collapse: collapse; margin: 0.4em 0; width: 100%; }
td, th { border: 1px solid #bbb; padding: 4px 8px; text-align: right; }
th { background: #eee; } td.l, th.l { text-align: left; }
table.job td, table.job th { text-align: left; }
.pass { background: #1b7f3a; color: white; padding: 2px 10px; border-radius: 4px; }
.fail { background: #b3261e; color: white; padding: 2px 10px; border-radius: 4px; }
.badge { font-size: 1.3em; font-weight: bold; }
.muted { color: #555; font-size: 0.9em; }
.warn { background: #fff4ce; border-left: 4px solid #e0a800; padding: 4px 10px; margin: 4px 0; }
.sign { display: grid; grid-template-columns: 1fr 1fr; gap: 1.2em 3em; margin-top: 1.5em; }
.sign div { border-top: 1px solid #222; padding-top: 3px; font-size: 0.9em; }
.digest { font-family: monospace; font-size: 0.8em; word-break: break-all; }
.released td { text-align: left; }
.unreleased { font-weight: bold; letter-spacing: 0.1em; text-transform: uppercase; }
img { max-width: 100%; }
pre { font-size: 0.8em; background: #f6f6f6; padding: 0.6em; white-space: pre-wrap; }
.appendix { margin-top: 2em; }
@page { size: A4; margin: 12mm 12mm 14mm 12mm; }
@media print {
  body { margin: 0; max-width: none; font-size: 11px; }
  .appendix { break-before: page; }
  img { max-height: 88mm; } .appendix img { max-height: 76mm; }
  .appendix img.speed { max-height: 52mm; }
  h2 { break-after: avoid; } table, .sign, .keep { break-inside: avoid; }
}
"""


BADGES = {
    "pass": ("pass", N_("IN TOLERANCE")),
    "fail": ("fail", N_("OUT OF TOLERANCE")),
    "undecided": ("fail", N_("UNDECIDED: measure longer")),
    "none": ("muted", N_("no tolerance set")),
}
"""The one verdict (:mod:`stand.solve.verdict`) as the certificate's badge: its style and
its words."""


def _badge(out: dict[str, Any], _: Language) -> str:
    style, text = BADGES[out.get("verdict", "none")]
    return f'<span class="badge {style}">{html.escape(_(text))}</span>'


def _verdict_word(state: str, _: Language) -> str:
    return html.escape(verdict_word(state, _))


def _job(out: dict[str, Any], result: Result, _: Language) -> str:
    e, j, st = html.escape, out["job"], out["stand"]
    cells = [
        (_("rotor type"), j.get("rotor_type")), (_("serial number"), j.get("serial")),
        (_("order"), j.get("order")), (_("operator"), j.get("operator")),
        (_("balancing stand"), st.get("name") or st.get("id")),
        (_("date"), _.when(result.provenance.start_time)),
    ]  # fmt: skip
    row = "".join(f"<th>{e(k)}</th><td>{e(v or '–')}</td>" for k, v in cells[:3])
    row2 = "".join(f"<th>{e(k)}</th><td>{e(v or '–')}</td>" for k, v in cells[3:])
    note = (f"<tr><th>{e(_('note'))}</th><td colspan=5>{e(j['note'])}</td></tr>"
            if j.get("note") else "")  # fmt: skip
    return f"<table class=job><tr>{row}</tr><tr>{row2}</tr>{note}</table>"


def _basis(out: dict[str, Any], _: Language) -> str:
    t, d, e = out.get("tolerance"), Display.of(out, _), html.escape
    if t is None:
        return "<p>" + e(_("Tolerance: none set (the configuration has no [tolerance] "
                           "table).")) + "</p>"  # fmt: skip
    per = ""
    if "permissible_g_mm" in t:
        per = f": U<sub>per</sub> = {d.unbalance(t['permissible_g_mm'])}"
    rows = "".join(
        f"<tr><td>{e(_(c['name']))}</td><td>{e(_value(c, d))}</td><td>{e(_limit(c, d))}</td>"
        f"<td><span class={'pass' if c['verdict'] == 'pass' else 'fail'}>"
        f"{_verdict_word(c['verdict'], _)}</span></td></tr>"
        for c in t["criteria"]
    )
    heads = "".join(
        f"<th>{e(h)}</th>"
        for h in (_("criterion"), _("value ± combined error"), _("permissible"), _("verdict"))
    )
    return (
        f"<p><b>{e(_('Tolerance:'))}</b> {e(_(t['source']))}{per}; "
        + e(_("judged in {where}. Balancing speed {rpm} rpm.").format(
            where=_(t["judged_in"]), rpm=_.number(out["rpm"], 0)))
        + (f"<br><b>{e(_('Allocation:'))}</b> {e(_(t['allocation']))}."
           if t.get("allocation") else "")
        + f"<br><b>{e(_('Rule:'))}</b> {e(_(t['rule']))}.</p>"
        + (  # planes judged alone show in the table of planes below
            f"<table><tr>{heads}</tr>{rows}</table>"
            if any(c["plane"] is None for c in t["criteria"])
            else ""
        )
        + _keys(out, _)
    )  # fmt: skip


def _keys(out: dict[str, Any], _: Language) -> str:
    """The keys' convention and the part's marking (ISO 21940-32)."""
    keys = out.get("keys") or []
    if not keys:
        return ""
    d, e = Display.of(out, _), html.escape
    items = "".join(
        "<li>" + e(_("keyway at {angle}°, key {mass} at radius {radius}: balanced with "
                     "{convention} ({fitted} fitted on the stand, the difference counted); "
                     ).format(angle=f"{k['angle_deg']:g}", mass=d.mass(k["mass_g"]),
                              radius=d.length(k["radius_mm"]),
                              convention=_(CONVENTION_WORDS[k["convention"]]),
                              fitted=_(FITTED_WORDS[k["fitted"]])))
        + f"<b>{e(_('mark the part {marking}').format(marking=k['marking']))}</b></li>"
        for k in keys
    )  # fmt: skip
    return f"<p><b>{e(_('Keys (ISO 21940-32):'))}</b></p><ul>{items}</ul>"


def _value(c: dict[str, Any], d: Display) -> str:
    if "value_g_mm2" in c:
        return f"{d.number(c['value_g_mm2'])} ± {d.number(c['error_g_mm2'])} g mm²"
    return f"{d.unbalance(c['value_g_mm'])} ± {d.number(c['error_g_mm'])}"


def _limit(c: dict[str, Any], d: Display) -> str:
    if "permissible_g_mm2" in c:
        return f"{d.number(c['permissible_g_mm2'])} g mm²"
    return d.unbalance(c["permissible_g_mm"])


def _results(out: dict[str, Any], _: Language) -> str:
    d, e = Display.of(out, _), html.escape
    crit = out.get("tolerance", {}).get("criteria", [])
    tol = {c["plane"]: c for c in crit if c["plane"] is not None}
    check = {p["plane"]: p for p in out.get("check", {}).get("planes", [])}
    u = d.unbalance_unit
    head = (
        f"<th>{e(_('before [{unit}]').format(unit=u))}</th>"
        f"<th>{e(_('after [{unit}] (95 %)').format(unit=u))}</th><th>URR</th>"
        if check
        else f"<th>{e(_('unbalance [{unit}] (95 %)').format(unit=u))}</th>"
    )
    rows = []
    for plane in out["planes"]:
        i = plane["plane"]
        now = f"{d.number(plane['unbalance_g_mm'])} ± {d.number(plane['uncertainty_g_mm'])}"
        cells = (
            f"<td>{d.number(check[i]['before_g_mm'])}</td><td>{now}</td>"
            f"<td>{100 * check[i]['urr']:.1f} %</td>"
            if i in check and check[i]["urr"] is not None
            else f"<td>{now}</td>"
        )
        angle = "–" if plane.get("within_noise") else f"{plane['angle_deg']:.1f}°"
        state = tol[i]["verdict"] if i in tol else None
        verdict = (
            "–" if state is None
            else f'<span class="{"pass" if state == "pass" else "fail"}">'
            f"{_verdict_word(state, _)}</span>"
        )  # fmt: skip
        per = d.number(tol[i]["permissible_g_mm"]) if i in tol else "–"
        rows.append(f"<tr><td>{i}</td>{cells}<td>{angle}</td><td>{per}</td><td>{verdict}</td></tr>")
    prev = (
        "<p class=muted>" + e(_("Before: the run {run}, before the correction; after: this "
                                "run.").format(run=file_name(out["check"]["previous_run"])))
        + "</p>"
        if check
        else ""
    )  # fmt: skip
    heads = (f"<th>{e(_('plane'))}</th>{head}<th>{e(_('angle'))}</th>"
             f"<th>{e(_('permissible [{unit}]').format(unit=u))}</th>"
             f"<th>{e(_('verdict'))}</th>")  # fmt: skip
    return f"<table><tr>{heads}</tr>{''.join(rows)}</table>{prev}"


def _judged(judged: bool | None, _: Language) -> str:
    return "" if judged is None else _(" (within tolerance)") if judged else _(" (OVER tolerance)")


def _machined(plane: dict[str, Any], c: dict[str, Any], d: Display, _: Language) -> str:
    """A drilled or milled plane: the cuts in drilling order, then what they leave."""
    e = html.escape
    cuts = [d.hole(h, _) for h in plane.get("holes") or []]
    if plane.get("slot"):
        cuts.append(d.slot(plane["slot"], _))
    verdict = _judged(c.get("residual_within_tolerance"), _)
    return (
        e(_("plane {i}: ").format(i=plane["plane"])) + f"<b>{e(d.cuts(plane, _))}</b>"
        + e(_(", removing {mass}; leaves {left}").format(
            mass=d.mass(plane["removed_g"]), left=d.unbalance(plane["leftover_g_mm"])))
        + f"{e(verdict)}<ul class=cuts>" + "".join(f"<li>{e(x)}</li>" for x in cuts) + "</ul>"
    )  # fmt: skip


def _corrections(out: dict[str, Any], _: Language) -> str:
    d, e = Display.of(out, _), html.escape
    items = []
    for plane, c in zip(out["planes"], out["corrections"], strict=True):
        i = plane["plane"]
        if c.get("within_noise"):
            items.append(e(_("plane {i}: no correction needed: the unbalance is inside its own "
                             "95 % interval").format(i=i)))  # fmt: skip
            continue
        if c.get("within_tolerance"):
            items.append(e(_("plane {i}: within tolerance: no correction needed").format(i=i)))
            continue
        if "holes" in plane:
            items.append(_machined(plane, c, d, _))
            continue
        what = " + ".join(
            f"{d.mass(w['mass_g'])}"
            + (
                f" ({' + '.join(d.mass(x) for x in w['pieces_g'])})"
                if len(w["pieces_g"]) > 1
                else ""
            )
            + _(" at {angle}°").format(angle=f"{w['angle_deg']:.1f}")
            + ("" if w["position"] is None else _(" (position {n})").format(n=w["position"]))
            for w in c["weights"]
        )
        left = ""
        if c["residual_g_mm"] > 0.05:
            left = _("; the weight rounding leaves {left}").format(
                left=d.unbalance(c["residual_g_mm"])) + _judged(
                c.get("residual_within_tolerance"), _)  # fmt: skip
        items.append(
            e(_("plane {i}: ").format(i=i)) + f"<b>{e(_(ACTIONS.get(c['action'], c['action'])))} "
            f"{e(what)}</b>" + e(_(" at radius {radius}").format(
                radius=d.length(plane["radius_mm"])) + left)
        )  # fmt: skip
    return "<ul>" + "".join(f"<li>{x}</li>" for x in items) + "</ul>"


def _calibration(out: dict[str, Any], result: Result, _: Language) -> str:
    p, e = result.provenance, html.escape
    when = out["stand"].get("calibrated")
    cal = (_("calibrated on {date}").format(date=when) if when
           else _("design values (no calibration date)"))  # fmt: skip
    matrix = e(_("; influence matrix {matrix}").format(matrix=p.matrix)) if p.matrix else ""
    t = out.get("tooling")
    if t:
        d = Display.of(out, _)
        parts = ", ".join(
            _("plane {i} {unbalance} at {angle}°").format(
                i=x["plane"], unbalance=d.unbalance(x["unbalance_g_mm"]),
                angle=f"{x['angle_deg']:.1f}")
            for x in t["subtracted"]
        )  # fmt: skip
        matrix += (
            f". <b>{e(_('Tooling compensation:'))}</b> " + e(_(
                "{name}, measured {date} by the two-run index procedure; its unbalance "
                "({parts}) is subtracted").format(name=t["name"], date=t["measured"][:10],
                                                   parts=parts))
        )  # fmt: skip
    return (
        f"<p><b>{e(_('Calibration used:'))}</b> " + e(_(
            "{config} (SHA-256 {digest}…, the stand's archive keeps it whole), {calibration}"
        ).format(config=_config_named(p.config_source, _), digest=p.config_sha256[:16],
                 calibration=cal)) + matrix + ". "
        + e(_("Measured with {software}.").format(software=p.software)) + "</p>"
    )  # fmt: skip


def _config_named(source: str | None, _: Language = ENGLISH) -> str:
    """The configuration a run was solved with, as the certificate names it."""
    if not source or source == "the stand's configuration":
        return _("the stand's configuration")
    if source in ("scene", "stored") or source.endswith("(stored)"):
        return _("the configuration stored with the run")
    return _("the configuration {name}").format(name=file_name(source))


RELEASE_START, RELEASE_END = "<!--release-->", "<!--/release-->"
"""Around the signature block: :func:`stand.report.release.released` puts a release in
its place."""


def _signatures(out: dict[str, Any], _: Language) -> str:
    e = html.escape
    op = out["job"].get("operator") or ""
    return (
        f"{RELEASE_START}<p class=unreleased>{e(_('not released'))}</p><div class=sign>"
        f"<div>{e(_('balanced by {operator}').format(operator=op))}</div><div>{e(_('date'))}</div>"
        f"<div>{e(_('inspected by'))}</div><div>{e(_('date'))}</div>"
        f"</div>{RELEASE_END}"
    )


def _cycle(out: dict[str, Any], _: Language) -> str:
    """The stand's own cycle, when a drive ran it: each phase's time and each stop."""
    text = cycle_sentence(out, _)
    return f"<p class=muted>{html.escape(text)}</p>" if text else ""


def render(result: Result, words: Language = ENGLISH) -> str:
    """The certificate of a result as one HTML document (figures embedded), in the
    language ``words`` (the customer's)."""
    out, _, e = to_json(result), words, html.escape
    title = e(_("Balancing certificate"))
    return f"""<!doctype html>
<html lang="{_.code}"><head><meta charset="utf-8"><title>{title}</title>
<style>{CSS}</style></head><body>
<header><h1>{title}</h1>{_badge(out, _)}</header>
{_job(out, result, _)}
{_basis(out, _)}
<h2>{e(_("Unbalance per correction plane"))}</h2>
{_results(out, _)}
<p class=muted>{
        e(
            _(
                "Angles from the reference mark, counted against the direction of "
                "rotation. Material is removed, or weights added, at the angles given."
            )
        )
    }</p>
<h2>{e(_("Correction"))}</h2>
{_corrections(out, _)}
<img alt="{e(_("each plane: tolerance, unbalance, correction"))}" src="{polar(out, _)}">
<p class=muted>{
        e(
            _(
                "▼ the reference mark; the arrow: the direction of rotation; angles are "
                "counted against it from the mark; 1..N: the holes (positions) when the "
                "correction uses them."
            )
        )
    }</p>
{_cycle(out, _)}
{_calibration(out, result, _)}
{_signatures(out, _)}
{appendix(out, result, _)}
</body></html>
"""
