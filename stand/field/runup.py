"""A recorded run-up or coast-down read as the stand's frequency response: each support's
1x order-tracked block by block (:func:`stand.measuring.track.track_1x`), the resonances
its response shape shows (:mod:`stand.core.resonance`): the modes fitted as the sweep
gives them (a run-up read as steady states reads each mode high by about its decay time
times the sweep), set against the stand model's own, and the balancing speed's separation
margin from each.

What the data cannot carry is said, never passed on: a run too short or of one speed, a
speed that goes backwards, a reference mark lost mid-sweep (the revolutions without an
edge are left out of the fit), a fit that leaves more than the points' noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from stand.config import Config
from stand.core.dsp import radius_factor
from stand.core.model import StandParameters
from stand.core.resonance import (
    ModalFit,
    Resonance,
    modal_fit,
    model_modes,
    resonances,
    response_shape,
    separation_margin_required,
    swept_fit,
)
from stand.drivers.streams import NodeStream, RunStreams
from stand.errors import MeasurementError
from stand.measuring.gate import node_segment
from stand.measuring.track import track_1x, track_1x_vk, track_orders

REVS_PER_BLOCK = 1
"""Revolutions in each order-tracking block: the curve's resolution in speed."""
EDGE = 0.3
"""The modal fit reads the curve above this fraction of its top speed (below, the 1x is
a few counts: ``A ~ w^4`` far below the resonances) and below 97 % of it (the hold)."""
MIN_BLOCKS = 20
"""Fewer blocks than this in a support's curve: too short a run-up to read."""
MIN_SPAN = 0.3
"""A run-up's speeds must span this fraction of its top speed (else: one speed)."""
BACKWARDS = 0.02
"""A block slower than the fastest before it by this fraction of the span (a run-up;
faster than the slowest before it, a coast-down): the speed went backwards."""
MAX_CHI = 3.0
"""A fit that leaves more than this many times the points' own noise is said: the stand
did not behave as a linear one with these modes (a loose part, a rub, a wrong count)."""


@dataclass(frozen=True)
class SupportCurve:
    """One support's order-tracked 1x: block speeds [rad/s], 1x acceleration [m/s^2],
    its standard error per component [m/s^2], and the resonances its shape shows; its 2x
    acceleration phasor at the same blocks [m/s^2] and that one's standard error (empty
    where not tracked)."""

    support: int
    omega_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    se_m_s2: np.ndarray
    resonances: tuple[Resonance, ...]
    x2_m_s2: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    x2_se_m_s2: np.ndarray = field(default_factory=lambda: np.zeros(0))


@dataclass(frozen=True)
class Waterfall:
    """One support's spectrum against speed: the speed at each slice's middle [rad/s], the
    frequencies [Hz] and the amplitude spectrum of each slice [m/s^2] (slices, freqs)."""

    support: int
    omega_rad_s: np.ndarray
    freq_hz: np.ndarray
    amplitude_m_s2: np.ndarray


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
class SecondOrder:
    """One support's 2x: its largest amplitude over the run [m/s^2] with that block's
    95 % radius and speed [rad/s]; at the balancing speed (the blocks within
    :data:`AT_SPEED` of it, their phasors averaged) its phasor [m/s^2], 95 % radius, the
    1x there and how many blocks; ``None`` there when the run has no block that close."""

    support: int
    peak_m_s2: float
    peak_radius95_m_s2: float
    peak_omega_rad_s: float
    at_balancing_m_s2: complex | None
    at_balancing_radius95_m_s2: float | None
    one_x_at_balancing_m_s2: float | None
    blocks_at_balancing: int


AT_SPEED = 0.01
"""A block within this fraction of the balancing speed counts as at it (the 2x there)."""


