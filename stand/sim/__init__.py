"""The simulated stand: scenes, their physics, and the frames their nodes send.

A scene (:mod:`stand.sim.scene`) describes one run; :func:`stand.sim.emit.simulate`
computes it from the stand model (:mod:`stand.sim.physics`) and emits
protocol-v1 frames through :mod:`drivers.nodes` (or a scan-stream module's,
:mod:`stand.sim.scan_emit`, or CANopen modules', :mod:`stand.sim.canopen_emit`, whose
set-up over SDO :class:`~stand.sim.canopen_node.SimulatedModules` answers).  This package
sits between the core and the CLI: it may import the core, the config and the drivers.
"""

from stand.sim.canopen_node import SimulatedModules, scene_modules
from stand.sim.emit import Simulation, simulate
from stand.sim.scene import Mass, Scene, load_scene, shipped_scenes, turned, with_masses

__all__ = [
    "Mass",
    "Scene",
    "SimulatedModules",
    "Simulation",
    "load_scene",
    "scene_modules",
    "shipped_scenes",
    "simulate",
    "turned",
    "with_masses",
]
