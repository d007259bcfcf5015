"""The report's figures (matplotlib, imported here only), as embedded PNG data URLs.

The polar plots show each plane turning as the arrow shows: the reference
mark at the top, angles counted against the direction of
rotation (the arrow), the holes or blades numbered 1..N when the correction
uses positions, the tolerance circle, the unbalance with its 95 % circle
(before and after, for a check) and the correction.  Text sits in the
legend below each plot and on the angular grid, so that nothing collides.
"""

from __future__ import annotations

import base64
import datetime as dt
import io
import math
from typing import Any

import numpy as np

from stand.core import rad_s_to_rpm
from stand.i18n.display import Display
from stand.i18n.language import ENGLISH, Language
from stand.report.units import ACTIONS
from stand.solve.result import Traces


def png(fig: Any) -> str:
    """The figure as a ``data:image/png`` URL (and closed)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def _grid(ax: Any, positions: dict[str, Any]) -> None:
    """The angular grid: the holes 1..N when there are positions, else every 30 deg."""
    n = int(positions.get("count") or 0)
    if n:
        first = float(positions.get("position1_deg") or 0.0)
        angles = [(first + k * 360.0 / n) % 360 for k in range(n)]
        ax.set_thetagrids(angles, labels=[f"{k + 1}" for k in range(n)], fontsize=9)
        ax.plot(np.radians(angles), [ax.get_rmax()] * n, "o", color="0.35", ms=5, clip_on=False)
    else:
        ax.set_thetagrids(
            range(0, 360, 30), labels=[f"{a}°" for a in range(0, 360, 30)], fontsize=8
        )
    ax.tick_params(axis="y", labelsize=7)


def _ticks(rmax: float) -> list[float]:
    """Two or three round radial ticks below ``rmax`` (their labels must not crowd)."""
    step = 10 ** math.floor(math.log10(rmax / 2))
    for m in (1, 2, 5, 10):
        if rmax / (m * step) <= 3:
            step *= m
            break
    return [k * step for k in range(1, int(rmax / step) + 1) if k * step < rmax * 0.98]


def _rotation(ax: Any, rmax: float) -> None:
    """The direction of rotation (against the angles) and the reference mark at the top."""
    arc = np.radians(np.linspace(60, 20, 30))  # angles count clockwise: rotation runs back
    r = np.full_like(arc, rmax * 1.16)
    ax.plot(arc, r, color="black", lw=1.2, clip_on=False)
    ax.annotate(
        "",
        xy=(arc[-1], r[-1]),
        xytext=(arc[-3], r[-3]),
        arrowprops={"arrowstyle": "-|>", "color": "black", "lw": 1.2},
        annotation_clip=False,
    )
    ax.plot([0], [rmax * 1.16], marker="v", color="black", ms=8, clip_on=False)


def _plane_limits(out: dict[str, Any]) -> dict[int, dict[str, float]]:
    """Each correction plane's limit (the tolerance circle), by plane number."""
    limits = (out.get("tolerance") or {}).get("plane_limits_g_mm") or []
    return {k + 1: {"permissible_g_mm": v} for k, v in enumerate(limits)}


def _cuts_and_weights(ax: Any, plane: dict[str, Any], corr: dict[str, Any], d: Display,
                      rmax: float, _: Language) -> None:  # fmt: skip
    """A plane's correction on its polar plot: the holes (numbered in drilling order, with
    their depths), the slot, the weights."""

    for h in plane.get("holes") or []:  # numbered in drilling order, with their depths
        a = math.radians(h["angle_deg"])
        ax.plot([a, a], [0, rmax * 0.95], color="tab:orange", lw=2.5)
        at = rmax * (0.82 - 0.3 * (h["number"] % 2 == 0))  # neighbours' labels apart
        ax.annotate(f"{h['number']}: {d.depth(h['depth_mm'])}", (a, at),
                    fontsize=9, fontweight="bold", ha="center", color="tab:orange",
                    bbox={"boxstyle": "round", "fc": "white", "ec": "tab:orange"})  # fmt: skip
    if plane.get("holes"):
        ax.plot([], [], color="tab:orange", lw=2.5, label=d.cuts(plane, _))
    if plane.get("slot"):
        sl = plane["slot"]
        arc = np.radians(sl["angle_deg"] + np.linspace(-0.5, 0.5, 50) * sl["arc_deg"])
        ax.plot(arc, np.full_like(arc, rmax * 0.9), color="tab:orange", lw=6,
                label=_("slot {arc}° × {depth}").format(
                    arc=f"{sl['arc_deg']:.0f}", depth=d.depth(sl["depth_mm"])))  # fmt: skip
    for k, w in enumerate(corr["weights"]):
        a = math.radians(w["angle_deg"])
        where = "" if w["position"] is None else _(" (position {n})").format(n=w["position"])
        text = f"{_(ACTIONS.get(corr['action'], corr['action']))} {d.mass(w['mass_g'])}{where}"
        ax.plot([a, a], [0, rmax * 0.95], color="tab:blue", lw=2.5,
                label=text if k < 3 else None)  # fmt: skip


