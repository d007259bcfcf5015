"""The page of a run-up or coast-down (``stand runup RUN --report PAGE.html``): the modes
found against the model's with the balancing speed's margins, each support's peaks and its
2x, what the run could not carry, and the Bode, polar and waterfall plots.  Formatting
only: the figures come from the JSON object :func:`stand.cli.runup.as_json` gives, the
plots from the same analysis (:mod:`stand.report.runup_plot`)."""

from __future__ import annotations

import html
from typing import Any

from stand.report.certificate import CSS
from stand.report.plots import png


def _num(x: float | None, fmt: str) -> str:
    return "–" if x is None else format(x, fmt)


def _modes(out: dict[str, Any]) -> str:
    rows = "".join(
        f"<tr><td>{k}</td><td>{m['rpm']:.1f}</td><td>{m['zeta']:.4f}</td>"
        f"<td>{m['amplification_factor']:.1f}</td><td>{_num(m['model_rpm'], '.1f')}</td>"
        f"<td>{_num(m['model_zeta'], '.4f')}</td><td>{m['margin_pct']:.1f} %</td>"
        f"<td>{m['required_pct']:.1f} %</td><td>{_num(m['steady_reading_rpm'], '.1f')}</td></tr>"
        for k, m in enumerate(out["modes"], 1)
    )
    if not rows:
        return "<p><b>No modal fit</b>: the resonances are the supports' peaks only.</p>"
    return (
        "<table><tr><th>mode</th><th>found [rpm]</th><th>damping ratio</th>"
        "<th>amplification factor</th><th>model [rpm]</th><th>model's damping</th>"
        "<th>margin</th><th>API 684 asks</th><th>read as steady [rpm]</th></tr>"
        f"{rows}</table>"
    )


def _supports(out: dict[str, Any]) -> str:
    rows = []
    for s in out["supports"]:
        peaks = (
            "<br>".join(
                f"{p['rpm']:.1f} rpm, damping {p['zeta_half_power']:.4f} (half-power), "
                f"{_num(p['zeta_circle_fit'], '.4f')} (circle fit), "
                f"AF {p['amplification_factor']:.1f}"
                for p in s["peaks"]
            )
            or "none with its whole half-power band in the run"
        )
        x = s["x2"]
        at = (
            "not reached in the run"
            if x["at_balancing_m_s2"] is None
            else f"{x['at_balancing_m_s2']:.4f} ± {x['at_balancing_radius95_m_s2']:.4f} m/s² "
            f"at {x['at_balancing_phase_deg']:.1f}° ({x['share_of_1x_at_balancing_pct']:.1f} % "
            "of the 1x)"
        )
        rows.append(
            f"<tr><td>{s['support']}</td><td>{s['points']}</td><td class=l>{peaks}</td>"
            f"<td class=l>{at}; at most {x['peak_m_s2']:.4f} ± {x['peak_radius95_m_s2']:.4f} "
            f"m/s² at {x['peak_rpm']:.0f} rpm</td></tr>"
        )
    return (
        "<table><tr><th>support</th><th>points</th><th>its peaks</th>"
        f"<th>2x at the balancing speed; its largest</th></tr>{''.join(rows)}</table>"
    )


def render_runup(out: dict[str, Any], analysis: Any, run: str) -> str:
    """A run-up's analysis as one self-contained HTML page (the plots inline)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stand.report.runup_plot import DRAWINGS

    e = html.escape
    pictures = "".join(
        f'<h2>{e(title)}</h2><img alt="{e(title)}" src="{png(draw(plt, analysis))}">'
        for _, title, draw in DRAWINGS
    )
    lo, hi = out["range_rpm"]
    first, last = (hi, lo) if out["direction"] == "coast-down" else (lo, hi)
    warnings = "".join(f"<li>{e(w)}</li>" for w in out["warnings"])
    said = f"<h2>Said</h2><ul>{warnings}</ul>" if warnings else ""
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{e(out["direction"])}: {e(run)}</title>
<style>{CSS}</style></head><body>
<header><h1>The stand's response: a {e(out["direction"])}</h1></header>
<p>{e(run)}: from {first:.0f} to {last:.0f} rpm at {out["sweep_rpm_per_s"]:.1f} rpm/s, a point
every {out["revolutions_per_point"]} revolution(s); balancing speed
<b>{out["balancing_rpm"]:.0f} rpm</b>. The modes are fitted as the sweep gives them (the
reading as steady states beside them is biased by the sweep); the margin is the balancing
speed's distance from each, against what API 684 asks at its amplification factor.</p>
<h2>Modes</h2>{_modes(out)}
<h2>Supports</h2>{_supports(out)}
{said}
{pictures}
</body></html>
"""
