"""The balancing report: one self-contained HTML file, figures embedded as PNG.

What an operator needs on one page: the verdict per plane, the correction
(mass, angle, remove or add) on a polar plot against the tolerance circles,
the support amplitudes and phases, the spectrum around 1x, the speed over
the run, the settings and the warnings.  matplotlib is imported here only.
"""

from __future__ import annotations

import base64
import html
import io
import math
from typing import Any

import numpy as np

from stand.core import rad_s_to_rpm
from stand.result import Result, Traces, to_json
from stand.units import Display


def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=96, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def _polar(out: dict[str, Any]) -> str:
    """Unbalance per plane, its 95 % circle, and the plane's tolerance circle."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, subplot_kw={"projection": "polar"}, figsize=(9, 4.4))
    tol = {p["plane"]: p for p in out.get("tolerance", {}).get("planes", [])}
    d = Display.of(out)
    for ax, plane, corr in zip(axes, out["planes"], out["corrections"], strict=True):
        i = plane["plane"]
        ax.set_theta_zero_location("N")  # the reference mark at the top
        ax.set_theta_direction(-1)  # phi counted against the direction of rotation
        u, phi = d.unbalance_value(plane["unbalance_g_mm"]), math.radians(plane["angle_deg"])
        r95 = d.unbalance_value(plane["uncertainty_g_mm"])
        ring = np.linspace(0, 2 * math.pi, 200)
        rmax = u * 1.25
        if i in tol:
            per = d.unbalance_value(tol[i]["permissible_g_mm"])
            ax.fill(ring, np.full_like(ring, per), color="tab:green", alpha=0.15)
            ax.plot(
                ring,
                np.full_like(ring, per),
                color="tab:green",
                lw=1.5,
                label=f"tolerance {d.unbalance(tol[i]['permissible_g_mm'])}",
            )
            rmax = max(rmax, per * 1.25)
        ax.plot(
            [phi],
            [u],
            "o",
            color="tab:red",
            ms=8,
            label=f"unbalance {d.unbalance(plane['unbalance_g_mm'])}",
        )
        # the 95 % circle around the unbalance, drawn in the plane (not in polar coordinates)
        z = u * np.exp(1j * phi) + r95 * np.exp(1j * ring)
        ax.plot(np.angle(z), np.abs(z), color="tab:red", lw=1)
        for k, w in enumerate(corr["weights"]):
            a = math.radians(w["angle_deg"])
            ax.plot(
                [a, a],
                [0, rmax * 0.95],
                color="tab:blue",
                lw=2.5,
                label=f"{corr['action']} {d.mass(w['mass_g'])} at {w['angle_deg']:.1f}°"
                if k < 3
                else None,
            )
        ax.set_rmax(rmax * 1.1)
        ax.set_title(f"plane {i} [{d.unbalance_unit}]", pad=18)
        ax.legend(loc="lower center", bbox_to_anchor=(0.5, -0.32), fontsize=8)
    return _png(fig)


def _spectrum_and_speed(traces: Traces | None, rpm: float) -> tuple[str, str]:
    import matplotlib.pyplot as plt

    f1 = rpm / 60
    fig, ax = plt.subplots(figsize=(9, 3.2))
    for n, (f, spec) in sorted((traces.spectra if traces else {}).items()):
        ax.semilogy(f, spec, lw=1, label=f"support {n}")
    for k in (1, 2, 3):
        ax.axvline(k * f1, color="grey", ls=":", lw=1)
        ax.text(k * f1, ax.get_ylim()[1], f"{k}x", ha="center", va="bottom", fontsize=8)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("amplitude [m/s²]")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    spectrum = _png(fig)

    fig, ax = plt.subplots(figsize=(9, 2.6))
    for n, (t, w) in sorted((traces.speeds if traces else {}).items()):
        ax.plot(t, rad_s_to_rpm(w), lw=1, label=f"node {n}")
    ax.set_xlabel("time [s] (node clock)")
    ax.set_ylabel("speed [rpm]")
    ax.ticklabel_format(axis="y", useOffset=False, style="plain")
    lo, hi = ax.get_ylim()
    mid = 0.5 * (lo + hi)
    half = max(0.5 * (hi - lo), 0.01 * mid)  # a steady speed shows as steady: at least +-1 %
    ax.set_ylim(mid - half, mid + half)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return spectrum, _png(fig)


_CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 960px; color: #222; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.5em 0; }
td, th { border: 1px solid #ccc; padding: 4px 10px; text-align: right; }
th { background: #f2f2f2; } td.l, th.l { text-align: left; }
.pass { background: #1b7f3a; color: white; padding: 2px 10px; border-radius: 4px; }
.fail { background: #b3261e; color: white; padding: 2px 10px; border-radius: 4px; }
.big { font-size: 1.25em; } .muted { color: #666; font-size: 0.9em; }
.warn { background: #fff4ce; border-left: 4px solid #e0a800; padding: 4px 10px; margin: 4px 0; }
img { max-width: 100%; }
"""


