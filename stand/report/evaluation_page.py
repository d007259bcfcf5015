"""The certificate of the stand's evaluation (``stand evaluate --report/--pdf``): what an
auditor reads of ISO 21940-21's machine tests: the proving rotor, the test masses, the
readings, each test's criterion and verdict.  Formatting only: from the JSON object
:func:`stand.cli.evaluate.to_json` gives."""

from __future__ import annotations

import html
from typing import Any

from stand.report.certificate import CSS

CRITERIA = {
    "u_mar": "ISO 21940-21 U_mar test: test masses of 10 U_mar in both test planes at once, at "
    "12 positions 30° apart, both planes read at each; pass when every amount reading lies "
    "within ±12 % of the mean of the 12. e_mar = 2 U_mar / m (per test plane, half the "
    "rotor's mass).",
    "urr": "ISO 21940-21 URR test: each indication against its known applied test unbalance, "
    "URR = 1 − |indication − applied| / |applied| per loaded plane; pass when every one is "
    "at or above the URR claimed.",
    "cross": "Cross-effect (plane separation, as makers state it): in a run loaded in one "
    "plane only, the change of the other plane's reading in % of its own.",
}
"""Each test's criterion, as the certificate quotes it (source: Bloch & Geitner, Machinery
Component Maintenance and Repair, pp. 309-316, reproducing the standard)."""


def _umar(u: dict[str, Any]) -> str:
    if not u["planes"]:
        return "<p>Not judged.</p>"
    head = "".join(f"<th>{30 * k}°</th>" for k in range(12))
    rows = "".join(
        f"<tr><td>{p['plane']}</td>"
        + "".join(f"<td>{x:.1f}</td>" for x in p["readings_g_mm"])
        + f"<td>{p['mean_g_mm']:.1f}</td><td>{p['spread_pct']:.2f} %</td>"
        f"<td>{'PASS' if p['passed'] else 'FAIL'}</td></tr>"
        for p in u["planes"]
    )
    return (f"<table><tr><th>plane</th>{head}<th>mean</th><th>largest deviation</th>"
            f"<th>verdict</th></tr>{rows}</table>")  # fmt: skip


def _cell(x: float | None, unit: str = "") -> str:
    return "–" if x is None else f"{x:.2f}{unit}"


def _urr(r: dict[str, Any]) -> str:
    rows = "".join(
        f"<tr><td>{html.escape(x['run'])}</td>"
        + "".join(f"<td>{_cell(a)}</td>" for a in x["applied_g_mm"])
        + "".join(f"<td>{_cell(a)}</td>" for a in x["indicated_g_mm"])
        + "".join(f"<td>{_cell(u, ' %')}</td>" for u in x["urr_pct"])
        + "</tr>"
        for x in r["runs"]
    )
    return ("<table><tr><th>run</th><th>applied 1 [g mm]</th><th>applied 2</th>"
            "<th>indicated 1 [g mm]</th><th>indicated 2</th><th>URR 1</th><th>URR 2</th></tr>"
            f"{rows}</table>")  # fmt: skip


def evaluation_page(out: dict[str, Any], mass_kg: float) -> str:
    """The whole HTML page."""
    e = html.escape
    u, r = out["u_mar_test"], out["urr_test"]
    a = out.get("archived") or {}
    when = f"{e(a['performed_at'][:16])} UTC; next due {e(a['due'])}" if a else "not archived"
    sim = " The runs are simulated." if a.get("simulated") else ""
    refused = "".join(f"<li>{e(x['run'])}: {e(x['why'])}</li>" for x in out["refused"])
    why = "".join(f"<li>{e(w)}</li>" for w in out["not_judged_because"])
    badge = {"pass": "pass", "fail": "fail"}.get(out["verdict"], "muted")
    umar = (f"U_mar {u['u_mar_g_mm']:g} g mm per test plane; e_mar {u['e_mar_g_mm_per_kg']:.4g} "
            "g mm/kg" if u["u_mar_g_mm"] is not None else "U_mar: not judged")  # fmt: skip
    ce = out["cross_effect_pct"]
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Balancing machine evaluation</title>
<style>{CSS}</style></head><body>
<header><h1>Balancing machine evaluation (ISO 21940-21)</h1>
<span class="badge {badge}">{e(out["verdict"].upper())}</span></header>
<p><b>Proving rotor:</b> {mass_kg:g} kg. <b>Performed:</b> {when}.{sim}</p>
<h2>U_mar test: {e(u["verdict"].upper())}</h2>
<p>{e(CRITERIA["u_mar"])}</p><p>{e(umar)}; readings [g mm]:</p>{_umar(u)}
<h2>URR test: {e(r["verdict"].upper())}</h2>
<p>{e(CRITERIA["urr"])} Claimed: {r["claim_pct"]:g} %.</p>{_urr(r)}
<h2>Cross-effect</h2>
<p>{e(CRITERIA["cross"])} Plane 1 on plane 2: {_cell(ce[0], " %")}; plane 2 on plane 1:
{_cell(ce[1], " %")}.</p>
{"<h2>Runs left out</h2><ul>" + refused + "</ul>" if refused else ""}
{"<h2>Not judged because</h2><ul>" + why + "</ul>" if why else ""}
<table class=job><tr><th>evaluated by</th><td></td><th>date</th><td></td></tr></table>
</body></html>
"""
