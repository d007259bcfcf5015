"""A recorded run-up or coast-down read as the stand's frequency response: each support's
1x order-tracked block by block (:func:`stand.measuring.track.track_1x`), the resonances
its response shape shows (:mod:`stand.core.resonance`), set against the stand model's own
modes, and the balancing speed's separation margin from each.

What the data cannot carry is said, never passed on: a run too short or of one speed, a
speed that goes backwards, a reference mark lost mid-sweep (the revolutions without an
edge are left out of the curve), a sweep too fast for a resonance's bandwidth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stand.config import Config
from stand.core.model import StandParameters
from stand.core.resonance import (
    ModalFit,
    Resonance,
    modal_fit,
    model_modes,
    resonances,
    response_shape,
    separation_margin_required,
)
from stand.drivers.streams import NodeStream, RunStreams
from stand.errors import MeasurementError
from stand.measuring.gate import node_segment
from stand.measuring.track import track_1x

REVS_PER_BLOCK = 1
"""Revolutions in each order-tracking block: the curve's resolution in speed."""
EDGE = 0.3
"""The modal fit reads the curve above this fraction of its top speed (below, the 1x is
a few counts: ``A ~ w^4`` far below the resonances) and below 97 % of it (the hold)."""
SWEEP_BIAS = 2.5
"""A run-up reads a mode's frequency high by at most ``SWEEP_BIAS alpha / (zeta w_n^2)``
of it (``alpha`` the sweep [rad/s^2]): the response lags the sweep by about the mode's
decay time.  Measured on the demo stand with damping (``tests/field/test_runup.py``, and
``docs/runup.md``'s table: 5, 20 and 60 rpm/s, both modes, 0.42 to 8 %; the bias was up
to 2.1 times ``alpha / (zeta w_n^2)``)."""
MAX_BIAS = 0.01
"""A mode whose sweep bias bound exceeds this fraction is said: run up slower."""
MIN_BLOCKS = 20
"""Fewer blocks than this in a support's curve: too short a run-up to read."""
MIN_SPAN = 0.3
"""A run-up's speeds must span this fraction of its top speed (else: one speed)."""
BACKWARDS = 0.02
"""A block slower than the fastest before it by this fraction of the span (a run-up;
faster than the slowest before it, a coast-down): the speed went backwards."""


@dataclass(frozen=True)
class SupportCurve:
    """One support's order-tracked 1x: block speeds [rad/s], 1x acceleration [m/s^2],
    its standard error per component [m/s^2], and the resonances its shape shows."""

    support: int
    omega_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    se_m_s2: np.ndarray
    resonances: tuple[Resonance, ...]


@dataclass(frozen=True)
class Margin:
    """The balancing speed against one fitted mode: its amplification factor ``1 / (2
    zeta)``, the margin the speed has and the one API 684 asks [fractions of the balancing
    speed], and whether the mode lies below the speed."""

    omega_rad_s: float
    amplification: float
    margin: float
    required: float
    below: bool


@dataclass(frozen=True)
class RunupAnalysis:
    """A run-up's (or coast-down's) resonances, the model's modes and the margins."""

    direction: str
    sweep_rad_s2: float
    omega_range_rad_s: tuple[float, float]
    revs_per_block: int
    curves: tuple[SupportCurve, ...]
    modes: ModalFit | None
    sweep_bias: tuple[float, ...]
    model_omega_rad_s: tuple[float, ...]
    model_zeta: tuple[float, ...]
    balancing_omega_rad_s: float
    margins: tuple[Margin, ...]
    warnings: tuple[str, ...]


def _lost_marks(s: NodeStream) -> list[tuple[float, float]]:
    """The speeds [rad/s] before and after each gap in the node's reference edges (a
    revolution without an edge) in the segment the curve is read from."""
    _, _, pos, rev = node_segment(s)
    assert s.rate_hz is not None
    gaps = np.flatnonzero(np.diff(rev) > 1)
    out = []
    for g in gaps:
        if g < 1 or g + 2 >= len(pos):
            continue
        before = 2 * math.pi / (pos[g] - pos[g - 1]) * s.rate_hz
        after = 2 * math.pi / (pos[g + 2] - pos[g + 1]) * s.rate_hz
        out.append((min(before, after), max(before, after)))
    return out


