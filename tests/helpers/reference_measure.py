"""The measuring path as it was before it was chunked: all samples at once (a test oracle).

Why it repeats the gate, the fit and the inverse: the product measures in chunks
(:mod:`stand.measuring.passes`, bounded memory) and forks node 2 beside
(:mod:`stand.process.beside`); this oracle does neither, so that
``tests/measuring/test_chunked.py`` can show the
product's answer is the whole-array answer to rounding.  It may go when those
tests compare against another independent path (a second implementation of the
chunked sums, or stored answers of the shipped scenes that the golden tests keep).
Kept verbatim (but for the stream accessors).  Original docstring:

From per-node streams to the unbalance, with a 95 % interval: the one measuring path.

Every path that computes unbalance (offline ``stand solve``, the live
measurement, the simulated stand) goes through :func:`measure`:

1. **gate** (:func:`steady_window`): the part of the run where the speed is
   steady and the supports have settled;
2. **1x phasor per support** (:func:`stand.core.dsp.fit_1x`) over that
   window, with its covariance;
3. **inverse** (:func:`stand.core.solve_unbalance`), the covariance
   propagated to each plane's unbalance, and each plane's 95 % radius.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from stand.core import Diagnostic, StandParameters, UnbalanceSolution, solve_unbalance
from stand.core.dsp import Phasor, fit_1x, radius_factor, shaft_angle
from stand.drivers import NodeStream, RunStreams
from stand.errors import MeasurementError

SPEED_TOLERANCE = 0.03
"""A revolution is at steady speed within 3 % of the steady part's median."""
BLOCK_REVS = 8
"""Revolutions per block when checking that the supports have settled."""
SETTLED = 0.02
"""A block agrees with the settled response within 2 % (or 4 standard errors).  A speed
ripple moves the 1x amplitude quasi-steadily by about its own size; a run-up's transient
decays through 2 % within a few damping times, and what is left averages out."""
HARMONIC_WARN = 0.10
"""3x above 10 % of 1x draws a warning: linear supports make almost none."""
SCATTER_FLOOR = 1e-3
"""Block scatter under 0.1 % of the 1x reading is never flagged."""
SCATTER_LIMIT = 4.0
"""Blocks scattering over 4 times the variance their noise explains (2 in rms) mean
something moves the 1x reading: a neighbour within the 1x bin, unsteady conditions."""
MIN_REVS = 30
"""A steady, settled window shorter than this many revolutions draws a warning."""


@dataclass(frozen=True)
class Window:
    """The gated part of one node's run, in its own sample positions."""

    start: float
    end: float
    revolutions: int
    settled_from: float


@dataclass(frozen=True)
class Measurement:
    """The outcome of one measurement.

    Attributes
    ----------
    supports : list of Phasor
        Node 1 then node 2.
    solution : UnbalanceSolution
        Unbalances, covariance, conditioning, diagnostics.
    radius95_kg_m : ndarray, shape (2,)
        Radius of each plane's 95 % circle around its unbalance [kg m].
    radius_m : tuple of float
        Correction radii R1, R2 [m].
    omega_rad_s : float
        Mean speed over the window [rad/s].
    windows : list of Window
    warnings : list of Diagnostic
    """

    supports: list[Phasor]
    solution: UnbalanceSolution
    radius95_kg_m: np.ndarray
    radius_m: tuple[float, float]
    omega_rad_s: float
    windows: list[Window]
    warnings: list[Diagnostic] = field(default_factory=list)


def _segment(s: NodeStream) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The node's longest clock segment: sample index, accel, edge positions and revs."""
    if s.accel_m_s2 is None:
        raise MeasurementError(f"node {s.node}: no STATUS, its samples cannot be scaled")
    if len(s.accel_m_s2) == 0:
        raise MeasurementError(
            f"node {s.node}: all {s.samples} samples are invalid (count -32768: sensor fault "
            "or overrange)"
            if s.samples
            else f"node {s.node}: no samples, only "
            f"{s.status_frames} STATUS and {s.marks} MARK frames"
        )
    if len(s.mark_segment) == 0:
        raise MeasurementError(
            f"node {s.node}: no reference edges: is the reference sensor "
            "wired and the mark passing it?"
        )
    seg = int(np.bincount(s.mark_segment).argmax())
    m = s.mark_segment == seg
    keep = s.segment == seg
    accel = s.accel_m_s2
    assert accel is not None
    return s.index[keep], accel[keep], s.mark_position[m], s.mark_rev[m]


