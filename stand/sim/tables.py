"""The scene's own tables: the run, the unbalance, the nodes and the effects.

A scene (:mod:`stand.sim.scene`) is a configuration's tables plus these.
Per-node values (gains, delays, clock errors ...) are one number for both
nodes or a list ``[node1, node2]``; units are in the key names; every table
refuses unknown keys.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.config import STRICT
from stand.config.autobalancer import AutobalancerTable
from stand.drivers.frames import FD_LENGTHS

NODES = 2

Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Probability = Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False)]
PerNode = FiniteFloat | list[FiniteFloat]
"""One value for every node, or ``[node1, node2]``."""


def per_node(value: float | list[float]) -> list[float]:
    """The value of each node."""
    if isinstance(value, list):
        return [float(v) for v in value]
    return [float(value)] * NODES


class _Table(BaseModel):
    model_config = STRICT

    @model_validator(mode="after")
    def _two_nodes(self) -> _Table:
        for name, value in self:
            if isinstance(value, list) and name != "axial" and len(value) != NODES:
                raise ValueError(
                    f"{name}: expected one value or {NODES} (one per node), got {len(value)}"
                )
        return self


class RunTable(_Table):
    """``[run]``: speed, length, random seed, physics path."""

    rpm: Positive
    seconds: Positive
    seed: int = 0
    physics: Literal["auto", "closed_form", "integrate"] = "auto"
    rtol: Positive = 1e-8
    """Relative tolerance of the time integration (when it runs)."""
    settle_s: NonNegative = 2.0
    """Time integrated (and not recorded) before the run starts, on the
    integration path without run-up, for the nonlinear supports to settle [s]."""
    index_deg: FiniteFloat = 0.0
    """How far the rotor is turned on its tooling (``[effects.tooling]``), in the angles'
    sense [deg]: 180 for the second run of the index procedure."""


class PlaneUnbalance(_Table):
    g_mm: NonNegative
    angle_deg: FiniteFloat


class DistributedUnbalance(_Table):
    """``[unbalance.distributed]`` (a rotor with ``[rotor.shaft]`` only): the mass centre
    line off the shaft's axis, at one angle; ``shape`` ``uniform`` (an eccentric shaft)
    or ``bow`` (a half sine over the shaft's length, largest at mid-length)."""

    eccentricity_um: NonNegative
    angle_deg: FiniteFloat
    shape: Literal["uniform", "bow"] = "bow"


class AxialUnbalance(_Table):
    """``[[unbalance.axial]]`` (a rotor with ``[rotor.shaft]`` only): an unbalance at a place
    along the shaft [m from its left end], ``g_mm`` at ``angle_deg`` (a correction in a
    third plane, a coupling)."""

    position_m: Annotated[FiniteFloat, Field(ge=0.0)]
    g_mm: NonNegative
    angle_deg: FiniteFloat


class UnbalanceTable(_Table):
    """``[unbalance]``: ``U_i = q_i R_i`` [g mm] at the seed's angle ``phi_i`` [deg], and
    optionally an unbalance spread along a bending shaft and unbalances at other places
    along it."""

    plane1: PlaneUnbalance
    plane2: PlaneUnbalance
    distributed: DistributedUnbalance | None = None
    axial: Annotated[list[AxialUnbalance], Field(max_length=64)] = []


class NodesTable(_Table):
    """``[nodes]``: the simulated sensor nodes."""

    rate_hz: Annotated[int, Field(gt=0, lt=65536)] = 4000
    scale_um_s2: Annotated[int, Field(gt=0, lt=65536)] = 100
    first_seq: Annotated[int, Field(ge=0, lt=65536)] = 0
    protocol: Literal["v1", "scan", "canopen"] = "v1"
    """``v1``: two sensor nodes; ``scan``: one scan-stream module (:mod:`stand.sim.scan_emit`);
    ``canopen``: a SYNC producer and two analog input modules (:mod:`stand.sim.canopen_emit`)."""
    counter: bool = True
    """``scan`` only: whether the module sends its scan counter."""
    scans_per_frame: Annotated[int, Field(ge=1, le=8)] = 1
    """``scan`` only: CAN FD frames of this many 8-byte scans (1: a classic frame a scan),
    by the same rule as ``[bus.scan]``: k x 8 bytes a CAN FD payload length (1, 2, 3, 4, 6
    or 8)."""
    sync_jitter_s: Annotated[float, Field(ge=0.0, le=1e-3)] = 0.0
    """``canopen`` only: the SYNC's timing jitter (rms): the modules sample when it comes."""
    sync_stall_s: Annotated[float, Field(ge=0.0, le=0.5)] = 0.0
    """``canopen`` only: the host that produces the SYNC stalls this long once every
    ``sync_stall_every_s`` (a loaded machine): the SYNCs due meanwhile go out when it ends,
    a bus cycle apart, until the producer's schedule is caught up."""
    sync_stall_every_s: Annotated[float, Field(ge=0.05, le=60.0)] = 1.0

    @model_validator(mode="after")
    def _fd_frame(self) -> NodesTable:
        if self.sync_stall_s >= self.sync_stall_every_s:
            raise ValueError(f"sync_stall_s ({self.sync_stall_s:g} s) must be shorter than "
                             f"sync_stall_every_s ({self.sync_stall_every_s:g} s)")  # fmt: skip
        if self.scans_per_frame > 1 and 8 * self.scans_per_frame not in FD_LENGTHS:
            lengths = ", ".join(map(str, FD_LENGTHS[8:]))
            raise ValueError(f"scans_per_frame: {self.scans_per_frame} x 8 bytes is not a CAN "
                             f"FD payload length ({lengths})")  # fmt: skip
        return self


class Noise(_Table):
    """White sensor noise: a density or an rms, not both."""

    density_m_s2_rthz: NonNegative | None = None
    rms_m_s2: NonNegative | None = None

    @model_validator(mode="after")
    def _one(self) -> Noise:
        if (self.density_m_s2_rthz is None) == (self.rms_m_s2 is None):
            raise ValueError("give density_m_s2_rthz or rms_m_s2 (one of them)")
        return self


class Clock(_Table):
    """Node clock error [ppm] and start offset [s] (when the node's sample 0 is taken)."""

    ppm: PerNode = 0.0
    offset_s: PerNode = 0.0


class SpeedEffect(_Table):
    """Speed ripple (a sine, in % of the speed) and a slow drift (% per second)."""

    ripple_pct: NonNegative = 0.0
    ripple_hz: Positive = 1.0
    drift_pct_per_s: FiniteFloat = 0.0


class RunUp(_Table):
    """Start from standstill, reach ``[run] rpm`` in ``ramp_s`` (a transient): linearly, or
    with ``base_rpm`` below it as a torque-limited inverter drive does (constant torque to
    the motor's base speed, constant power above: the acceleration falls as base / speed).
    """

    ramp_s: Positive
    base_rpm: Positive | None = None


class CoastDown(_Table):
    """After ``after_s`` at ``[run] rpm`` (from its steady state, or from the run-up's
    top), the drive lets go and a brake holds the deceleration: the speed falls linearly
    to standstill in ``ramp_s`` (a transient; the recording ends at ``[run] seconds``,
    which must come before the standstill)."""

    ramp_s: Positive
    after_s: NonNegative = 1.0


class Sensor(_Table):
    """Sensor gain and group delay [s]: the phase lag grows with speed, ``w * delay``."""

    gain: PerNode = 1.0
    delay_s: PerNode = 0.0


class EdgeJitter(_Table):
    """Timing jitter of the reference edge (Gaussian, rms) [s]."""

    rms_s: NonNegative


class LostFrames(_Table):
    """Frames lost on the bus: single (probability per frame) and in bursts."""

    probability: Probability = 0.0
    bursts_per_s: NonNegative = 0.0
    burst_frames: Annotated[int, Field(ge=1)] = 10


class Invalid(_Table):
    """Invalid samples (count -32768), each with this probability."""

    probability: Probability


class Clipping(_Table):
    """The sensor saturates at +-``range_m_s2``; STATUS reports overrange."""

    range_m_s2: Positive


class Harmonics(_Table):
    """2x and 3x components (misalignment): ``Re(H e^{i k theta})`` per node."""

    x2_m_s2: PerNode = 0.0
    x2_phase_deg: PerNode = 0.0
    x3_m_s2: PerNode = 0.0
    x3_phase_deg: PerNode = 0.0


class Neighbour(_Table):
    """A neighbouring machine's vibration at a fixed (non-synchronous) frequency."""

    rpm: Positive
    amplitude_m_s2: PerNode
    phase_deg: PerNode = 0.0


class Friction(_Table):
    """Dry friction in the supports: ``-F (2/pi) arctan(beta v)`` [N]."""

    force_n: PerNode
    beta_s_m: Positive | None = None
    """Smoothing [s/m]; default 100 / (the support's steady velocity amplitude)."""


class Clearance(_Table):
    """A clearance (dead band) of ``gap_m`` in each support's spring, smoothed."""

    gap_m: PerNode
    beta_per_m: Positive | None = None
    """Smoothing [1/m]; default 100 / gap."""


class ToolingEffect(_Table):
    """``[effects.tooling]``: the unbalance of the adapter, mandrel or coupling the rotor
    sits on [g mm, deg at index 0].  It turns with the rotor, but stays with the tooling
    when the rotor is turned on it (``[run] index_deg``, ``--index``): the reference mark
    is on the rotor, so the tooling's angle moves by the index."""

    plane1: PlaneUnbalance
    plane2: PlaneUnbalance


DriftParameter = Literal["C1", "C2", "M1", "M2"]


class DriftEffect(_Table):
    """``[effects.drift]``: a production series (``stand simulate --series``) on a stand
    that changes from rotor ``from_rotor`` on (1-based): ``step_pct`` at once (e.g.
    ``{ C1 = -8.0 }``) and ``per_rotor_pct`` more with every rotor after it; the runs keep
    the calibration the software believes."""

    from_rotor: Annotated[int, Field(ge=1)] = 1
    step_pct: dict[DriftParameter, Annotated[float, Field(gt=-90.0, lt=900.0)]] = {}
    per_rotor_pct: dict[DriftParameter, Annotated[float, Field(gt=-10.0, lt=10.0)]] = {}

    def factor(self, name: str, rotor: int) -> float:
        """How much ``name`` is multiplied by at ``rotor`` (1-based)."""
        if rotor < self.from_rotor:
            return 1.0
        step = {str(k): v for k, v in self.step_pct.items()}.get(name, 0.0)
        per = {str(k): v for k, v in self.per_rotor_pct.items()}.get(name, 0.0)
        ramp = per * (rotor - self.from_rotor)
        return float(max(0.01, 1 + (step + ramp) / 100))


class PlacementEffect(_Table):
    """``[effects.placement]``: the operator's scatter when the correction is put on
    (``--series``): each mass off by ``mass_pct`` (relative) and its angle by ``angle_deg``
    (standard deviations)."""

    mass_pct: NonNegative = 0.0
    angle_deg: NonNegative = 0.0


class Runout(_Table):
    """``[effects.runout]``: each journal runs out in its support by ``um`` at ``angle_deg``
    (the support follows it: a kinematic 1x, ``-w^2`` times the runout, that is not
    unbalance; a slow-roll run measures it, ``--slow-roll``)."""

    um: PerNode
    angle_deg: PerNode = 0.0


class Dropout(_Table):
    """The bus carries nothing from ``at_s`` for ``seconds``."""

    at_s: NonNegative
    seconds: Positive


class CanopenFaults(_Table):
    """``[effects.canopen]`` (``[nodes] protocol = "canopen"``): what the simulated modules
    do wrong.  ``node`` (1 or 2) is the module the timed faults hit."""

    node: Literal[1, 2] = 1
    late_probability: Probability = 0.0
    """A TPDO sent after the next SYNC (past the synchronous window)."""
    emcy_at_s: NonNegative | None = None
    """An EMCY (error code 0x5000, device hardware) at this time; the accelerometer input's
    AI status says not valid for ``invalid_s`` after it."""
    invalid_s: NonNegative = 0.02
    restart_at_s: NonNegative | None = None
    """The module restarts (boot-up, pre-operational): no TPDO from it after this time."""
    vendor_id: Annotated[int, Field(ge=0, le=0xFFFFFFFF)] | None = None
    """The identity's vendor id the modules show (0x1018 sub 1) instead of their EDS's."""
    refuse_mapping: bool = False
    """The modules refuse to have TPDO1 mapped (SDO abort 0x06040041)."""


class DriveFaults(_Table):
    """``[effects.drive]`` (a config with a ``[drive]`` the scene's simulated drive serves):
    what the stand's drive and guard do wrong."""

    guard_open: bool = False
    """The guard is open from the start."""
    guard_opens_at_s: NonNegative | None = None
    """The guard opens at this time after the run-up began."""
    fault_code: Annotated[int, Field(ge=0, le=0xFFFF)] = 0
    """The drive is in fault with this code."""
    silent: bool = False
    """The drive never answers."""
    speed_scale: Annotated[FiniteFloat, Field(gt=0.0, le=10.0)] = 1.0
    """The speed the drive reports, times this (a map with a wrong scaling)."""
    overspeed_pct: Annotated[FiniteFloat, Field(ge=0.0, le=50.0)] = 0.0
    """The drive runs this much over its set point (a speed loop gone wrong)."""
    stall_rpm: Annotated[FiniteFloat, Field(gt=0.0, le=1e5)] | None = None
    """The drive never turns faster than this (a motor too weak, a brake left on)."""


class Effects(_Table):
    """``[effects.*]``: each absent unless named."""

    noise: Noise | None = None
    clock: Clock | None = None
    speed: SpeedEffect | None = None
    run_up: RunUp | None = None
    coast_down: CoastDown | None = None
    sensor: Sensor | None = None
    edge_jitter: EdgeJitter | None = None
    lost_frames: LostFrames | None = None
    invalid: Invalid | None = None
    clipping: Clipping | None = None
    harmonics: Harmonics | None = None
    neighbour: Neighbour | None = None
    friction: Friction | None = None
    clearance: Clearance | None = None
    dropout: Dropout | None = None
    tooling: ToolingEffect | None = None
    drift: DriftEffect | None = None
    runout: Runout | None = None
    placement: PlacementEffect | None = None
    canopen: CanopenFaults | None = None
    drive: DriveFaults | None = None
    autobalancer: AutobalancerTable | None = None
    """A ball balancer on the rotor, its balls free on their race (the ``[autobalancer]``
    table's keys): integrated with the stand (:mod:`stand.core.balls`)."""

    def named(self) -> list[str]:
        """The effects the scene names, in table order."""
        return [name for name, value in self if value is not None]

    @property
    def sweeps(self) -> bool:
        """A run-up or a coast-down: the speed sweeps, the physics is integrated in time."""
        return self.run_up is not None or self.coast_down is not None

    @property
    def nonlinear(self) -> bool:
        return self.friction is not None or self.clearance is not None