def polar(out: dict[str, Any], _: Language = ENGLISH) -> str:
    """Each plane: tolerance, unbalance (before and after a check), correction, holes."""
    import matplotlib.pyplot as plt

    d = Display.of(out, _)
    fig, axes = plt.subplots(1, 2, subplot_kw={"projection": "polar"}, figsize=(9.5, 5.0))
    tol = _plane_limits(out)
    check = {p["plane"]: p for p in out.get("check", {}).get("planes", [])}
    ring = np.linspace(0, 2 * math.pi, 200)
    for ax, plane, corr in zip(axes, out["planes"], out["corrections"], strict=True):
        i = plane["plane"]
        ax.set_theta_zero_location("N")  # the reference mark at the top
        ax.set_theta_direction(-1)  # angles counted against the direction of rotation
        u, phi = d.unbalance_value(plane["unbalance_g_mm"]), math.radians(plane["angle_deg"])
        r95 = d.unbalance_value(plane["uncertainty_g_mm"])
        rmax = max(u + r95, 1e-9) * 1.2
        if i in check:
            rmax = max(rmax, d.unbalance_value(check[i]["before_g_mm"]) * 1.2)
        if i in tol:
            per = d.unbalance_value(tol[i]["permissible_g_mm"])
            ax.fill(ring, np.full_like(ring, per), color="tab:green", alpha=0.15)
            ax.plot(ring, np.full_like(ring, per), color="tab:green", lw=1.5,
                    label=_("tolerance {limit}").format(
                        limit=d.unbalance(tol[i]["permissible_g_mm"])))  # fmt: skip
            rmax = max(rmax, per * 1.25)
        if i in check:  # the run before the correction, where it was
            b = check[i]
            ax.plot([math.radians(b["before_angle_deg"])], [d.unbalance_value(b["before_g_mm"])],
                    "s", color="0.45", ms=7, label=_("before {unbalance} at {angle}°").format(
                        unbalance=d.unbalance(b["before_g_mm"]),
                        angle=f"{b['before_angle_deg']:.1f}"))  # fmt: skip
        word = (
            _("after {unbalance} at {angle}°")
            if i in check
            else _("unbalance {unbalance} at {angle}°")
        )
        label = word.format(unbalance=d.unbalance(plane["unbalance_g_mm"]),
                            angle=f"{plane['angle_deg']:.1f}")  # fmt: skip
        ax.plot([phi], [u], "o", color="tab:red", ms=7, label=label)
        z = u * np.exp(1j * phi) + r95 * np.exp(1j * ring)  # the 95 % circle, in the plane
        ax.plot(np.angle(z), np.abs(z), color="tab:red", lw=1)
        _cuts_and_weights(ax, plane, corr, d, rmax, _)
        ax.set_rmax(rmax)
        ax.set_rticks(_ticks(rmax))
        ax.set_rlabel_position(112)
        _grid(ax, out.get("correction_positions", {}))
        _rotation(ax, rmax)
        ax.set_title(_("plane {i} [{unit}]").format(i=i, unit=d.unbalance_unit), pad=26)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), fontsize=8, frameon=False)
    return png(fig)


def spectrum_and_speed(traces: Traces | None, rpm: float,
                       _: Language = ENGLISH) -> tuple[str, str]:  # fmt: skip
    """The spectrum around 1x and the speed over the run, per node."""
    import matplotlib.pyplot as plt

    f1 = rpm / 60
    fig, ax = plt.subplots(figsize=(9, 3.2))
    for n, (f, spec) in sorted((traces.spectra if traces else {}).items()):
        ax.semilogy(f, spec, lw=1, label=_("support {n}").format(n=n))
    for k in (1, 2, 3):
        ax.axvline(k * f1, color="grey", ls=":", lw=1)
        ax.text(k * f1, ax.get_ylim()[1], f"{k}x", ha="center", va="bottom", fontsize=8)
    ax.set_xlabel(_("frequency [Hz]"))
    ax.set_ylabel(_("amplitude [m/s²]"))
    if ax.get_legend_handles_labels()[0]:  # without traces no curve to name
        ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    spectrum = png(fig)

    fig, ax = plt.subplots(figsize=(9, 2.6))
    for n, (t, w) in sorted((traces.speeds if traces else {}).items()):
        ax.plot(t, rad_s_to_rpm(w), lw=1, label=_("node {n}").format(n=n))
    ax.set_xlabel(_("time [s] (node clock)"))
    ax.set_ylabel(_("speed [rpm]"))
    ax.ticklabel_format(axis="y", useOffset=False, style="plain")
    lo, hi = ax.get_ylim()
    mid = 0.5 * (lo + hi)
    half = max(0.5 * (hi - lo), 0.01 * mid)  # a steady speed shows as steady: at least +-1 %
    ax.set_ylim(mid - half, mid + half)
    if ax.get_legend_handles_labels()[0]:  # without traces no curve to name
        ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return spectrum, png(fig)


