"""A run-up's pictures: the Bode plot (each support's 1x amplitude and phase against speed,
its 2x amplitude thin,
the modes fitted, the model's modes, the balancing speed), the polar plot (each support's
response shape ``-A / w^4`` in the complex plane, the modes marked) and the waterfall
(each support's spectrum against speed, the orders 1 to 4 drawn)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from stand.core.resonance import response_shape
from stand.field.runup import EDGE
from stand.files import output

RPM = 30 / math.pi
"""rad/s to rpm."""


def _bode(plt: Any, a: Any) -> Any:
    fig, (amp, ph) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for c, colour in zip(a.curves, ("tab:blue", "tab:orange"), strict=True):
        rpm = c.omega_rad_s * RPM
        amp.semilogy(rpm, np.abs(c.accel_m_s2), color=colour, label=f"support {c.support}")
        if len(c.x2_m_s2):
            amp.semilogy(rpm, np.abs(c.x2_m_s2), color=colour, lw=0.7, ls="-.",
                         label=f"support {c.support}, 2x")  # fmt: skip
        ph.plot(rpm, np.degrees(np.unwrap(np.angle(c.accel_m_s2))), color=colour)
    for w in a.model_omega_rad_s:
        amp.axvline(w * RPM, color="0.5", ls="--", lw=1)
    for w in a.modes.omega_rad_s if a.modes else ():
        amp.axvline(w * RPM, color="black", ls=":", lw=1.2)
    amp.axvline(a.balancing_omega_rad_s * RPM, color="tab:green", lw=1.5,
                label=f"balancing speed {a.balancing_omega_rad_s * RPM:.0f} rpm")  # fmt: skip
    amp.plot([], [], color="0.5", ls="--", label="the model's modes")
    amp.plot([], [], color="black", ls=":", label="the modes fitted")
    amp.set_ylabel("1x (and 2x) acceleration [m/s^2]")
    amp.set_title(f"Bode plot of the {a.direction} (a point every {a.revs_per_block} "
                  "revolution(s))")  # fmt: skip
    amp.legend(fontsize=8)
    ph.set_ylabel("1x phase [deg]")
    ph.set_xlabel("speed [rpm]")
    fig.tight_layout()
    return fig


def _polar(plt: Any, a: Any) -> Any:
    fig, axes = plt.subplots(1, 2, figsize=(10, 5))
    hi = a.omega_range_rad_s[1]
    fitted = a.modes.omega_rad_s if a.modes else ()
    for ax, c in zip(axes, a.curves, strict=True):
        band = (c.omega_rad_s >= EDGE * hi) & (c.omega_rad_s <= 0.97 * hi)
        w, G = c.omega_rad_s[band], response_shape(c.omega_rad_s[band], c.accel_m_s2[band])
        z = G / (float(np.abs(G).max()) or 1.0)
        ax.plot(z.real, z.imag, color="0.3", lw=1, marker=".", ms=3)
        for wn in fitted:
            k = int(np.argmin(np.abs(w - wn)))
            ax.scatter([z[k].real], [z[k].imag], color="tab:red", zorder=3)
            ax.annotate(f"{wn * RPM:.0f} rpm", (z[k].real, z[k].imag), fontsize=8,
                        xytext=(4, 4), textcoords="offset points")  # fmt: skip
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"support {c.support}: -A / w^4 from {EDGE * hi * RPM:.0f} rpm (scaled)")
        ax.set_xlabel("Re")
        ax.set_ylabel("Im")
    fig.tight_layout()
    return fig


def _waterfall(plt: Any, a: Any) -> Any:
    fig, axes = plt.subplots(1, 2, figsize=(11, 5), sharey=True)
    for ax, wf in zip(axes, a.waterfalls, strict=True):
        if not len(wf.omega_rad_s):
            ax.set_title(f"support {wf.support}: too short for a waterfall")
            continue
        top_hz = float(wf.omega_rad_s.max()) / (2 * math.pi)
        band = wf.freq_hz <= 4.5 * top_hz
        level = 20 * np.log10(np.maximum(wf.amplitude_m_s2[:, band], 1e-6))
        mesh = ax.pcolormesh(wf.freq_hz[band], wf.omega_rad_s * RPM, level, shading="auto",
                             cmap="viridis", vmin=float(level.max()) - 60)  # fmt: skip
        for order in (1, 2, 3, 4):
            ax.plot(order * wf.omega_rad_s / (2 * math.pi), wf.omega_rad_s * RPM, color="white",
                    lw=0.6, ls=":")  # fmt: skip
        ax.set_xlim(0, 4.5 * top_hz)
        ax.set_title(f"support {wf.support}: spectrum against speed (orders 1 to 4 dotted)")
        ax.set_xlabel("frequency [Hz]")
        fig.colorbar(mesh, ax=ax, label="dB re 1 m/s^2")
    axes[0].set_ylabel("speed [rpm]")
    fig.tight_layout()
    return fig


DRAWINGS = (
    ("bode.png", "Bode plot: each support's 1x (and 2x) against speed", _bode),
    ("polar.png", "Polar plot: each support's response shape", _polar),
    ("waterfall.png", "Waterfall: each support's spectrum against speed", _waterfall),
)
"""Each picture: its file name, its title on a page, and what draws it."""


def runup_plots(analysis: Any, folder: str, force: bool) -> list[str]:
    """Write ``bode.png``, ``polar.png`` and ``waterfall.png`` into ``folder`` (made if
    missing; each file safely: a temporary name, then the file; never over one without
    ``force``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    Path(folder).mkdir(parents=True, exist_ok=True)
    written = []
    for name, _, draw in DRAWINGS:
        fig = draw(plt, analysis)
        path = str(Path(folder) / name)
        with output(path, force=force) as tmp:
            fig.savefig(tmp, format="png", dpi=100)
        plt.close(fig)
        written.append(path)
    return written
