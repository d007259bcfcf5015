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
    """Write the PNG (safely: a temporary name, then the file)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 5))
    ring = np.exp(1j * np.linspace(0, 2 * math.pi, 361))
    for i, ax in enumerate(axes):
        z = (readings[:, i] - reference[i]) * 1e6  # g mm from the master's value
        ax.scatter(z.real, z.imag, s=10, color="0.25", label=f"{len(z)} readings")
        band = BAND * tol[i] * 1e6 * ring
        ax.plot(
            band.real,
            band.imag,
            color="tab:green",
            label=f"0.2 U_per ({BAND * tol[i] * 1e6:.0f} g mm)",
        )
        c = planes[i]
        r = c.r_ref_kg_m * 1e6 * ring
        ax.plot(r.real, r.imag, color="tab:red", ls="--", label="99.73 % about the master")
        ax.scatter([0], [0], marker="x", color="tab:blue", s=60, label="master's value")
        ax.set_aspect("equal")
        ax.set_title(f"plane {i + 1}: Cg_v {c.cg:.2f}, Cgk_v {c.cgk:.2f}")
        ax.set_xlabel("Re [g mm] from the master")
        ax.set_ylabel("Im [g mm]")
        ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    with output(path, force=force) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
