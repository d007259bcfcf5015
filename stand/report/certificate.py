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

import datetime as dt
import html
from pathlib import PurePath
from typing import Any

from stand.report.plots import polar, spectrum_and_speed
from stand.report.units import Display
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
img { max-width: 100%; }
pre { font-size: 0.8em; background: #f6f6f6; padding: 0.6em; white-space: pre-wrap; }
.appendix { margin-top: 2em; }
@page { size: A4; margin: 12mm 12mm 14mm 12mm; }
@media print {
  body { margin: 0; max-width: none; font-size: 11px; }
  .appendix { break-before: page; }
  img { max-height: 88mm; }
  h2 { break-after: avoid; } table, .sign { break-inside: avoid; }
}
"""


def local_time(iso_utc: str) -> str:
    """``2026-11-22 15:03 CET`` from an ISO 8601 UTC time (as given if unreadable).

    >>> local_time("")
    ''
    """
    if not iso_utc:
        return ""
    try:
        t = dt.datetime.fromisoformat(iso_utc)
    except ValueError:
        return iso_utc
    return t.astimezone().strftime("%Y-%m-%d %H:%M %Z")


BADGES = {
    "pass": '<span class="badge pass">IN TOLERANCE</span>',
    "fail": '<span class="badge fail">OUT OF TOLERANCE</span>',
    "undecided": '<span class="badge fail">UNDECIDED: measure longer</span>',
    "none": '<span class="badge muted">no tolerance set</span>',
}
"""The one verdict (:mod:`stand.solve.verdict`) as the certificate's badge."""


def _badge(out: dict[str, Any]) -> str:
    return BADGES[out.get("verdict", "none")]


def _job(out: dict[str, Any], result: Result) -> str:
    e, j, st = html.escape, out["job"], out["stand"]
    cells = [
        ("rotor type", j.get("rotor_type")), ("serial number", j.get("serial")),
        ("order", j.get("order")), ("operator", j.get("operator")),
        ("balancing stand", st.get("name") or st.get("id")),
        ("date", local_time(result.provenance.start_time)),
    ]  # fmt: skip
    row = "".join(f"<th>{k}</th><td>{e(v or '–')}</td>" for k, v in cells[:3])
    row2 = "".join(f"<th>{k}</th><td>{e(v or '–')}</td>" for k, v in cells[3:])
    note = f"<tr><th>note</th><td colspan=5>{e(j['note'])}</td></tr>" if j.get("note") else ""
    return f"<table class=job><tr>{row}</tr><tr>{row2}</tr>{note}</table>"


def _basis(out: dict[str, Any]) -> str:
    t, d, e = out.get("tolerance"), Display.of(out), html.escape
    if t is None:
        return "<p><b>Tolerance:</b> none set (the configuration has no [tolerance] table).</p>"
    per = ""
    if "permissible_g_mm" in t:
        per = f": U<sub>per</sub> = {d.unbalance(t['permissible_g_mm'])}"
    rows = "".join(
        f"<tr><td>{e(c['name'])}</td><td>{e(_value(c, d))}</td><td>{e(_limit(c, d))}</td>"
        f"<td><span class={'pass' if c['verdict'] == 'pass' else 'fail'}>"
        f"{c['verdict'].upper()}</span></td></tr>"
        for c in t["criteria"]
    )
    return (
        f"<p><b>Tolerance:</b> {e(t['source'])}{per}; judged in {e(t['judged_in'])}. "
        f"Balancing speed {out['rpm']:.0f} rpm.<br><b>Rule:</b> {e(t['rule'])}.</p>"
        + (  # planes judged alone show in the table of planes below
            f"<table><tr><th>criterion</th><th>value &plusmn; combined error</th>"
            f"<th>permissible</th><th>verdict</th></tr>{rows}</table>"
            if any(c["plane"] is None for c in t["criteria"])
            else ""
        )
        + _keys(out)
    )


def _keys(out: dict[str, Any]) -> str:
    """The keys' convention and the part's marking (ISO 21940-32)."""
    keys = out.get("keys") or []
    if not keys:
        return ""
    d, e = Display.of(out), html.escape
    items = "".join(
        f"<li>keyway at {k['angle_deg']:g}°, key {d.mass(k['mass_g'])} at radius "
        f"{d.length(k['radius_mm'])}: balanced with {CONVENTION_WORDS[k['convention']]} "
        f"({FITTED_WORDS[k['fitted']]} fitted on the stand, the difference counted); "
        f"<b>mark the part {e(k['marking'])}</b></li>"
        for k in keys
    )
    return f"<p><b>Keys (ISO 21940-32):</b></p><ul>{items}</ul>"


def _value(c: dict[str, Any], d: Display) -> str:
    if "value_g_mm2" in c:
        return f"{d.number(c['value_g_mm2'])} ± {d.number(c['error_g_mm2'])} g mm²"
    return f"{d.unbalance(c['value_g_mm'])} ± {d.number(c['error_g_mm'])}"


def _limit(c: dict[str, Any], d: Display) -> str:
    if "permissible_g_mm2" in c:
        return f"{d.number(c['permissible_g_mm2'])} g mm²"
    return d.unbalance(c["permissible_g_mm"])


def _results(out: dict[str, Any]) -> str:
    d, e = Display.of(out), html.escape
    crit = out.get("tolerance", {}).get("criteria", [])
    tol = {c["plane"]: c for c in crit if c["plane"] is not None}
    check = {p["plane"]: p for p in out.get("check", {}).get("planes", [])}
    u = d.unbalance_unit
    head = (
        f"<th>before [{u}]</th><th>after [{u}] (95 %)</th><th>URR</th>"
        if check
        else f"<th>unbalance [{u}] (95 %)</th>"
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
        angle = f"{plane['angle_deg']:.1f}°"
        state = tol[i]["verdict"] if i in tol else None
        verdict = (
            "–" if state is None
            else f'<span class="{"pass" if state == "pass" else "fail"}">{state.upper()}</span>'
        )  # fmt: skip
        per = d.number(tol[i]["permissible_g_mm"]) if i in tol else "–"
        rows.append(f"<tr><td>{i}</td>{cells}<td>{angle}</td><td>{per}</td><td>{verdict}</td></tr>")
    prev = (
        f"<p class=muted>Before: the run {e(_file_name(out['check']['previous_run']))}, "
        "before the correction; after: this run.</p>"
        if check
        else ""
    )
    return (
        f"<table><tr><th>plane</th>{head}<th>angle</th><th>permissible [{u}]</th>"
        f"<th>verdict</th></tr>{''.join(rows)}</table>{prev}"
    )


def _machined(plane: dict[str, Any], c: dict[str, Any], d: Display) -> str:
    """A drilled or milled plane: the cuts in drilling order, then what they leave."""
    e = html.escape
    cuts = [d.hole(h) for h in plane.get("holes") or []]
    if plane.get("slot"):
        cuts.append(d.slot(plane["slot"]))
    judged = c.get("residual_within_tolerance")
    verdict = "" if judged is None else " (within tolerance)" if judged else " (OVER tolerance)"
    return (
        f"plane {plane['plane']}: <b>{e(d.cuts(plane))}</b>, removing "
        f"{e(d.mass(plane['removed_g']))}; leaves {e(d.unbalance(plane['leftover_g_mm']))}"
        f"{verdict}<ul class=cuts>" + "".join(f"<li>{e(x)}</li>" for x in cuts) + "</ul>"
    )


def _corrections(out: dict[str, Any]) -> str:
    d, e = Display.of(out), html.escape
    items = []
    for plane, c in zip(out["planes"], out["corrections"], strict=True):
        i = plane["plane"]
        if c.get("within_noise"):
            items.append(
                f"plane {i}: no correction needed: the unbalance is inside its own 95 % interval"
            )
            continue
        if c.get("within_tolerance"):
            items.append(f"plane {i}: within tolerance: no correction needed")
            continue
        if "holes" in plane:
            items.append(_machined(plane, c, d))
            continue
        what = " + ".join(
            f"{d.mass(w['mass_g'])}"
            + (
                f" ({' + '.join(d.mass(x) for x in w['pieces_g'])})"
                if len(w["pieces_g"]) > 1
                else ""
            )
            + f" at {w['angle_deg']:.1f}°"
            + ("" if w["position"] is None else f" (position {w['position']})")
            for w in c["weights"]
        )
        left = ""
        if c["residual_g_mm"] > 0.05:
            judged = c.get("residual_within_tolerance")
            left = f"; the weight rounding leaves {d.unbalance(c['residual_g_mm'])}" + (
                "" if judged is None else " (within tolerance)" if judged else " (OVER tolerance)"
            )
        items.append(
            f"plane {i}: <b>{e(c['action'])} {e(what)}</b> at radius "
            f"{d.length(plane['radius_mm'])}{left}"
        )
    return "<ul>" + "".join(f"<li>{x}</li>" for x in items) + "</ul>"


def _calibration(out: dict[str, Any], result: Result) -> str:
    p, e = result.provenance, html.escape
    when = out["stand"].get("calibrated")
    cal = f"calibrated on {e(when)}" if when else "design values (no calibration date)"
    matrix = f"; influence matrix {e(p.matrix)}" if p.matrix else ""
    t = out.get("tooling")
    if t:
        d = Display.of(out)
        parts = ", ".join(
            f"plane {x['plane']} {d.unbalance(x['unbalance_g_mm'])} at {x['angle_deg']:.1f}°"
            for x in t["subtracted"]
        )
        matrix += (
            f". <b>Tooling compensation:</b> {e(t['name'])}, measured {e(t['measured'][:10])} "
            f"by the two-run index procedure; its unbalance ({e(parts)}) is subtracted"
        )
    return (
        f"<p><b>Calibration used:</b> {e(_config_named(p.config_source))} (SHA-256 "
        f"{p.config_sha256[:16]}…, the stand's archive keeps it whole), {cal}{matrix}. "
        f"Measured with {e(p.software)}.</p>"
    )


def _file_name(path: str | None) -> str:
    """A file as a customer's paper names it: its name, never the stand's folders."""
    return PurePath(path).name if path else "–"


def _config_named(source: str | None) -> str:
    """The configuration a run was solved with, as the certificate names it."""
    if not source or source == "the stand's configuration":
        return "the stand's configuration"
    if source in ("scene", "stored") or source.endswith("(stored)"):
        return "the configuration stored with the run"
    return f"the configuration {_file_name(source)}"


RELEASE_START, RELEASE_END = "<!--release-->", "<!--/release-->"
"""Around the signature block: :func:`stand.report.release.released` puts a release in
its place."""


def _signatures(out: dict[str, Any]) -> str:
    op = html.escape(out["job"].get("operator") or "")
    return (
        f"{RELEASE_START}<div class=sign>"
        f"<div>balanced by {op}</div><div>date</div>"
        "<div>inspected by</div><div>date</div>"
        f"</div>{RELEASE_END}"
    )


def _uncertainty(out: dict[str, Any]) -> str:
    pu = out.get("parameter_uncertainty")
    if pu is None:
        return ""
    t = pu["tolerances"]
    d = Display.of(out)
    rows = "".join(
        f"<tr><td>{p['plane']}</td><td>±{d.number(p['radius95_monte_carlo_g_mm'])}</td>"
        f"<td>±{d.number(p['radius95_linear_g_mm'])}</td>"
        f"<td>±{d.number(p['combined_g_mm'])}</td>"
        f"<td class=l>{', '.join(f'{k} {100 * s:.0f} %' for k, s in p['largest_shares'])}</td></tr>"
        for p in pu["planes"]
    )
    return (
        f"<h2>Parameter tolerances</h2><p class=muted>Uniform within C ±{t['C_pct']:g} %, "
        f"M and J3 ±{t['M_pct']:g} %, lengths ±{d.length(t['length_mm'])}, sensor gains "
        f"±{t['gain_pct']:g} %; {pu['draws']} Monte Carlo draws.</p>"
        f"<table><tr><th>plane</th><th>95 % [{d.unbalance_unit}], Monte Carlo</th>"
        "<th>linearised</th>"
        "<th>with the measurement</th><th class=l>largest shares</th></tr>"
        f"{rows}</table>"
    )


def _appendix(out: dict[str, Any], result: Result) -> str:
    e = html.escape
    supports = "".join(
        f"<tr><td>{s['node']}</td><td>{s['amplitude_m_s2']:.4f} ± {s['uncertainty_m_s2']:.4f}</td>"
        f"<td>{s['phase_deg']:.2f}°</td><td>{s['revolutions']:.0f}</td>"
        f"<td>{s['noise_m_s2']:.4f}</td></tr>"
        for s in out["supports"]
    )
    warnings = (
        "".join(f'<div class="warn">{e(w)}</div>' for w in out["warnings"])
        or "<p class=muted>none</p>"
    )
    spectrum, speed = spectrum_and_speed(result.traces, out["rpm"])
    p = result.provenance
    meta = {
        "run file": _file_name(p.run_file), "start time (UTC)": p.start_time,
        "frames": p.frames, "duration [s]": round(p.duration_s, 3),
        **_parameters(out),
    }  # fmt: skip
    rows = "".join(
        f"<tr><th class=l>{e(str(k))}</th><td class=l>{e(str(v))}</td></tr>"
        for k, v in meta.items()
    )
    return f"""<div class=appendix>
<h2>Measurement</h2>
<table><tr><th>support</th><th>1x amplitude [m/s²] (95 %)</th><th>phase</th><th>revolutions</th>
<th>noise at 1x [m/s²]</th></tr>{supports}</table>
{_uncertainty(out)}
<h2>Spectrum around 1x</h2><img alt="spectrum" src="{spectrum}">
<h2>Speed over the run</h2><img alt="speed" src="{speed}">
<h2>Warnings</h2>{warnings}
<h2>Run and parameters</h2><table>{rows}</table>
<p class=muted>The whole configuration is kept in the stand's archive under its SHA-256
({e(p.config_sha256[:16])}…).</p>
</div>"""


def _parameters(out: dict[str, Any]) -> dict[str, str]:
    """The few parameters a customer needs (the rest stays in the archive)."""
    d = Display.of(out)
    got = {"speed [rpm]": f"{out['rpm']:.0f}"}
    for x in out.get("planes", []):
        if x.get("radius_mm") is not None:
            got[f"plane {x['plane']}: correction radius"] = d.length(x["radius_mm"])
    t = out.get("tolerance") or {}
    if t.get("source"):
        got["tolerance"] = str(t["source"])
    return got


def render(result: Result) -> str:
    """The certificate of a result as one HTML document (figures embedded)."""
    out = to_json(result)
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Balancing certificate</title>
<style>{CSS}</style></head><body>
<header><h1>Balancing certificate</h1>{_badge(out)}</header>
{_job(out, result)}
{_basis(out)}
<h2>Unbalance per correction plane</h2>
{_results(out)}
<p class=muted>Angles from the reference mark, counted
<b>against the direction of rotation</b>. Material is removed, or weights added, at the
angles given.</p>
<h2>Correction</h2>
{_corrections(out)}
<img alt="each plane: tolerance, unbalance, correction" src="{polar(out)}">
<p class=muted>▼ the reference mark; the arrow: the direction of rotation; angles are counted
against it from the mark; 1..N: the holes (positions) when the correction uses them.</p>
{_calibration(out, result)}
{_signatures(out)}
{_appendix(out, result)}
</body></html>
"""