def second_order(c: SupportCurve, w_bal: float) -> SecondOrder:
    """The 2x of the support's curve ``c`` over the run and at the speed ``w_bal``
    [rad/s] (see :class:`SecondOrder`; radii :func:`stand.core.dsp.radius_factor` at
    infinite degrees of freedom: each block holds hundreds of samples)."""
    k95 = radius_factor(math.inf)
    amp = np.abs(c.x2_m_s2)
    k = int(np.argmax(amp))
    near = np.abs(c.omega_rad_s - w_bal) <= AT_SPEED * w_bal
    n = int(np.count_nonzero(near))
    if n == 0:
        return SecondOrder(c.support, float(amp[k]), k95 * float(c.x2_se_m_s2[k]),
                           float(c.omega_rad_s[k]), None, None, None, 0)  # fmt: skip
    se = float(np.sqrt(np.sum(c.x2_se_m_s2[near] ** 2))) / n  # the mean's, per component
    return SecondOrder(
        c.support, float(amp[k]), k95 * float(c.x2_se_m_s2[k]), float(c.omega_rad_s[k]),
        complex(np.mean(c.x2_m_s2[near])), k95 * se, float(np.abs(np.mean(c.accel_m_s2[near]))),
        n,
    )  # fmt: skip


@dataclass(frozen=True)
class RunupAnalysis:
    """A run-up's (or coast-down's) resonances, the model's modes and the margins."""

    direction: str
    sweep_rad_s2: float
    omega_range_rad_s: tuple[float, float]
    revs_per_block: int
    curves: tuple[SupportCurve, ...]
    modes: ModalFit | None
    steady: ModalFit | None
    model_omega_rad_s: tuple[float, ...]
    model_zeta: tuple[float, ...]
    balancing_omega_rad_s: float
    margins: tuple[Margin, ...]
    warnings: tuple[str, ...]
    waterfalls: tuple[Waterfall, ...] = ()
    second: tuple[SecondOrder, ...] = ()
    vk_hz: float | None = None


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


def _track(s: NodeStream, gamma_rad: float, vk_hz: float | None) -> tuple[np.ndarray, ...]:
    """The node's 1x per block in time order: by revolution blocks (the 1x alone: its
    least noise), or by the Vold-Kalman filter of ``vk_hz`` averaged over the blocks."""
    if vk_hz is None:
        return track_1x(s, gamma_rad, REVS_PER_BLOCK)
    return track_1x_vk(s, gamma_rad, vk_hz, REVS_PER_BLOCK)


def _curve(
    s: NodeStream,
    support: int,
    gamma_rad: float,
    warn: list[str],
    tracked: tuple[np.ndarray, ...],
    vk_hz: float | None = None,
) -> SupportCurve:
    """One support's curve from its 1x ``tracked`` in time order (:func:`_track`), ordered
    by speed, the blocks about a lost mark left out; its 2x by revolution blocks (with the
    Vold-Kalman filter's 1x: interpolated to its points)."""
    w, A, se = tracked
    wb, (_, (A2, se2)) = track_orders(s, gamma_rad, REVS_PER_BLOCK, (1, 2))
    if vk_hz is not None:
        k = np.argsort(wb, kind="stable")
        A2 = np.interp(w, wb[k], A2[k].real) + 1j * np.interp(w, wb[k], A2[k].imag)
        se2 = np.interp(w, wb[k], se2[k])
    keep = np.ones(len(w), bool)
    for lo, hi in _lost_marks(s):
        out = (w >= 0.98 * lo) & (w <= 1.02 * hi)
        keep &= ~out
        warn.append(f"support {support}: the reference mark was lost between "
                    f"{lo * 30 / math.pi:.0f} and {hi * 30 / math.pi:.0f} rpm: "
                    f"{int(np.count_nonzero(out))} block(s) there left out")  # fmt: skip
    w, A, se, A2, se2 = w[keep], A[keep], se[keep], A2[keep], se2[keep]
    if len(w) < MIN_BLOCKS:
        raise MeasurementError(f"support {support}: a run-up too short to read: {len(w)} "
                               f"blocks of {REVS_PER_BLOCK} revolutions, {MIN_BLOCKS} at "
                               "least")  # fmt: skip
    order = np.argsort(w, kind="stable")
    w, A, se = w[order], A[order], se[order]
    shape = tuple(resonances(w, response_shape(w, A)))
    return SupportCurve(support, w, A, se, shape, A2[order], se2[order])


SLICE_REVS = 16
"""The waterfall's slices last this many revolutions at the run's top speed (Hann
windows, half overlapping): a sixteenth of the top 1x frequency apart, its bins."""