def _curve(s: NodeStream, support: int, gamma_rad: float, warn: list[str]) -> SupportCurve:
    """One support's curve, ordered by speed, the blocks about a lost mark left out."""
    w, A, se = track_1x(s, gamma_rad, REVS_PER_BLOCK)
    keep = np.ones(len(w), bool)
    for lo, hi in _lost_marks(s):
        out = (w >= 0.98 * lo) & (w <= 1.02 * hi)
        keep &= ~out
        warn.append(f"support {support}: the reference mark was lost between "
                    f"{lo * 30 / math.pi:.0f} and {hi * 30 / math.pi:.0f} rpm: "
                    f"{int(np.count_nonzero(out))} block(s) there left out")  # fmt: skip
    w, A, se = w[keep], A[keep], se[keep]
    if len(w) < MIN_BLOCKS:
        raise MeasurementError(f"support {support}: a run-up too short to read: {len(w)} "
                               f"blocks of {REVS_PER_BLOCK} revolutions, {MIN_BLOCKS} at "
                               "least")  # fmt: skip
    order = np.argsort(w, kind="stable")
    w, A, se = w[order], A[order], se[order]
    return SupportCurve(support, w, A, se, tuple(resonances(w, response_shape(w, A))))


def _direction(w_blocks: np.ndarray) -> str:
    """``run-up`` or ``coast-down`` of the blocks' speeds in time order; refused when they
    span one speed or go backwards."""
    top, low = float(w_blocks.max()), float(w_blocks.min())
    span = top - low
    if span < MIN_SPAN * top:
        raise MeasurementError(f"one speed, not a run-up: {low * 30 / math.pi:.0f} to "
                               f"{top * 30 / math.pi:.0f} rpm ({span / top:.0%} of the top "
                               f"speed; a run-up spans {MIN_SPAN:.0%} at least)")  # fmt: skip
    up = float(w_blocks[-1]) > float(w_blocks[0])
    ahead = np.maximum.accumulate(w_blocks) if up else np.minimum.accumulate(w_blocks)
    back = np.abs(ahead - w_blocks) > BACKWARDS * span
    if back.any():
        k = int(np.argmax(back))
        raise MeasurementError(f"the speed goes backwards at {w_blocks[k] * 30 / math.pi:.0f} "
                               f"rpm (block {k + 1} of {len(w_blocks)}): a run-up or a "
                               "coast-down is read one way only")  # fmt: skip
    return "run-up" if up else "coast-down"


def _sweep(w_blocks: np.ndarray) -> float:
    """The sweep [rad/s^2]: the slope of the blocks' speeds against their times (each block
    one revolution: ``t = cumsum(2 pi / w)``) between :data:`EDGE` and 97 % of the top."""
    t = np.cumsum(2 * math.pi * REVS_PER_BLOCK / np.maximum(w_blocks, 1e-9))
    top = float(w_blocks.max())
    band = (w_blocks >= EDGE * top) & (w_blocks <= 0.97 * top)
    if np.count_nonzero(band) < 3:
        return 0.0
    return float(np.polyfit(t[band], w_blocks[band], 1)[0])


def _fit(curves: tuple[SupportCurve, ...], n_modes: int) -> ModalFit | None:
    """The modes fitted to both supports' shapes at once, on support 1's speeds between
    :data:`EDGE` and 97 % of the top (support 2's curve interpolated to them)."""
    c1 = curves[0]
    top = float(c1.omega_rad_s[-1])
    keep = (c1.omega_rad_s >= EDGE * top) & (c1.omega_rad_s <= 0.97 * top)
    w = c1.omega_rad_s[keep]
    shapes = []
    for c in curves:
        G, se = response_shape(c.omega_rad_s, c.accel_m_s2), c.se_m_s2 / c.omega_rad_s**4
        Gw = np.interp(w, c.omega_rad_s, G.real) + 1j * np.interp(w, c.omega_rad_s, G.imag)
        shapes.append((Gw, np.maximum(np.interp(w, c.omega_rad_s, se), 1e-300)))
    return modal_fit(w, shapes, n_modes)


