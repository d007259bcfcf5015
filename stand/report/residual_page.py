"""The certificate of a rotor's residual-unbalance check (``stand residual --report``): per
plane the polar plot of the readings with the fitted circle, its centre (the residual) and
the permissible circle, the readings, the verdict and its rule.  Formatting only: the page
comes from the JSON object :func:`stand.cli.residual.to_json` gives."""

from __future__ import annotations

import html
import math
from typing import Any

from stand.report.certificate import CSS
from stand.report.plots import png

RULE = ("API 610/617/687 annex B: a trial mass at 6 or 12 equally spaced positions, one run "
        "each; the readings lie on a circle whose centre is the residual unbalance, scaled by "
        "the trial's known effect over the circle's radius. Judged by "
        "ISO 21940-14 directly after balancing: pass if residual + its 95 % radius <= "
        "permissible, fail if residual - it > permissible, else undecided.")  # fmt: skip


def _polar(planes: list[dict[str, Any]]) -> str:
    """The readings, the fitted circle and its centre, and the permissible, per plane."""
    import matplotlib.pyplot as plt
    import numpy as np

    fig, axes = plt.subplots(1, len(planes), subplot_kw={"projection": "polar"},
                             figsize=(4.8 * len(planes), 4.8), squeeze=False)  # fmt: skip
    ring = np.linspace(0, 2 * math.pi, 361)
    for ax, p in zip(axes[0], planes, strict=True):
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)  # angles against the direction of rotation
        z = np.array([complex(r["re_g_mm"], r["im_g_mm"]) for r in p["readings"]
                      if r["re_g_mm"] is not None])  # fmt: skip
        if z.size:  # the seed's U = q e^{-i phi}: the angle is -arg
            ax.scatter(-np.angle(z), np.abs(z), color="0.2", s=18, zorder=3, label="readings")
        ax.plot(ring, np.full_like(ring, p["permissible_g_mm"]), color="tab:green", lw=1.5,
                label=f"permissible {p['permissible_g_mm']:.1f} g mm")  # fmt: skip
        f = p.get("fit")
        if f is not None:  # the circle as read: its centre, its radius
            c = f["centre_read_g_mm"] * np.exp(-1j * math.radians(f["centre_read_angle_deg"]))
            pts = c + f["radius_read_g_mm"] * np.exp(1j * ring)
            ax.plot(-np.angle(pts), np.abs(pts), color="tab:blue", lw=1, label="fitted circle")
        if p["residual_g_mm"] is not None:  # scaled by the trial's ratio
            a = p["residual_angle_deg"]
            c = p["residual_g_mm"] * np.exp(-1j * math.radians(0.0 if a is None else a))
            ax.scatter([-np.angle(c)], [abs(c)], color="tab:red", marker="x", s=60, zorder=4,
                       label=f"residual {p['residual_g_mm']:.1f} g mm"
                       + (" (no angle)" if a is None else ""))  # fmt: skip
        ax.set_title(f"plane {p['plane']} [g mm]")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.06), fontsize=8, frameon=False)
    fig.tight_layout()
    return png(fig)


def _amount(r: dict[str, Any]) -> str:
    if r["re_g_mm"] is None:
        return "–"
    return f"{abs(complex(r['re_g_mm'], r['im_g_mm'])):.1f}"


def residual_page(out: dict[str, Any]) -> str:
    """The whole HTML page."""
    e = html.escape
    rows = []
    for p in out["planes"]:
        res = "–"
        if p["residual_g_mm"] is not None:
            res = f"{p['residual_g_mm']:.1f} ± {p['error95_g_mm']:.1f}"
            a = p["residual_angle_deg"]
            res += " (no angle: within its error of 0)" if a is None else f" at {a:.1f}°"
            if p.get("fit"):
                f = p["fit"]
                res += (f"; trial read at {100 * f['trial_read_share']:.1f} %, scatter "
                        f"{100 * f['scatter_share']:.2f} % of the radius")  # fmt: skip
        rows.append(f"<tr><td>{p['plane']}</td><td>{len(p['readings'])}</td>"
                    f"<td>{p['trial_g_mm']:.1f}</td><td>{res}</td>"
                    f"<td>{p['permissible_g_mm']:.1f}</td><td><b>{e(p['verdict'].upper())}</b>"
                    f"{'' if not p['why'] else ': ' + e(p['why'])}</td></tr>")  # fmt: skip
    readings = "".join(
        f"<tr><td>{p['plane']}</td><td>{e(r['run'])}</td><td>{r['angle_deg']:.1f}°</td>"
        f"<td>{_amount(r)}</td><td>{e(r['unread'] or '')}</td></tr>"
        for p in out["planes"]
        for r in p["readings"]
    )
    badge = {"pass": "pass", "fail": "fail"}.get(out["verdict"], "muted")
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Residual-unbalance check</title>
<style>{CSS}</style></head><body>
<header><h1>Residual-unbalance check</h1>
<span class="badge {badge}">{e(out["verdict"].upper())}</span></header>
<p><b>Rule:</b> {e(RULE)} Angles from the reference mark, against the direction of
rotation.</p>
<table><tr><th>plane</th><th>positions</th><th>trial [g mm]</th>
<th>residual [g mm] (95 %)</th><th>permissible [g mm]</th><th>verdict</th></tr>
{"".join(rows)}</table>
<img src="{_polar(out["planes"])}" alt="readings and fitted circle per plane">
<h2>Readings</h2>
<table><tr><th>plane</th><th>run</th><th>trial at</th><th>reading [g mm]</th><th></th></tr>
{readings}</table>
</body></html>
"""