def _verdict(out: dict[str, Any]) -> str:
    t = out.get("tolerance")
    if t is None:
        return '<p class="big">No tolerance set: correct as shown below.</p>'
    ok = all(p["pass"] for p in t["planes"])
    if ok:
        return (
            '<p class="big"><span class="pass">IN TOLERANCE</span> both planes within '
            f"ISO 21940-11 G {t['grade_mm_s']:g}: no correction needed.</p>"
        )
    bad = ", ".join(str(p["plane"]) for p in t["planes"] if not p["pass"])
    return (
        '<p class="big"><span class="fail">OUT OF TOLERANCE</span> plane(s) '
        + bad
        + ": make the correction below, then run again with --check.</p>"
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


def render(result: Result) -> str:
    """The report of a result as one HTML document (figures embedded): formatting only."""
    e = html.escape
    out = to_json(result)
    p = result.provenance
    meta = {
        "run file": p.run_file or "",
        "start time": p.start_time,
        "software": p.software,
        "source": p.source,
        "frames": p.frames,
        "duration [s]": round(p.duration_s, 3),
        "configuration": f"{p.config_source} (SHA-256 {p.config_sha256[:16]})",
    }
    config_text = p.config_toml
    d = Display.of(out)
    rows = []
    tol = {p["plane"]: p for p in out.get("tolerance", {}).get("planes", [])}
    for plane, corr in zip(out["planes"], out["corrections"], strict=True):
        i = plane["plane"]
        what = (
            " + ".join(
                f"{d.mass(w['mass_g'])} at {w['angle_deg']:.1f}°"
                + ("" if w["position"] is None else f" (position {w['position']})")
                for w in corr["weights"]
            )
            or "nothing"
        )
        if i in tol:
            t = tol[i]
            verdict = (
                '<span class="pass">PASS</span>' if t["pass"] else '<span class="fail">FAIL</span>'
            )
            margin = ("margin " if t["pass"] else "over by ") + d.unbalance(abs(t["margin_g_mm"]))
            tol_cell = (
                f"{d.unbalance(t['permissible_g_mm'])}: {verdict} <span class=muted>{margin}</span>"
            )
        else:
            tol_cell = "<span class=muted>no [tolerance] set</span>"
        if corr.get("within_noise"):
            action = "no correction: inside its own 95 % interval (angle undefined)"
        elif corr.get("within_tolerance"):
            action = "within tolerance: no correction needed"
        else:
            action = (
                f"<b>{e(corr['action'])} {e(what)}</b> at radius {d.length(plane['radius_mm'])}"
            )
        angle = "–" if corr.get("within_noise") else f"{plane['angle_deg']:.1f}°"
        rows.append(
            f"<tr><td>{i}</td><td>{d.number(plane['unbalance_g_mm'])} ± "
            f"{d.number(plane['uncertainty_g_mm'])}"
            f"</td><td>{angle}</td><td class=l big>{action}</td>"
            f"<td class=l>{tol_cell}</td></tr>"
        )
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
    spectrum, speed = _spectrum_and_speed(result.traces, out["rpm"])
    st, cp = out["static"], out["couple"]
    t = out.get("tolerance")
    tol_line = (
        f"ISO 21940-11, G {t['grade_mm_s']:g} at {t['max_speed_rpm']:g} rpm: "
        f"U<sub>per</sub> = {d.unbalance(t['permissible_g_mm'])}"
        if t
        else "no tolerance set"
    )
    run_meta = "".join(
        f"<tr><th class=l>{e(str(k))}</th><td class=l>{e(str(v))}</td></tr>"
        for k, v in meta.items()
    )
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Balancing report</title>
<style>{_CSS}</style></head><body>
<h1>Balancing report</h1>
{_verdict(out)}
<p class=muted>{e(str(meta.get("run file", "")))} · {out["rpm"]:.1f} rpm ·
{e(str(meta.get("start time", "")))}</p>
<h2>Correction</h2>
<p class=muted>Angles from the reference mark, counted <b>against the direction of rotation</b>.
To remove material: at that angle; to add a weight: 180° opposite.</p>
<table><tr><th>plane</th><th>unbalance [{d.unbalance_unit}] (95 %)</th><th>angle</th>
<th class=l>correction</th><th class=l>tolerance</th></tr>{"".join(rows)}</table>
<p>Static part {d.unbalance(st["unbalance_g_mm"])} at {st["angle_deg"]:.1f}°; couple part
±{d.unbalance(cp["unbalance_g_mm"])} at {cp["angle_deg"]:.1f}° (plane 1 / plane 2).
{tol_line}.</p>
<img alt="corrections against the tolerance circles" src="{_polar(out)}">
{_uncertainty(out)}
<h2>Supports (1x)</h2>
<table><tr><th>node</th><th>amplitude [m/s²] (95 %)</th><th>phase</th><th>revolutions</th>
<th>noise at 1x [m/s²]</th></tr>{supports}</table>
<h2>Spectrum around 1x</h2><img alt="spectrum" src="{spectrum}">
<h2>Speed over the run</h2><img alt="speed" src="{speed}">
<h2>Warnings</h2>{warnings}
<h2>Settings</h2><table>{run_meta}</table>
<pre>{e(config_text)}</pre>
</body></html>
"""
