"""Order tracking (``stand.measuring.track``): through a run-up, each block of two
revolutions gives the 1x the support had at that block's speed."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.drivers.v1.build import rebuild
from stand.drivers.v1.nodes import merge, node_frames
from stand.measuring.track import track_1x

RATE = 4000.0


def _ramp(w0: float, w1: float, seconds: float, A: complex, kappa: float):  # type: ignore[no-untyped-def]
    """A node whose 1x is ``A (w / w1)^2 e^{i kappa w}`` while the speed ramps linearly
    from ``w0`` to ``w1`` [rad/s]; its stream (a second node the same, as the protocol
    needs two)."""
    n = round(seconds * RATE)
    t = np.arange(n) / RATE
    al = (w1 - w0) / seconds
    theta = w0 * t + 0.5 * al * t * t
    w = w0 + al * t
    a = (A * (w / w1) ** 2 * np.exp(1j * kappa * w) * np.exp(1j * theta)).real
    turns = np.arange(1, int(theta[-1] / (2 * math.pi)))
    edges = (-w0 + np.sqrt(w0 * w0 + 2 * al * 2 * math.pi * turns)) / al * RATE  # theta = 2 pi k
    counts = np.rint(a / 1e-4).astype(np.int16)  # 100 um/s^2 a count: 3 m/s^2 in 30000
    frames = merge([node_frames(i, counts, rate_hz=RATE, scale_um_s2=100, edges=edges)
                    for i in (1, 2)])  # fmt: skip
    return rebuild(frames).nodes[1]


@settings(max_examples=20, deadline=None)
@given(
    st.floats(20.0, 60.0), st.floats(1.0, 3.0), st.floats(0.0, 2 * math.pi),
    st.floats(-0.02, 0.02),
)  # fmt: skip
def test_each_block_holds_the_1x_at_its_speed(w0: float, amp: float, phase: float,
                                              kappa: float) -> None:  # fmt: skip
    """A ramp from ``w0`` to 100 rad/s in 6 s (up to 13 rad/s^2: four times the shipped
    run-up's), the 1x growing with the speed squared and turning with it: every block's
    phasor is the one at its mean speed to 2e-3 of the top amplitude.  Measured 1.4e-3:
    a block fits a constant phasor to a 1x that grows through its two revolutions, and
    the growth leaks into its quadrature (first order in the growth per radian); the
    quantization, 1e-4 m/s^2 a count, averages out over a block's samples."""
    A = amp * np.exp(1j * phase)
    s = _ramp(w0, 100.0, 6.0, A, kappa)
    w, got, _ = track_1x(s, 0.0)
    assert len(w) > 20
    want = A * (w / 100.0) ** 2 * np.exp(1j * kappa * w)
    assert np.max(np.abs(got - want)) < 2e-3 * amp
