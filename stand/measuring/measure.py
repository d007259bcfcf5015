"""From per-node streams to the unbalance, with a 95 % interval: the one measuring path.

Every path that computes unbalance (offline ``stand solve``, the live
measurement, the simulated stand) goes through :func:`measure`:

1. **gate** (:func:`stand.measuring.passes.steady_revolutions`,
   :func:`stand.measuring.passes.settled_block`): the part of the run where the speed
   is steady and the supports have settled;
2. **1x phasor per support** over that window, with its covariance: the
   estimator of :func:`stand.core.dsp.fit_1x`, built from sums
   (:mod:`stand.core.fitsums`) in chunks (:func:`stand.measuring.passes.node_phasor`);
3. **inverse** (:func:`stand.core.solve_unbalance`), the covariance
   propagated to each plane's unbalance, and each plane's 95 % radius.

Long runs are read in chunks, in bounded memory: see :mod:`stand.measuring.passes`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from stand.core import Diagnostic, StandParameters, UnbalanceSolution, rad_s_to_rpm, solve_unbalance
from stand.core.beam import BeamRotor, solve_beam
from stand.core.dsp import Phasor, radius95, sensor_response
from stand.core.influence import InfluenceMap, solve_influence
from stand.core.nonlinear import Nonlinearity, detect
from stand.drivers.streams import SUPPORT_NODES, RunStreams
from stand.errors import MeasurementError, SensorFaultError
from stand.i18n.words import said
from stand.measuring.gate import (
    BLOCK_REVS,
    MIN_REVS,
    Window,
    block_drift,
    block_scatter,
    check_saturation,
    check_timing,
)
from stand.measuring.passes import NodeFit, node_phasor
from stand.process import Beside, can_fork

__all__ = ["BLOCK_REVS", "MIN_REVS", "Measurement", "Window", "measure"]

CLOCK_TOLERANCE = 1e-3
"""Two nodes' speeds of one shaft agree within 0.1 % (crystal clocks are good to 1e-4)."""
HARMONIC_WARN = 0.10
"""3x above 10 % of 1x draws a warning: linear supports make almost none."""
SCATTER_LIMIT = 4.0
"""Blocks scattering over 4 times the variance their noise explains (2 in rms) mean
something moves the 1x reading: a neighbour within the 1x bin, unsteady conditions."""


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
    tooling : stand.solve.tooling.Tooling or None
        The tooling whose unbalance was subtracted (:mod:`stand.solve.tooling`).
    cov_A_m2_s4 : ndarray, shape (4, 4), or None
        Covariance of ``(Re A1, Im A1, Re A2, Im A2)`` [m^2/s^4], the reference
        edges' common jitter included.
    """

    supports: list[Phasor]
    solution: UnbalanceSolution
    radius95_kg_m: np.ndarray
    radius_m: tuple[float, float]
    omega_rad_s: float
    windows: list[Window]
    warnings: list[Diagnostic] = field(default_factory=list)
    cov_A_m2_s4: np.ndarray | None = None
    tooling: Any = None
    """The tooling compensation subtracted from the unbalance, if any
    (:class:`stand.solve.tooling.Tooling`)."""
    fits: tuple[NodeFit, ...] | None = field(default=None, repr=False, compare=False)
    """What a live update extends, node 1 then node 2 (:mod:`stand.measuring.live_fit`); None when
    the fit was tapered."""


NONLINEAR_WIDEN = 1.5
"""A nonlinear support's estimated error widens the 95 % radius 1.5 times over: the
estimate is a square wave's (friction and clearance scenes: within 10 % of the true
error; the rest covers the smoothing and what the model leaves out)."""


def _nonlinear_supports(
    p: StandParameters, omega: float, supports: list[Phasor], U: np.ndarray
) -> Nonlinearity | None:
    """Dry friction or a clearance, from the 3x (:func:`stand.core.nonlinear.detect`)."""
    five = all(5 in ph.harmonics_m_s2 for ph in supports)  # 4x is not measured: a 0 row
    A = np.array(
        [[ph.A_m_s2 for ph in supports]]
        + [
            [ph.harmonics_m_s2.get(k, 0j) for ph in supports]
            for k in (2, 3, 4, 5)[: 4 if five else 2]
        ]
    )
    cov3 = np.zeros((4, 4))  # the noise at 3x is taken as at 1x (white)
    cov3[:2, :2], cov3[2:, 2:] = supports[0].cov_m2_s4, supports[1].cov_m2_s4
    return detect(p, omega, A, cov3, U)


def _nonlinear_note(found: Nonlinearity, p: StandParameters) -> Diagnostic:
    f = found.fit
    if f.kind == "friction":
        what = said("dry friction of {f1} N and {f2} N at supports 1 and 2",
                    f1=f"{f.size_n[0]:.2g}", f2=f"{f.size_n[1]:.2g}")  # fmt: skip
        cure = said("free the supports (dry friction)")
    else:
        gaps = f.size_n / np.array([p.C1, p.C2]) * 1e6
        what = said("a clearance of about {g1} and {g2} micrometres at supports 1 and 2",
                    g1=f"{gaps[0]:.2g}", g2=f"{gaps[1]:.2g}")  # fmt: skip
        cure = said("take up the clearance in the supports")
    d, e = abs(found.dU_kg_m) * 1e6, found.error_deg
    moves = said("{d1} g mm ({e1} deg) in plane 1 and {d2} g mm ({e2} deg) in plane 2",
                 d1=f"{d[0]:.3g}", e1=f"{e[0]:.1f}",
                 d2=f"{d[1]:.3g}", e2=f"{e[1]:.1f}")  # fmt: skip
    return Diagnostic("nonlinear_support", said(
        "the supports do not move linearly: their 3x and 5x are what {what} makes; it moves the "
        "answer by about {moves}; the interval is widened by {k} times that; {cure} and measure "
        "again", what=what, moves=moves, k=f"{NONLINEAR_WIDEN:g}", cure=cure),
        float(found.error_deg.max()))  # fmt: skip


JITTER_NOTE = 0.1
"""Say so when the edges' jitter widens a support's 95 % radius by more than 10 %."""


def _with_edge_jitter(
    supports: list[Phasor], windows: list[Window]
) -> tuple[list[Phasor], np.ndarray, list[Diagnostic]]:
    """Both supports' phasors with the reference edges' timing jitter in their covariance,
    and the 4x4 covariance of ``(Re A1, Im A1, Re A2, Im A2)``.

    The shaft angle is built from the edges, so an edge off by ``delta_k``
    shifts the angle around it; over a window of ``N`` revolutions the fit
    sees the mean shift, of variance ``sigma_theta^2 / N`` (a simulation of
    the Hermite angle gives 0.93 of that).  The reference is one sensor wired
    to both nodes, so the shift is common: both phasors turn by one angle
    ``epsilon``, ``A -> A e^{-i epsilon}``, adding ``var(epsilon) v v^T`` with
    ``v = (Re iA1, Im iA1, Re iA2, Im iA2)`` (the unbalances then turn together too).
    """
    var = float(np.mean([w.edge_jitter_rad**2 / max(w.revolutions, 1) for w in windows]))
    v = np.array([[-ph.A_m_s2.imag, ph.A_m_s2.real] for ph in supports]).ravel()
    cov = np.zeros((4, 4))
    cov[:2, :2] = supports[0].cov_m2_s4
    cov[2:, 2:] = supports[1].cov_m2_s4
    cov += var * np.outer(v, v)
    out = [
        replace(ph, cov_m2_s4=cov[2 * k : 2 * k + 2, 2 * k : 2 * k + 2])
        for k, ph in enumerate(supports)
    ]
    notes = []
    share = [  # how much wider each support's radius is for the jitter
        math.sqrt(np.trace(new.cov_m2_s4) / max(np.trace(old.cov_m2_s4), 1e-300)) - 1.0
        for old, new in zip(supports, out, strict=True)
    ]
    if var > 0 and max(share) > JITTER_NOTE:
        rms_deg = math.degrees(float(np.mean([w.edge_jitter_rad for w in windows])))
        notes.append(Diagnostic("edge_jitter", said(
            "the reference edges jitter by {deg} deg of shaft angle (rms): the interval is "
            "widened for it; a cleaner reference signal (sensor gap, mark edge) narrows it",
            deg=f"{rms_deg:.2g}"), rms_deg))  # fmt: skip
    return out, cov, notes


def _support(
    node: int,
    s: Any,
    gamma: float,
    taper: bool,
    gate: bool,
    sensor: tuple[float, float],
    bad: str,
) -> tuple[Phasor, Window, list[Diagnostic], NodeFit | None]:
    """One support's 1x phasor from its node's stream: gated and fitted
    (:func:`stand.measuring.passes.node_phasor`), then judged (:func:`judge_support`); its
    window, its warnings and what a live update extends."""
    try:
        check_timing(s)
        check_saturation(s)
        ph, window, blocks, notes, fit = node_phasor(s, gamma, taper, gate)
    except MeasurementError as exc:  # name the node, keep the kind (fault or not yet)
        more = bad if "no samples" in str(exc) or "no reference edges" in str(exc) else ""
        raise type(exc)(f"node {node}: {exc}{more}") from None
    ratio = block_scatter(blocks, ph.noise_m_s2)
    window = replace(window, drift=block_drift(blocks))
    ph, warnings = judge_support(node, ph, window, ratio, sensor)
    if fit is not None:
        fit = replace(fit, scatter=ratio)
    gated = [Diagnostic("gate", said("node {node}: {note}", node=node, note=n)) for n in notes]
    return ph, window, gated + warnings, fit


FORK_SAMPLES = 500_000
"""A node with this many samples or more (about 2 min at 4 kHz) is measured beside the other,
in a forked child (:mod:`stand.process.beside`): below it the fork costs more than it saves."""


def _supports(args: list[tuple[Any, ...]]) -> list[tuple[Phasor, Window, list[Diagnostic], Any]]:
    """:func:`_support` of each node, in order; the second beside the first when both are
    long and the process may fork (the first node's error is raised first, as in order)."""
    if len(args) == 2 and min(a[1].samples for a in args) >= FORK_SAMPLES and can_fork():
        other = Beside(_support, *args[1])
        try:
            first = _support(*args[0])
        except BaseException:
            other.cancel()
            raise
        return [first, other.result()]
    return [_support(*a) for a in args]


def harmonic_ratio(ph: Phasor) -> tuple[float, float]:
    """The 3x amplitude over the 1x, and the least that ratio can be within both readings'
    95 % radii (the 3x read from the same samples in the same noise: the 1x's radius).  A
    ratio of two amplitudes at the noise's level is anything; its lower bound is then 0."""
    r = ph.radius95_m_s2
    h3, a1 = abs(ph.harmonics_m_s2.get(3, 0j)), abs(ph.A_m_s2)
    return h3 / max(a1, 1e-300), max(h3 - r, 0.0) / max(a1 + r, 1e-300)


def judge_support(
    node: int, ph: Phasor, window: Window, ratio: float, sensor: tuple[float, float]
) -> tuple[Phasor, list[Diagnostic]]:
    """A support's raw phasor with the sensor's gain and delay taken out, widened by the
    blocks' scatter ``ratio`` (over the noise's), and the warnings of a short window or a
    strong 3x."""
    warnings: list[Diagnostic] = []
    if window.revolutions < MIN_REVS:
        warnings.append(Diagnostic("short_window", said(
            "node {node}: only {n} steady, settled revolutions (want {want} or more): measure "
            "longer", node=node, n=window.revolutions, want=MIN_REVS),
            float(window.revolutions)))  # fmt: skip
    gain, delay = sensor
    if gain != 1.0 or delay != 0.0:
        # the node reads gain * a(t - delay): the support's own phasor is A / (g e^{-i w d})
        turn = sensor_response(gain, delay, ph.omega_ref_rad_s)
        R = np.array([[turn.real, -turn.imag], [turn.imag, turn.real]]) / abs(turn) ** 2
        ph = replace(ph, A_m_s2=complex(ph.A_m_s2 / turn), cov_m2_s4=R.T @ ph.cov_m2_s4 @ R)
    if ratio > SCATTER_LIMIT:
        warnings.append(Diagnostic("unsteady_1x", said(
            "node {node}: the 1x reading wanders between blocks of {block} revolutions {k} times "
            "more than the noise explains: a vibration close to 1x (a neighbouring machine "
            "beating with it) or unsteady conditions; the interval is widened to match; measure "
            "longer, or --taper", node=node, block=BLOCK_REVS, k=f"{math.sqrt(ratio):.1f}"),
            ratio))  # fmt: skip
        ph = replace(ph, cov_m2_s4=ph.cov_m2_s4 * ratio)
    odd, odd_low = harmonic_ratio(ph)
    # against a real 1x only, and judged with its interval: two noise levels never warn
    if abs(ph.A_m_s2) > ph.radius95_m_s2 and odd_low > HARMONIC_WARN:
        warnings.append(Diagnostic("strong_3x", said(
            "node {node}: 3x is {pct} % of 1x (at least {low} % within the 95 % intervals): the "
            "supports may not be linear (dry friction, a clearance) or the drive is misaligned; "
            "the model assumes linear supports, so the result may be off", node=node,
            pct=f"{100 * odd:.0f}", low=f"{100 * odd_low:.0f}"), odd))  # fmt: skip
    return ph, warnings


def _check_clocks(
    w1: float, w2: float, rates_hz: tuple[float, ...], clock_tolerance: float
) -> None:
    """Both nodes see one shaft: the speeds they measure [rad/s] agree within
    ``clock_tolerance``, else a node's sample rate or clock is wrong (refused)."""
    if abs(w1 / w2 - 1) > clock_tolerance:
        rates = " and ".join(f"{r:g}" for r in rates_hz)
        raise SensorFaultError(
            f"nodes 1 and 2 see one shaft at different speeds: {rad_s_to_rpm(w1):.2f} and "
            f"{rad_s_to_rpm(w2):.2f} rpm ({100 * (w1 / w2 - 1):+.3f} %, tolerance "
            f"+-{100 * clock_tolerance:g} %): a node's sample rate (STATUS says {rates} Hz) "
            "or its clock is wrong"
        )


def measure(
    streams: RunStreams,
    p: StandParameters,
    *,
    reference_angle_deg: float = 0.0,
    taper: bool = False,
    gate: bool = True,
    sensor_gain: tuple[float, float] = (1.0, 1.0),
    sensor_delay_s: tuple[float, float] = (0.0, 0.0),
    clock_tolerance: float = CLOCK_TOLERANCE,
    influence: InfluenceMap | None = None,
    beam: BeamRotor | None = None,
) -> Measurement:
    """The unbalance of both planes from a run's streams (nodes 1 and 2).

    Both nodes see one shaft: the speeds they measure (their edges against
    their own sample clocks) must agree within ``clock_tolerance`` (relative),
    else a node's sample rate or clock is wrong and the run is refused.
    ``influence``: a measured influence matrix takes the stand model's place in
    the inverse (:func:`stand.core.influence.solve_influence`); the model still
    judges the supports' linearity.  ``beam``: the rotor bends, and the flexible
    stand (:func:`stand.core.beam.solve_beam`) inverts instead of the rigid one.

    Raises
    ------
    MeasurementError
        A node is missing, unscaled, or without reference edges.
    """
    warnings: list[Diagnostic] = []
    supports: list[Phasor] = []
    windows: list[Window] = []
    fits: list[NodeFit | None] = []
    gamma = math.radians(reference_angle_deg)
    # frames left out as malformed explain a node with nothing usable: say so beside it
    bad = next((f" ({w.message})" for w in streams.warnings if w.code == "bad_frames"), "")
    for node in SUPPORT_NODES:
        if streams.nodes.get(node) is None:
            raise MeasurementError(
                f"node {node} sent nothing: need nodes 1 and 2 (one per "
                f"support), got {sorted(streams.nodes) or 'none'}{bad}"
            )
    args = [
        (node, streams.nodes[node], gamma, taper, gate, (sensor_gain[k], sensor_delay_s[k]), bad)
        for k, node in enumerate(SUPPORT_NODES)
    ]
    for ph, window, notes, fit in _supports(args):
        warnings.extend(notes)
        supports.append(ph)
        windows.append(window)
        fits.append(fit)
    rates = tuple(float(streams.nodes[n].rate_hz or 0.0) for n in SUPPORT_NODES)
    m = combine(supports, windows, warnings, p, rates, clock_tolerance, influence, beam)
    done = [f for f in fits if f is not None]
    return replace(m, fits=tuple(done) if len(done) == len(fits) else None)


def combine(
    supports: list[Phasor],
    windows: list[Window],
    warnings: list[Diagnostic],
    p: StandParameters,
    rates_hz: tuple[float, ...],
    clock_tolerance: float = CLOCK_TOLERANCE,
    influence: InfluenceMap | None = None,
    beam: BeamRotor | None = None,
) -> Measurement:
    """Both supports' judged phasors (node 1, node 2) to the measurement: their clocks
    compared, the edges' jitter added, inverted (:func:`measure` says how), each plane's
    95 % radius, and the supports' linearity judged from their 3x and 5x."""
    warnings = list(warnings)
    w1, w2 = supports[0].omega_ref_rad_s, supports[1].omega_ref_rad_s
    _check_clocks(w1, w2, rates_hz, clock_tolerance)
    omega = 0.5 * (w1 + w2)
    plain = supports  # their covariance is the noise's alone: the 3x test's weights
    supports, cov, jitter_notes = _with_edge_jitter(supports, windows)
    warnings.extend(jitter_notes)
    A = np.array([supports[0].A_m_s2, supports[1].A_m_s2])
    if influence is not None:
        sol = solve_influence(influence, A, cov)
    elif beam is not None:
        sol = solve_beam(beam, p, omega, A, cov)
    else:
        sol = solve_unbalance(p, omega, A, cov)
    dof = min(ph.noise_dof for ph in supports)
    cov_U = np.asarray(sol.cov_U).real if sol.cov_U is not None else np.zeros((4, 4))
    radius = np.array(
        [radius95(cov_U[2 * i : 2 * i + 2, 2 * i : 2 * i + 2], dof) for i in range(2)]
    )
    warnings.extend(sol.diagnostics)
    found = _nonlinear_supports(p, omega, plain, sol.U_kg_m)
    if found is not None:
        radius = radius + NONLINEAR_WIDEN * np.abs(found.dU_kg_m)
        warnings = [w for w in warnings if w.code != "strong_3x"]  # explained: say what it is
        warnings.append(_nonlinear_note(found, p))
    return Measurement(
        supports=supports,
        solution=sol,
        radius95_kg_m=radius,
        radius_m=(p.R1, p.R2),
        omega_rad_s=float(omega),
        windows=windows,
        warnings=warnings,
        cov_A_m2_s4=cov,
    )
