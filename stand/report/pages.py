"""The other pages in the certificate's style: a rotor type's production statistics
(``stand stats --report``) and a correction across speeds (``stand report
--across-speeds``, the station's History).  Formatting only: each page comes from one
JSON object (:func:`stand.archive.stats.production`, :func:`stand.field.speeds.speeds_json`).
"""

from __future__ import annotations

import html
from typing import Any

from stand.report.certificate import CSS
from stand.report.plots import production, speed_bars
from stand.solve.verdict import verdicts_text
from stand.solve.words import counted, first_pass_text


def _p(p: float) -> str:
    """``p = 0.21``, or ``p < 0.0001`` (a p-value is never shown as 0)."""
    return "p < 0.0001" if p < 1e-4 else f"p = {p:.2g}"


def render_production(out: dict[str, Any]) -> str:
    """A rotor type's production statistics (``stand stats --report``) as one HTML page."""

    e = html.escape
    polar_png, trend_png = production(out)
    rows = []
    for key, title in (("plane1", "plane 1"), ("plane2", "plane 2"), ("static", "static part"),
                       ("couple", "couple part")):  # fmt: skip
        s = out[key]
        if "mean" not in s:
            rows.append(
                f"<tr><td class=l>{title}</td><td colspan=5 class=l>{e(s['note'])}</td></tr>"
            )
            continue
        a, b = s["region95_g_mm"]
        verdict = "yes" if s["systematic"] else "no"
        rows.append(
            f"<tr><td class=l>{title}</td><td>{s['mean']['unbalance_g_mm']:.1f}</td>"
            f"<td>{s['mean']['angle_deg']:.1f}°</td><td>± {a:.1f} × {b:.1f}</td>"
            f"<td>{s['spread_rms_g_mm']:.1f}</td><td>{verdict} ({_p(s['p_value'])})</td></tr>"
        )
    fpy = out["first_pass_yield"]
    own = out["stand_interval95_g_mm"]
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Production of {e(out["rotor_type"])}</title>
<style>{CSS}</style></head><body>
<header><h1>Production statistics: {e(out["rotor_type"])}</h1></header>
<p>{counted(out["rotors"], "rotor")} ({counted(out["runs"], "run")}). First-pass yield
<b>{"–" if fpy is None else f"{100 * fpy:.1f} %"}</b>: {e(first_pass_text(out))}.
Verdicts (ISO 21940-14):
{e(verdicts_text(out["verdicts"]))}.</p>
<h2>Initial unbalance (each rotor's first run)</h2>
<table><tr><th class=l>part</th><th>mean [g mm]</th><th>at</th>
<th>95 % region of the mean [g mm]</th><th>spread rms [g mm]</th>
<th>systematic?</th></tr>{"".join(rows)}</table>
<p class=muted>Hotelling's T² on the complex unbalances: a systematic part is a mean that
differs from zero at the 5 % level; its 95 % region is an ellipse (semi-axes given). The
stand's own 95 % interval per run: ± {own[0]:.1f} and ± {own[1]:.1f} g mm.</p>
<img alt="initial unbalances, per part" src="{polar_png}">
<p class=muted>Angles from the reference mark, against the direction of rotation; grey:
the rotors; green: the tolerance; red: the mean and its 95 % region.</p>
<h2>Over time</h2><img alt="initial unbalance over time" src="{trend_png}">
</body></html>
"""


def render_speeds(out: dict[str, Any]) -> str:
    """A correction across speeds (``stand report --across-speeds``, the station's
    History) as one HTML page: the corrections in N planes, and per speed what each
    measuring plane keeps, before and after, against its permissible value."""

    e = html.escape
    planes = "".join(
        f"<tr><td class=l>{p['plane']}</td><td>{p['position_mm']:g}</td><td>{p['radius_mm']:g}</td>"
        f"<td class=l>{p['action']} "
        + (
            " + ".join(f"{w['mass_g']:.2f} g at {w['angle_deg']:.1f}°" for w in p["weights"])
            or "nothing"
        )
        + (" (left out: not independent)" if p["dependent"] else "")
        + (" (at the mass limit)" if p["at_limit"] else "")
        + f"</td><td>{p['unbalance_g_mm']:.1f} ± {p['uncertainty_g_mm']:.1f}</td></tr>"
        for p in out["planes"]
    )
    verdict = {
        True: "<span class=pass>pass</span>",
        False: "<span class=fail>FAIL</span>",
        None: "–",
    }
    rows = []
    for s in out["speeds"]:
        per = s["permissible_g_mm"] or [None, None]
        cells = "".join(
            f"<td>{b['unbalance_g_mm']:.1f}</td><td>{a['unbalance_g_mm']:.1f}</td>"
            f"<td>{'–' if q is None else f'{q:.0f}'}</td>"
            for b, a, q in zip(s["before"], s["after"], per, strict=True)
        )
        rows.append(
            f"<tr><td>{s['rpm']:.0f}</td>{cells}<td>{verdict[s['pass_after']]}</td>"
            f"<td class=l>{e(s['run'])}</td></tr>"
        )
    warnings = "".join(f"<p class=warn>{e(w)}</p>" for w in out["warnings"])
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Correction across speeds</title>
<style>{CSS}</style></head><body>
<header><h1>Correction across speeds</h1>
<span class=badge>{verdict[out["pass"]]}</span></header>
<p>{len(out["planes"])} correction planes, {len(out["speeds"])} speeds
({ {"ls": "least squares", "wls": "weighted least squares", "minmax": "min-max"}[out["method"]] }
of each speed's share of the tolerance).</p>
<h2>Correction</h2>
<table><tr><th class=l>plane</th><th>at [mm from the left end]</th><th>radius [mm]</th>
<th class=l>what to do</th><th>its unbalance, 95 % [g mm]</th></tr>{planes}</table>
<p class=muted>Angles from the reference mark, counted <b>against the direction of
rotation</b>.</p>
<h2>At each speed, predicted after the correction</h2>
<img alt="per speed: each plane before and after" src="{speed_bars(out)}">
<table><tr><th rowspan=2>speed [rpm]</th><th colspan=3>plane 1 [g mm]</th>
<th colspan=3>plane 2 [g mm]</th><th rowspan=2>verdict</th><th class=l rowspan=2>run</th></tr>
<tr><th>before</th><th>after</th><th>permissible</th><th>before</th><th>after</th>
<th>permissible</th></tr>{"".join(rows)}</table>
<p class=muted>Each speed's unbalance in the stand's two measuring planes: what moves the
supports as the bending rotor does at that speed. Grey: before; green (red: over the
tolerance): after, as the beam model predicts; dashed: the permissible value.
Check each speed with a run after the correction.</p>
{warnings}
</body></html>
"""
