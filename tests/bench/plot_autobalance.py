"""The window diagram of docs/autobalancer.md: Re H_PP against speed on the demo stand with
two 50 g balls on 60 mm in plane 1 (damped: H1 = 40, H2 = 60 N s/m, so that the curve
stays finite), the windows shaded, the natural and antiresonance speeds marked.

    .venv/bin/python tests/bench/plot_autobalance.py     # writes docs/autobalancer-windows.png
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from stand.core import rad_s_to_rpm, rpm_to_rad_s
from stand.core.autobalance import antiresonance, driving_point, windows, with_balls
from stand.core.model import natural_frequencies
from stand.sim import load_scene

OUT = Path(__file__).resolve().parents[2] / "docs" / "autobalancer-windows.png"


def main() -> None:
    _, p, _ = load_scene("demo")
    p = with_balls(dataclasses.replace(p, H1=40.0, H2=60.0), 1, 0.1)
    rpm = np.linspace(100, 1200, 2000)
    re = np.array([driving_point(p, 1, float(rpm_to_rad_s(r))).real for r in rpm]) * 1e6
    fig, ax = plt.subplots(figsize=(8, 4.2), dpi=110)
    ax.plot(rpm, re, color="#1f4e79", lw=1.6, label="Re H_PP, race plane 1 [µm/N]")
    ax.axhline(0, color="black", lw=0.6)
    for lo, hi in windows(p, 1, float(rpm_to_rad_s(1200))):
        lo_rpm = float(rad_s_to_rpm(lo))
        hi_rpm = 1200 if hi is None else float(rad_s_to_rpm(hi))
        ax.axvspan(lo_rpm, hi_rpm, color="#8fd19e", alpha=0.45, lw=0)
    for k, w in enumerate(natural_frequencies(p)):
        ax.axvline(float(rad_s_to_rpm(w)), color="#c0392b", ls="--", lw=1,
                   label="natural speeds" if k == 0 else None)  # fmt: skip
    anti = antiresonance(p, 1)
    if anti is not None:
        ax.axvline(float(rad_s_to_rpm(anti)), color="#8e44ad", ls=":", lw=1.4,
                   label="antiresonance of plane 1")  # fmt: skip
    ax.fill_between([], [], color="#8fd19e", alpha=0.45, label="windows: the balls balance")
    ax.set_xlim(100, 1200)
    ax.set_ylim(np.percentile(re, 2) * 1.2, np.percentile(re, 98) * 1.2)
    ax.set_xlabel("speed [rpm]")
    ax.set_ylabel("Re H_PP [µm/N]")
    ax.set_title("Where two 50 g balls on 60 mm balance the demo rotor (plane 1)")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