def block_fits(
    theta: np.ndarray, accel: np.ndarray, at: np.ndarray, edges: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least-squares 1x of every block between consecutive ``edges`` (sample positions).

    Each block is fitted on ``cos theta, sin theta, 1`` over the samples it
    has (lost ones simply absent), all blocks at once from cumulative sums.

    Returns
    -------
    A : ndarray of complex
        The blocks' 1x phasors.
    n : ndarray
        Samples per block.
    var : ndarray
        Residual variance per sample in each block (noise, plus 2x and 3x:
        conservative).
    """
    cut = np.searchsorted(at, edges)
    lo, hi = int(cut[0]), int(cut[-1])
    th, a = theta[lo:hi], accel[lo:hi]
    c, s = np.cos(th), np.sin(th)
    starts = cut[:-1] - lo
    n = np.diff(cut).astype(float)

    def sums(x: np.ndarray) -> np.ndarray:  # per block, in one pass
        out = np.add.reduceat(x, starts) if len(x) else np.zeros(len(starts))
        return np.where(n > 0, out, 0.0)

    ac, as_ = a * c, a * s
    cc, cs = sums(c * c), sums(c * s)
    ss = n - cc
    c1, s1, a1 = sums(c), sums(s), sums(a)
    aa = sums(a * a)
    ac, as_ = sums(ac), sums(as_)
    M = np.stack(
        [np.stack([cc, cs, c1], -1), np.stack([cs, ss, s1], -1), np.stack([c1, s1, n], -1)], -2
    )  # (blocks, 3, 3)
    rhs = np.stack([ac, as_, a1], -1)
    ok = n >= 8
    coef = np.zeros((len(n), 3))
    coef[ok] = np.linalg.solve(M[ok], rhs[ok][..., None])[..., 0]
    resid = aa - np.einsum("bi,bi->b", coef, rhs)  # sum r^2 = sum a^2 - coef . X^T a
    var = np.where(ok, np.maximum(resid, 0) / np.maximum(n - 3, 1), np.inf)
    return coef[:, 0] - 1j * coef[:, 1], n, var


def _std(ph: Phasor) -> float:
    """Standard error of the phasor along its worst axis [m/s^2]."""
    return math.sqrt(float(np.max(np.linalg.eigvalsh(ph.cov_m2_s4))))


def steady_window(
    theta: np.ndarray,
    omega: np.ndarray,
    accel: np.ndarray,
    at: np.ndarray,
    pos: np.ndarray,
    rev: np.ndarray,
) -> tuple[tuple[int, int], list[str]]:
    """The longest run of steady-speed revolutions, from where the supports have settled.

    Parameters are one node's samples between its first and last edge: shaft
    angle, speed, acceleration and sample position ``at``; and its edges.
    Returns the edges ``(first, last)`` that bound the window.

    Speed steady: each revolution within :data:`SPEED_TOLERANCE` of the
    median.  Settled: blocks of :data:`BLOCK_REVS` revolutions are fitted on
    their own; the window starts at the first block from which every block's
    1x agrees with the last half's to within 4 of its standard errors, or
    :data:`SETTLED`, or 3 times the scatter of the last half's blocks (a beat
    with a neighbour near 1x is not a transient).
    """
    notes: list[str] = []
    if len(pos) < 3:
        raise MeasurementError(f"only {len(pos)} reference edges: need at least 3")
    period = np.diff(pos) / np.maximum(np.diff(rev), 1)  # samples per revolution
    speed = 1.0 / period
    steady = np.abs(speed / np.median(speed) - 1) < SPEED_TOLERANCE
    best: tuple[int, int] = (0, 0)
    start: int | None = None
    for k, ok in enumerate([*steady.tolist(), False]):  # revolution k: edges k .. k+1
        if ok and start is None:
            start = k
        elif not ok and start is not None:
            if k - start > best[1] - best[0]:
                best = (start, k)
            start = None
    a, b = best  # revolutions a .. b-1, edges a .. b
    if b - a < 2:
        raise MeasurementError("the speed is never steady for two revolutions in a row")
    if a > 0 or b < len(steady):
        notes.append(f"speed steady over revolutions {a}..{b} of {len(steady)}")
    settled = a
    n_blocks = (b - a) // BLOCK_REVS
    if n_blocks >= 4:
        edges = pos[a + BLOCK_REVS * np.arange(n_blocks + 1)]
        A_blocks, n, var = block_fits(theta, accel, at, edges)
        std = np.sqrt(2 * var / np.maximum(n, 1))  # per component of each block's 1x
        tail = slice(n_blocks // 2, n_blocks)
        A_tail = np.sum(A_blocks[tail] * n[tail]) / np.sum(n[tail])
        # a decaying transient leaves a tight tail; a beat (a neighbour near 1x) does not:
        # blocks are unsettled only if they stand out from the tail's own scatter
        spread = float(np.sqrt(np.mean(np.abs(A_blocks[tail] - A_tail) ** 2)))
        ok = np.abs(A_blocks - A_tail) <= np.maximum.reduce(
            [4 * std, np.full(n_blocks, SETTLED * abs(A_tail)), np.full(n_blocks, 3 * spread)]
        )
        first_good = n_blocks
        for k in range(n_blocks - 1, -1, -1):
            if not ok[k]:
                break
            first_good = k
        settled = a + first_good * BLOCK_REVS
        if first_good > 0:
            notes.append(f"supports settled after {first_good * BLOCK_REVS} revolutions")
    return (settled, b), notes


def block_scatter(
    theta: np.ndarray, accel: np.ndarray, at: np.ndarray, pos: np.ndarray, noise: float
) -> float:
    """How much blocks of whole revolutions scatter, against what the noise explains.

    The window is cut at every :data:`BLOCK_REVS`-th edge; each block's 1x is
    fitted (:func:`block_fits`).  Returns the scatter of the block values around their mean
    over its expectation from ``noise`` (about 1 when only noise moves them;
    0 when there are fewer than 3 blocks, which cannot tell).
    """
    n_blocks = (len(pos) - 1) // BLOCK_REVS
    if n_blocks < 3 or noise <= 0:
        return 0.0
    A, n, _ = block_fits(theta, accel, at, pos[::BLOCK_REVS][: n_blocks + 1])
    mean = np.sum(A * n) / np.sum(n)
    dev2 = np.abs(A - mean) ** 2
    if np.sqrt(np.mean(dev2)) < SCATTER_FLOOR * abs(mean):
        return 0.0  # immaterial, however many standard errors it is
    expected = 4 * noise**2 / np.maximum(n, 1)  # E|A_b - A|^2 from noise: 2 sigma^2/n per part
    return float(np.sum(dev2 / expected) / (n_blocks - 1))


def measure(
    streams: RunStreams,
    p: StandParameters,
    *,
    reference_angle_deg: float = 0.0,
    taper: bool = False,
    gate: bool = True,
    sensor_gain: tuple[float, float] = (1.0, 1.0),
    sensor_delay_s: tuple[float, float] = (0.0, 0.0),
) -> Measurement:
    """The unbalance of both planes from a run's streams (nodes 1 and 2).

    Raises
    ------
    MeasurementError
        A node is missing, unscaled, or without reference edges.
    """
    warnings: list[Diagnostic] = []
    supports: list[Phasor] = []
    windows: list[Window] = []
    gamma = math.radians(reference_angle_deg)
    for node in (1, 2):
        s = streams.nodes.get(node)
        if s is None:
            raise MeasurementError(
                f"node {node} sent nothing: need nodes 1 and 2 (one per "
                f"support), got {sorted(streams.nodes) or 'none'}"
            )
        index, accel, pos, rev = _segment(s)
        assert s.rate_hz is not None
        inside, th, w = shaft_angle(index, pos, rev, gamma)  # once, for the gate and the fit
        at, acc = index[inside], accel[inside]
        e0, e1 = 0, len(pos) - 1
        if gate:
            try:
                (e0, e1), notes = steady_window(th, w, acc, at, pos, rev)
            except MeasurementError as exc:
                raise MeasurementError(f"node {node}: {exc}") from None
            for note in notes:
                warnings.append(Diagnostic("gate", f"node {node}: {note}", 0.0))
        window = Window(
            start=float(pos[e0]),
            end=float(pos[e1]),
            revolutions=int(rev[e1] - rev[e0]),
            settled_from=float(pos[e0]),
        )
        if window.revolutions < MIN_REVS:
            warnings.append(
                Diagnostic(
                    "short_window",
                    f"node {node}: only {window.revolutions} steady, settled revolutions "
                    f"(want {MIN_REVS} or more): measure longer",
                    float(window.revolutions),
                )
            )
        i0, i1 = np.searchsorted(at, [pos[e0], pos[e1]], side="left")
        i1 = int(np.searchsorted(at, pos[e1], side="right"))
        ph = fit_1x(th[i0:i1], acc[i0:i1], w[i0:i1], rate_hz=s.rate_hz, taper=taper)
        k = node - 1
        if sensor_gain[k] != 1.0 or sensor_delay_s[k] != 0.0:
            # the node reads gain * a(t - delay): the support's own phasor is A / (g e^{-i w d})
            turn = sensor_gain[k] * np.exp(-1j * ph.omega_ref_rad_s * sensor_delay_s[k])
            R = np.array([[turn.real, -turn.imag], [turn.imag, turn.real]]) / abs(turn) ** 2
            ph = replace(ph, A_m_s2=complex(ph.A_m_s2 / turn), cov_m2_s4=R.T @ ph.cov_m2_s4 @ R)
        ratio = block_scatter(th[i0:i1], acc[i0:i1], at[i0:i1], pos[e0 : e1 + 1], ph.noise_m_s2)
        if ratio > SCATTER_LIMIT:
            warnings.append(
                Diagnostic(
                    "unsteady_1x",
                    f"node {node}: the 1x reading wanders between blocks of {BLOCK_REVS} "
                    f"revolutions {math.sqrt(ratio):.1f} times more than the noise explains: a "
                    "vibration close to 1x (a neighbouring machine beating with it) or unsteady "
                    "conditions; the interval is widened to match; measure longer, or --taper",
                    ratio,
                )
            )
            ph = replace(ph, cov_m2_s4=ph.cov_m2_s4 * ratio)
        odd = abs(ph.harmonics_m_s2.get(3, 0j)) / max(abs(ph.A_m_s2), 1e-300)
        if odd > HARMONIC_WARN:
            warnings.append(
                Diagnostic(
                    "strong_3x",
                    f"node {node}: 3x is {100 * odd:.0f} % of 1x: the supports may not be linear "
                    "(dry friction, a clearance) or the drive is misaligned; the model assumes "
                    "linear supports, so the result may be off",
                    odd,
                )
            )
        supports.append(ph)
        windows.append(window)
    omega = 0.5 * (supports[0].omega_ref_rad_s + supports[1].omega_ref_rad_s)
    A = np.array([supports[0].A_m_s2, supports[1].A_m_s2])
    cov = np.zeros((4, 4))
    cov[:2, :2] = supports[0].cov_m2_s4
    cov[2:, 2:] = supports[1].cov_m2_s4
    sol = solve_unbalance(p, omega, A, cov)
    dof = min(ph.noise_dof for ph in supports)
    cov_U = np.asarray(sol.cov_U).real if sol.cov_U is not None else np.zeros((4, 4))
    radius = np.array(
        [
            radius_factor(dof)
            * math.sqrt(
                float(np.max(np.linalg.eigvalsh(cov_U[2 * i : 2 * i + 2, 2 * i : 2 * i + 2])))
            )
            for i in range(2)
        ]
    )
    warnings.extend(sol.diagnostics)
    return Measurement(
        supports=supports,
        solution=sol,
        radius95_kg_m=radius,
        radius_m=(p.R1, p.R2),
        omega_rad_s=float(omega),
        windows=windows,
        warnings=warnings,
    )