_PARTS = (("plane1", "plane 1"), ("plane2", "plane 2"), ("static", "static part"),
          ("couple", "couple part"))  # fmt: skip


def production(out: dict[str, Any]) -> tuple[str, str]:
    """A rotor type's initial unbalances: a polar scatter per part (tolerance circle, the
    mean and its 95 % region), and their size over time."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, subplot_kw={"projection": "polar"}, figsize=(14, 4.4))
    fig.subplots_adjust(wspace=0.55)
    ring = np.linspace(0, 2 * math.pi, 200)
    per = dict(zip(("plane1", "plane2"), out.get("permissible_g_mm") or [None, None], strict=True))
    for ax, (key, title) in zip(axes, _PARTS, strict=True):
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        pts = np.array([complex(x, y) for x, y in out["points_g_mm"][key]])
        ax.plot(-np.angle(pts), np.abs(pts), ".", ms=3, color="0.4", label="rotors")
        rmax = float(np.abs(pts).max()) * 1.1 if len(pts) else 1.0
        if per.get(key):
            ax.plot(ring, np.full_like(ring, per[key]), color="tab:green", lw=1.5,
                    label=f"tolerance {per[key]:.0f} g mm")  # fmt: skip
            rmax = max(rmax, per[key] * 1.2)
        s = out[key]
        if "mean" in s:
            m = s["mean"]["unbalance_g_mm"] * np.exp(-1j * math.radians(s["mean"]["angle_deg"]))
            a, b = s["region95_g_mm"]
            t = math.radians(-s["region95_major_deg"])  # the ellipse, drawn in the plane
            e = m + (a * np.cos(ring) + 1j * b * np.sin(ring)) * np.exp(1j * t)
            ax.plot(-np.angle(e), np.abs(e), color="tab:red", lw=1.5, label="mean: 95 % region")
            ax.plot([-np.angle(m)], [abs(m)], "+", color="tab:red", ms=10, mew=2)
        ax.set_rmax(rmax)
        ax.set_rticks(_ticks(rmax))
        ax.set_rlabel_position(112)
        ax.set_thetagrids(range(0, 360, 90), labels=["0°", "90°", "180°", "270°"], fontsize=7)
        ax.tick_params(axis="y", labelsize=7)
        ax.set_title(title, pad=14)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), fontsize=7, frameon=False)
    polar_png = png(fig)

    import matplotlib.dates as mdates

    fig, ax = plt.subplots(figsize=(10, 3.2))
    times = mdates.date2num([dt.datetime.fromisoformat(t) for t in out["times"]])  # type: ignore[no-untyped-call]
    ax.xaxis_date()
    for key, title in _PARTS[:2]:
        size = [abs(complex(x, y)) for x, y in out["points_g_mm"][key]]
        ax.plot(times, size, ".", ms=3, label=title)
    for key in ("plane1", "plane2"):
        if per.get(key):
            ax.axhline(per[key], color="tab:green", lw=1, ls="--")
    ax.set_ylabel("initial unbalance [g mm]")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.autofmt_xdate()
    return polar_png, png(fig)


def speed_bars(out: dict[str, Any]) -> str:
    """Balancing across speeds: per speed, each plane's equivalent unbalance before and
    after the correction (log scale: before is thousands of g mm, after a few) against
    the permissible value."""
    import matplotlib.pyplot as plt

    speeds = out["speeds"]
    fig, axes = plt.subplots(1, len(speeds), figsize=(3.2 * len(speeds), 3.0), sharey=True)
    axes = np.atleast_1d(axes)
    values = [p["unbalance_g_mm"] for s in speeds for k in ("before", "after") for p in s[k]]
    floor = max(min([*values, 1.0]) / 3, 1e-3)
    pers = [q for s in speeds for q in (s["permissible_g_mm"] or [])]
    top = 3 * max([*values, *pers, floor])
    for ax, s in zip(axes, speeds, strict=True):
        x = np.arange(len(s["before"]))
        before = [max(p["unbalance_g_mm"], floor) for p in s["before"]]
        after = [max(p["unbalance_g_mm"], floor) for p in s["after"]]
        ax.bar(x - 0.2, before, 0.38, color="0.7", label="before")
        colour = "tab:green" if s["pass_after"] in (True, None) else "tab:red"
        ax.bar(x + 0.2, after, 0.38, color=colour, label="after")
        if s["permissible_g_mm"]:
            for i, per in enumerate(s["permissible_g_mm"]):
                ax.plot([i - 0.45, i + 0.45], [per, per], "k--", lw=1)
        ax.set_yscale("log")
        ax.set_ylim(floor, top)
        ax.set_xticks(x, [f"plane {p['plane']}" for p in s["before"]])
        ax.set_title(f"{s['rpm']:.0f} rpm", fontsize=10)
        ax.grid(True, axis="y", alpha=0.3)
    axes[0].set_ylabel("unbalance [g mm]")
    axes[0].plot([], [], "k--", lw=1, label="permissible")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, -0.06))  # fmt: skip
    fig.tight_layout()
    return png(fig)
