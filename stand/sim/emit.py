"""A scene, simulated: the sensors' samples and the mark's edges, then the frames of the
scene's hardware (:mod:`stand.sim.hardware`).

:func:`simulate` runs the scene's physics (:mod:`stand.sim.physics`), then
the sensor side of each node (gain and delay, 2x/3x and a neighbour's
vibration, noise, clipping, quantisation, invalid samples, its clock), then
what the bus does (lost frames, bursts, a dropout).  An effect the scene
does not name is never computed, and each effect draws from its own random
stream (``numpy.random.default_rng([seed, effect, node])``), so naming one
effect changes no byte that another effect produced.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stand.core import forward, rpm_to_rad_s, unbalance_from_polar
from stand.core.dsp import sensor_response
from stand.core.model import FloatArray, StandParameters
from stand.core.transient import Progress
from stand.drivers import Frames
from stand.drivers.runs.budget import frames_budget
from stand.drivers.v1.nodes import merge
from stand.errors import ConfigError
from stand.sim.balls import free_balls
from stand.sim.bus_side import rng_of
from stand.sim.hardware import simulated
from stand.sim.physics import (
    SceneSpeed,
    closed_form,
    edge_times,
    integrated,
    steady_forward,
    support_force,
)
from stand.sim.scene import Scene, node_unbalance, per_node, scene_beam, unbalance_kg_m


@dataclass(frozen=True)
class Simulation:
    """A simulated run.

    Attributes
    ----------
    frames : Frames
        What the nodes put on the bus, in arrival order (host time from 0).
    physics : str
        ``"closed_form"`` or ``"integrate"``.
    nfev : int
        Right-hand-side evaluations of the time integration (0 if none).
    wall_s : float
        Compute time [s].
    truth : dict
        For checking: per node ``t_s`` (sample times, physics time) and
        ``accel_m_s2`` (the measured acceleration before noise and
        quantisation); ``edges_s`` (edge times); ``A_m_s2`` (steady 1x
        phasors at the scene's speed, sensor gain and delay included).
    """

    frames: Frames
    physics: str
    nfev: int
    wall_s: float
    truth: dict[str, object] = field(default_factory=dict)


def scene_speed(scene: Scene) -> tuple[SceneSpeed, float]:
    """The speed law and the recording's start in physics time [s]."""
    e = scene.effects
    ramp = e.run_up.ramp_s if e.run_up else 0.0
    # nonlinear supports settle before the record; free balls start with it
    hold = (
        scene.run.settle_s if scene.needs_integration and not (e.run_up or e.autobalancer) else 0.0
    )
    t_start = hold  # a run-up is recorded from standstill
    sp, cd = e.speed, e.coast_down
    speed = SceneSpeed(
        coast_at_s=t_start + ramp + cd.after_s if cd else 0.0,
        coast_s=cd.ramp_s if cd else 0.0,
        base_omega_rad_s=float(rpm_to_rad_s(e.run_up.base_rpm))
        if e.run_up and e.run_up.base_rpm
        else 0.0,
        omega0_rad_s=float(rpm_to_rad_s(scene.run.rpm)),
        end_s=t_start + scene.run.seconds,
        ramp_s=ramp,
        hold_s=hold,
        ripple=sp.ripple_pct / 100 if sp else 0.0,
        ripple_hz=sp.ripple_hz if sp else 1.0,
        drift_per_s=sp.drift_pct_per_s / 100 if sp else 0.0,
    )
    return speed, t_start


def _sensor_side(scene: Scene, node: int, t: FloatArray, a: FloatArray, speed: Any) -> FloatArray:
    """Harmonics, a neighbour's vibration and the journal's runout (they are at the support
    too)."""
    e = scene.effects
    theta = speed.theta(t)
    if e.runout:
        # x = r cos(theta + phi) followed kinematically: x'' = -r (w^2 cos + alpha sin)
        r = per_node(e.runout.um)[node] * 1e-6
        phi = math.radians(per_node(e.runout.angle_deg)[node])
        w, al = speed.omega(t), speed.alpha(t)
        a = a - r * (w * w * np.cos(theta + phi) + al * np.sin(theta + phi))
    if e.harmonics:
        h = e.harmonics
        for k, amp, ph in ((2, h.x2_m_s2, h.x2_phase_deg), (3, h.x3_m_s2, h.x3_phase_deg)):
            A = per_node(amp)[node] * np.exp(1j * math.radians(per_node(ph)[node]))
            if A != 0:
                a = a + (A * np.exp(1j * k * theta)).real
    if e.neighbour:
        nb = e.neighbour
        w = float(rpm_to_rad_s(nb.rpm))
        a = a + per_node(nb.amplitude_m_s2)[node] * np.cos(
            w * t + math.radians(per_node(nb.phase_deg)[node])
        )
    return a


def scene_frames(scene: Scene) -> float:
    """About how many frames a scene makes: per node a SAMPLES frame per 3 samples, a MARK
    per revolution, a STATUS per second (the run-up's ramp counted at full speed)."""
    seconds = scene.run.seconds + (scene.effects.run_up.ramp_s if scene.effects.run_up else 0)
    per_s = scene.nodes.rate_hz / 3 + scene.run.rpm / 60 + 1
    return 2 * per_s * seconds


def scene_budget(scene: Scene) -> None:
    """Refuse a scene whose frames this machine has no memory for (before any is made)."""

    frames_budget(scene_frames(scene), f"the scene ({scene.run.seconds:g} s at "
                  f"{scene.run.rpm:g} rpm)", "to simulate")  # fmt: skip


def _support_force(scene: Scene, p: StandParameters, speed: Any, U: Any) -> Any:
    """The supports' nonlinear force (dry friction, clearances), or None when linear; the
    smoothing widths from the steady response when not given (seed 003)."""
    e = scene.effects
    if not e.nonlinear:
        return None
    w0 = speed.omega0_rad_s
    v_ss = np.abs(forward(p, w0, U)) / w0
    fr = per_node(e.friction.force_n) if e.friction else None
    fb = None
    if e.friction:
        fb = (
            [e.friction.beta_s_m] * 2
            if e.friction.beta_s_m
            else [100.0 / max(v, 1e-12) for v in v_ss]
        )
    gap = per_node(e.clearance.gap_m) if e.clearance else None
    gb = None
    if e.clearance and gap is not None:
        gb = (
            [e.clearance.beta_per_m] * 2
            if e.clearance.beta_per_m
            else [100.0 / max(g, 1e-12) for g in gap]
        )
    return support_force(p, fr, fb, gap, gb)


def _physics(
    scene: Scene,
    p: StandParameters,
    speed: Any,
    U: Any,
    seen: list[Any],
    beam: Any,
    truth: dict[str, object],
    progress: Progress | None,
) -> tuple[list[Any], int]:
    """Each support's acceleration at the times its sensor sees [m/s^2]: integrated in time
    (a run-up, nonlinear supports) or in closed form; and the integrator's evaluations."""
    if scene.effects.autobalancer is not None:
        return free_balls(scene.effects.autobalancer, p, speed, U, seen, scene.run.rtol,
                          scene.effects.run_up is None, truth, progress)  # fmt: skip
    if scene.needs_integration:
        both = np.concatenate(seen)
        a_both, nfev = integrated(
            p,
            speed,
            U,
            both,
            force=_support_force(scene, p, speed, U),
            rtol=scene.run.rtol,
            from_steady=scene.effects.run_up is None,
            progress=progress,
        )
        return [a_both[: len(seen[0]), 0], a_both[len(seen[0]) :, 1]], nfev
    spread = node_unbalance(scene, beam)
    return [closed_form(p, speed, U, s, beam, spread)[:, i] for i, s in enumerate(seen)], 0


def _on_the_bus(scene: Scene, blocks: list[Frames]) -> Frames:
    """The nodes' frames merged as the bus carries them, host time from the first frame
    (the start-up STATUS), a dropout taken out."""
    frames = merge(blocks)
    if len(frames):
        frames = Frames(
            frames.t_s - frames.t_s[0], frames.can_id, frames.dlc, frames.data, frames.flags
        )
    d = scene.effects.dropout
    if d:
        rel = frames.t_s
        frames = frames.take(~((rel >= d.at_s) & (rel < d.at_s + d.seconds)))
    return frames


def simulate(
    scene: Scene, p: StandParameters, *, progress: Callable[[float, float], None] | None = None
) -> Simulation:
    """Simulate the scene: its frames, and the truth they were made from.

    ``progress``, where given, is told now and then during a time integration the physics'
    time reached and its end [s] (for a progress line on a long simulation)."""
    start = time.perf_counter()
    scene_budget(scene)
    e = scene.effects
    speed, t_start = scene_speed(scene)
    t_end = t_start + scene.run.seconds
    U = unbalance_from_polar(*unbalance_kg_m(scene))
    beam = scene_beam(scene)  # a [rotor.shaft] table: the rotor bends
    if beam is not None and scene.needs_integration:
        raise ConfigError(
            "a bending rotor ([rotor.shaft]) is simulated in the closed form only: no "
            "run-up from standstill, nonlinear supports or integrated physics",
            key="rotor.shaft",
        )
    hw = simulated(scene.nodes.protocol)
    if hw.one_clock and e.clock:
        raise ConfigError(f"{hw.name}: the modules sample on one clock: no "
                          "[effects.clock] per node", key="effects.clock")  # fmt: skip
    if e.canopen and hw.faults != "canopen":
        raise ConfigError("[effects.canopen] needs [nodes] protocol = \"canopen\"",
                          key="effects.canopen")  # fmt: skip
    ppm = per_node(e.clock.ppm) if e.clock else [0.0, 0.0]
    offset = per_node(e.clock.offset_s) if e.clock else [0.0, 0.0]
    gain = per_node(e.sensor.gain) if e.sensor else [1.0, 1.0]
    delay = per_node(e.sensor.delay_s) if e.sensor else [0.0, 0.0]

    # --- when each node samples (physics time), and what the sensor sees then
    times = _sample_times(scene, t_start, ppm, offset)
    seen = [t - d for t, d in zip(times, delay, strict=True)]  # a group delay: earlier motion
    truth: dict[str, object] = {}
    told = None if progress is None else (lambda t: progress(t, t_end))
    a_phys, nfev = _physics(scene, p, speed, U, seen, beam, truth, told)

    edges = edge_times(speed, math.radians(scene.stand.reference_angle_deg), t_start, t_end)
    if e.edge_jitter:
        edges = edges + rng_of(scene, "edge_jitter").normal(0.0, e.edge_jitter.rms_s, len(edges))
    truth.update({"edges_s": edges, "t_start_s": t_start})
    w0 = speed.omega0_rad_s
    truth["A_m_s2"] = steady_forward(p, beam, w0, U, node_unbalance(scene, beam)) * np.array(
        [sensor_response(g, d, w0) for g, d in zip(gain, delay, strict=True)]
    )
    accel = []
    for i in range(2):
        a = gain[i] * _sensor_side(scene, i, seen[i], a_phys[i], speed)
        truth[f"node{i + 1}"] = {"t_s": times[i], "accel_m_s2": a}
        accel.append(a)
    return Simulation(
        frames=_on_the_bus(
            scene, hw.emit(scene, accel, times, edges, [*zip(ppm, offset, strict=True)])
        ),
        physics="integrate" if scene.needs_integration else "closed_form",
        nfev=nfev,
        wall_s=time.perf_counter() - start,
        truth=truth,
    )


def _sample_times(scene: Scene, t_start: float, ppm: list[float],
                  offset: list[float]) -> list[FloatArray]:  # fmt: skip
    """When each node samples (physics time): its clock's rate and offset; CANopen's
    modules when each SYNC comes (its jitter)."""
    rate = scene.nodes.rate_hz
    times = []
    for i in range(2):
        true_rate = rate * (1 + ppm[i] * 1e-6)
        n = math.floor((scene.run.seconds - offset[i]) * true_rate)
        times.append(t_start + offset[i] + np.arange(max(n, 0)) / true_rate)
    nodes = scene.nodes
    if simulated(nodes.protocol).clocked_by_sync and nodes.sync_jitter_s > 0:
        late = rng_of(scene, "sync_jitter", 0).normal(0.0, nodes.sync_jitter_s, len(times[0]))
        times = [t + late[: len(t)] for t in times]
    if simulated(nodes.protocol).clocked_by_sync and nodes.sync_stall_s > 0:
        times = [stalled(t, nodes.sync_stall_s, nodes.sync_stall_every_s) for t in times]
    return times


SYNC_BURST_S = 0.3e-3
"""A SYNC and two 8-byte TPDOs on the wire at 1 Mbit/s [s]: how close a SYNC producer
catching up can send its SYNCs (each module still answers before the next)."""


def stalled(due: FloatArray, stall_s: float, every_s: float) -> FloatArray:
    """When a SYNC producer on an absolute schedule (python-can's cyclic task: each SYNC
    due one period after the last one's due time) sends its SYNCs ``due`` [s] when its
    host stalls for the last ``stall_s`` of every ``every_s`` (from the first due time):
    a SYNC due in a stall goes out when the stall ends, and the late ones a
    :data:`SYNC_BURST_S` apart until the schedule is caught up."""
    if not len(due):
        return due
    phase = (due - due[0]) % every_s
    released = np.where(phase > every_s - stall_s, due - phase + every_s, due)
    k = np.arange(len(due)) * SYNC_BURST_S
    backlog = np.maximum.accumulate(released - k) + k
    out: FloatArray = np.where(backlog > released + 1e-9, backlog, released)  # on time: as due
    return out