def analyse_runup(
    streams: RunStreams, cfg: Config, p: StandParameters, balancing_rpm: float | None = None
) -> RunupAnalysis:
    """The run-up of ``streams`` read with the configuration ``cfg`` (its stand model
    ``p``); ``balancing_rpm`` the speed whose margins are asked (default the run's top).

    Raises
    ------
    MeasurementError
        A support cannot be tracked, the run is too short, of one speed or goes backwards.
    """
    if set(streams.nodes) != {1, 2}:
        raise MeasurementError(f"a run-up needs both supports' nodes, got {sorted(streams.nodes)}")
    gamma = math.radians(cfg.stand.reference_angle_deg)
    warn: list[str] = []
    timed = track_1x(streams.nodes[1], gamma, REVS_PER_BLOCK)[0]
    direction = _direction(timed)
    curves = tuple(_curve(streams.nodes[i], i, gamma, warn) for i in (1, 2))
    sweep = _sweep(timed)
    wn_model, zeta_model = model_modes(p)
    lo = max(float(c.omega_rad_s[0]) for c in curves)
    hi = min(float(c.omega_rad_s[-1]) for c in curves)
    w_bal = (balancing_rpm or hi * 30 / math.pi) * math.pi / 30
    fit = _fit(curves, max(len(wn_model), 1))
    bias: tuple[float, ...] = ()
    margins = []
    if fit is None:
        warn.append("too few points for the modal fit: the resonances are the peaks' only")
    else:
        bias = tuple(SWEEP_BIAS * abs(sweep) / (z * w * w)
                     for w, z in zip(fit.omega_rad_s, fit.zeta, strict=True))  # fmt: skip
        for w, z, b in zip(fit.omega_rad_s, fit.zeta, bias, strict=True):
            margins.append(_margin(w, z, w_bal, warn))
            if b > MAX_BIAS:
                slower = MAX_BIAS / b * abs(sweep) * 30 / math.pi
                warn.append(f"the sweep ({abs(sweep) * 30 / math.pi:.1f} rpm/s) may read the "
                            f"mode at {w * 30 / math.pi:.0f} rpm up to {b:.1%} high: run up "
                            f"at {slower:.1f} rpm/s at most for 1 %")  # fmt: skip
    if len(wn_model) and w_bal < float(wn_model.max()):
        warn.append(f"the balancing speed {w_bal * 30 / math.pi:.0f} rpm is below the supports' "
                    f"resonance at {float(wn_model.max()) * 30 / math.pi:.0f} rpm (the model's):"
                    " a soft-bearing stand measures above its supports' resonances")  # fmt: skip
    return RunupAnalysis(
        direction=direction, sweep_rad_s2=sweep, omega_range_rad_s=(lo, hi),
        revs_per_block=REVS_PER_BLOCK, curves=curves, modes=fit, sweep_bias=bias,
        model_omega_rad_s=tuple(float(x) for x in wn_model),
        model_zeta=tuple(float(x) for x in zeta_model), balancing_omega_rad_s=w_bal,
        margins=tuple(margins), warnings=tuple(warn),
    )  # fmt: skip


def _margin(w: float, zeta: float, w_bal: float, warn: list[str]) -> Margin:
    """The balancing speed ``w_bal`` against the mode ``w``, ``zeta`` (said when short)."""
    af = 1.0 / (2.0 * max(zeta, 1e-12))
    below = w < w_bal
    margin = abs(w_bal - w) / w_bal
    need = separation_margin_required(af, below)
    if margin < need:
        warn.append(f"the balancing speed {w_bal * 30 / math.pi:.0f} rpm lies {margin:.1%} "
                    f"from the mode at {w * 30 / math.pi:.0f} rpm; API 684 asks {need:.1%} "
                    f"at its amplification factor {af:.1f}")  # fmt: skip
    return Margin(w, af, margin, need, below)
