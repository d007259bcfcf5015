"""The capability study's picture: per plane the readings as a scatter about the master's
value, the band (0.2 U_per) the indices compare with, and the 99.73 % circle."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from stand.core.capability import BAND
from stand.files import output


def capability_plot(readings: np.ndarray, reference: np.ndarray, planes: Any,
                    tol: tuple[float, float], path: str, force: bool) -> None:  # fmt: skip
    """Write the PNG (safely: a temporary name, then the file): per plane, above, the runs'
    scatter about the master's value with the 99.73 % circles (scaled to them, so that the
    runs show as runs); below, the same against the band (0.2 U_per) and the tolerance
    circle U_per."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 9.6))
    ring = np.exp(1j * np.linspace(0, 2 * math.pi, 361))
    for i in range(2):
        z = (readings[:, i] - reference[i]) * 1e6  # g mm from the master's value
        c = planes[i]
        mean = complex(z.mean())
        for ax, whole in ((axes[0, i], False), (axes[1, i], True)):
            ax.scatter(z.real, z.imag, s=10, color="0.25", zorder=3,
                       label=f"{len(z)} readings")  # fmt: skip
            about = mean + c.r_mean_kg_m * 1e6 * ring
            ax.plot(about.real, about.imag, color="tab:orange",
                    label=f"99.73 % about the mean ({c.r_mean_kg_m * 1e6:.2f} g mm)")  # fmt: skip
            r = c.r_ref_kg_m * 1e6 * ring
            ax.plot(r.real, r.imag, color="tab:red", ls="--",
                    label=f"99.73 % about the master ({c.r_ref_kg_m * 1e6:.2f} g mm)")  # fmt: skip
            ax.scatter([0], [0], marker="x", color="tab:blue", s=60, zorder=4,
                       label="master's value")  # fmt: skip
            if whole:
                for share, colour, name in ((BAND, "tab:green", "0.2 U_per"),
                                            (1.0, "0.5", "U_per")):  # fmt: skip
                    b = share * tol[i] * 1e6 * ring
                    ax.plot(b.real, b.imag, color=colour,
                            label=f"{name} ({share * tol[i] * 1e6:.0f} g mm)")  # fmt: skip
                ax.set_title(f"plane {i + 1} against its tolerance")
            else:
                ax.set_title(f"plane {i + 1}: Cg_v {c.cg:.2f}, Cgk_v {c.cgk:.2f}: the runs")
            ax.set_aspect("equal")
            ax.set_xlabel("Re [g mm] from the master")
            ax.set_ylabel("Im [g mm]")
            ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    with output(path, force=force) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
