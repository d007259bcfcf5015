"""The simulated stand's acquisition hardware: one entry a family of the drivers' registry
(:data:`stand.drivers.family.FAMILIES`), each what a scene's ``[nodes] protocol`` puts on
the stand.  The one place the simulator chooses by family: :func:`simulated`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from stand.drivers.frames import Frames
from stand.errors import ConfigError
from stand.sim.canopen_emit import bus_keys as canopen_keys
from stand.sim.canopen_emit import emit as canopen_emit
from stand.sim.canopen_node import SimulatedModules
from stand.sim.node_emit import emit as node_emit
from stand.sim.scan_emit import bus_keys as scan_keys
from stand.sim.scan_emit import emit as scan_emit


@dataclass(frozen=True)
class SimHardware:
    """One family's simulated hardware.

    ``emit(scene, accel, times, edges, clocks)``: the frames for the accelerations the
    sensors read at their sample times; ``bus_keys(nodes)``: the ``[bus]`` keys that
    decode them (stored in a run's config; none for v1); ``one_clock``: its devices sample
    on one clock (no ``[effects.clock]`` per node); ``clocked_by_sync``: they sample when
    the host's SYNC comes (``[nodes] sync_jitter_s``); ``faults``: the ``[effects.<name>]``
    table only it takes; ``modules(scene)``: what answers its set-up on a bus, or None."""

    name: str
    emit: Callable[..., list[Frames]]
    bus_keys: Callable[[Any], dict[str, Any]]
    one_clock: bool
    clocked_by_sync: bool = False
    faults: str | None = None
    modules: Callable[[Any], Any] = lambda scene: None


SIMULATED: dict[str, SimHardware] = {
    "v1": SimHardware("v1", node_emit, lambda nodes: {}, one_clock=False),
    "scan": SimHardware("scan", scan_emit, scan_keys, one_clock=True),
    "canopen": SimHardware(
        "canopen",
        canopen_emit,
        canopen_keys,
        one_clock=True,
        clocked_by_sync=True,
        faults="canopen",
        modules=lambda scene: SimulatedModules(scene.effects.canopen),
    ),
}
"""Family name -> its simulated hardware (``tests/sim`` holds it against the registry)."""


def simulated(name: str) -> SimHardware:
    """The simulated hardware of the family ``name``."""
    if name not in SIMULATED:
        raise ConfigError(f"no simulated hardware for {name!r} (one of {', '.join(SIMULATED)})",
                          key="nodes.protocol")  # fmt: skip
    return SIMULATED[name]


def scene_modules(scene: Any) -> Any:
    """What answers a scene's set-up on a bus (its CANopen modules, with their faults), or
    None for hardware that takes no set-up."""
    return simulated(scene.nodes.protocol).modules(scene)