def waterfall(s: NodeStream, support: int) -> Waterfall:
    """The support's amplitude spectrum in slices of :data:`SLICE_REVS` (scipy's
    ``spectrogram``, Hann, half overlapping; the samples of its longest segment taken as
    contiguous: a lost frame is a glitch of a few samples), each slice's speed
    interpolated from the reference edges."""
    from scipy.signal import spectrogram

    lo, hi, pos, rev = node_segment(s)
    assert s.rate_hz is not None
    a = s.accel(lo, hi)
    if len(pos) < 2:
        return Waterfall(support, np.zeros(0), np.zeros(0), np.zeros((0, 0)))
    edge_w = 2 * math.pi * np.diff(rev) / np.diff(pos) * s.rate_hz  # at the edges' middles
    n = max(16, int(SLICE_REVS * 2 * math.pi / float(edge_w.max()) * s.rate_hz))
    if len(a) < n:
        return Waterfall(support, np.zeros(0), np.zeros(0), np.zeros((0, 0)))
    f, t, S = spectrogram(a, fs=s.rate_hz, window="hann", nperseg=n, noverlap=n // 2,
                          scaling="spectrum", mode="magnitude")  # fmt: skip
    middle = float(s.index[lo]) + t * s.rate_hz
    w = np.interp(middle, 0.5 * (pos[1:] + pos[:-1]), edge_w)
    return Waterfall(support, w, f, 2 * S.T)  # one-sided: a sine's amplitude


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


def _covered(w: np.ndarray, c: SupportCurve) -> np.ndarray:
    """Which speeds ``w`` the curve ``c`` has a point within two of its spacings of: none
    about the revolutions a lost mark left out (interpolating across them would invent)."""
    k = np.clip(np.searchsorted(c.omega_rad_s, w), 1, len(c.omega_rad_s) - 1)
    near = np.minimum(np.abs(w - c.omega_rad_s[k - 1]), np.abs(w - c.omega_rad_s[k]))
    covered: np.ndarray = near <= 2 * float(np.median(np.diff(c.omega_rad_s)))
    return covered


def _fits(curves: tuple[SupportCurve, ...], tracked: tuple[np.ndarray, ...], n_modes: int
          ) -> tuple[ModalFit | None, ModalFit | None]:  # fmt: skip
    """The modes as steady states would give them (:func:`modal_fit` on the response
    shapes), then as the sweep gives them (:func:`swept_fit`, started from those): on
    support 1's blocks in time order ``tracked``, between :data:`EDGE` and 97 % of the top,
    the revolutions a lost mark left out of either support kept out; support 2
    interpolated to support 1's speeds."""
    w, A1, se1 = tracked
    top = float(w.max())
    keep = (w >= EDGE * top) & (w <= 0.97 * top) & np.isin(w, curves[0].omega_rad_s)
    accels = [(A1, se1)]
    for c in curves[1:]:
        keep &= _covered(w, c)
        accels.append((np.interp(w, c.omega_rad_s, c.accel_m_s2.real)
                       + 1j * np.interp(w, c.omega_rad_s, c.accel_m_s2.imag),
                       np.interp(w, c.omega_rad_s, c.se_m_s2)))  # fmt: skip
    accels = [(A, np.maximum(se, 1e-12 * float(np.abs(A).max()))) for A, se in accels]
    order = np.argsort(w[keep], kind="stable")
    wk = w[keep][order]
    shapes = [(response_shape(wk, A[keep][order]), se[keep][order] / wk**4) for A, se in accels]
    steady = modal_fit(wk, shapes, n_modes)
    if steady is None or not _finite(steady):
        return None, None
    t = np.concatenate(([0.0], np.cumsum(2 * math.pi * REVS_PER_BLOCK / w)[:-1]))
    swept = swept_fit(w, t, accels, keep, steady)
    return (swept if _finite(swept) else None), steady


def _finite(fit: ModalFit) -> bool:
    """Every figure of ``fit`` finite (a fit that failed numerically is no answer)."""
    return all(math.isfinite(v) for v in (*fit.omega_rad_s, *fit.zeta, fit.chi))


def analyse_runup(
    streams: RunStreams, cfg: Config, p: StandParameters, balancing_rpm: float | None = None,
    vk_hz: float | None = None,
) -> RunupAnalysis:  # fmt: skip
    """The run-up of ``streams`` read with the configuration ``cfg`` (its stand model
    ``p``); ``balancing_rpm`` the speed whose margins are asked (default the run's top);
    ``vk_hz`` the half-power bandwidth [Hz] of a Vold-Kalman filter that tracks the 1x
    (default: revolution blocks).

    Raises
    ------
    MeasurementError
        A support cannot be tracked, the run is too short, of one speed or goes backwards.
    """
    if set(streams.nodes) != {1, 2}:
        raise MeasurementError(f"a run-up needs both supports' nodes, got {sorted(streams.nodes)}")
    gamma = math.radians(cfg.stand.reference_angle_deg)
    warn: list[str] = []
    each = {i: _track(streams.nodes[i], gamma, vk_hz) for i in (1, 2)}  # once a node
    tracked = each[1]
    timed = tracked[0]
    direction = _direction(timed)
    curves = tuple(_curve(streams.nodes[i], i, gamma, warn, each[i], vk_hz) for i in (1, 2))
    sweep = _sweep(timed)
    wn_model, zeta_model = model_modes(p)
    if vk_hz is not None:
        _bandwidth(vk_hz, sweep, wn_model, zeta_model, warn)
    lo = max(float(c.omega_rad_s[0]) for c in curves)
    hi = min(float(c.omega_rad_s[-1]) for c in curves)
    w_bal = (balancing_rpm or hi * 30 / math.pi) * math.pi / 30
    fit, steady = _fits(curves, tracked, max(len(wn_model), 1))
    margins = []
    if fit is None:
        warn.append("no modal fit (too few points, or the fit failed numerically): the "
                    "resonances are the supports' peaks only")  # fmt: skip
    else:
        margins = [_margin(w, z, w_bal, warn) for w, z in zip(fit.omega_rad_s, fit.zeta,
                                                              strict=True)]  # fmt: skip
        if fit.chi > MAX_CHI:
            warn.append(f"the modes fitted leave {fit.chi:.1f} times the points' noise: the "
                        "stand did not respond as a linear one with these modes (a loose "
                        "part, a rub?): read them with care")  # fmt: skip
    if len(wn_model) and w_bal < float(wn_model.max()):
        warn.append(f"the balancing speed {w_bal * 30 / math.pi:.0f} rpm is below the supports' "
                    f"resonance at {float(wn_model.max()) * 30 / math.pi:.0f} rpm (the model's):"
                    " a soft-bearing stand measures above its supports' resonances")  # fmt: skip
    return RunupAnalysis(
        direction=direction, sweep_rad_s2=sweep, omega_range_rad_s=(lo, hi),
        revs_per_block=REVS_PER_BLOCK, curves=curves, modes=fit, steady=steady,
        model_omega_rad_s=tuple(float(x) for x in wn_model),
        model_zeta=tuple(float(x) for x in zeta_model), balancing_omega_rad_s=w_bal,
        margins=tuple(margins), warnings=tuple(warn),
        waterfalls=tuple(waterfall(streams.nodes[i], i) for i in (1, 2)),
        second=tuple(second_order(c, w_bal) for c in curves), vk_hz=vk_hz,
    )  # fmt: skip


def _bandwidth(vk_hz: float, sweep: float, wn: np.ndarray, zeta: np.ndarray,
               warn: list[str]) -> None:  # fmt: skip
    """Said when the filter is too narrow for the sweep: crossing a mode's half-power band
    ``2 zeta f_n`` at the sweep [Hz/s] takes ``T``, and a filter narrower than ``1 / T``
    smooths the peak (lower, later, wider)."""
    for w, z in zip(wn, zeta, strict=True):
        need = abs(sweep) / (2 * math.pi) / max(2 * z * w / (2 * math.pi), 1e-12)
        if vk_hz < need:
            warn.append(f"the Vold-Kalman filter's {vk_hz:g} Hz is narrower than the "
                        f"{need:.2f} Hz at which the sweep crosses the mode at "
                        f"{w * 30 / math.pi:.0f} rpm (its half-power band in {1 / need:.1f} s):"
                        " the peak is smoothed; widen the filter")  # fmt: skip


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
