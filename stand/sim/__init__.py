"""The simulated stand: scenes, their physics, and the frames their nodes send.

A scene (:mod:`stand.sim.scene`) describes one run; :func:`stand.sim.emit.simulate`
computes it from the stand model (:mod:`stand.sim.physics`) and emits the frames of the
hardware its ``[nodes] protocol`` names, chosen in one place
(:mod:`stand.sim.hardware`, one entry a family of the drivers' registry): sensor nodes
(:mod:`stand.sim.node_emit`), a scan-stream module (:mod:`stand.sim.scan_emit`) or CANopen
modules (:mod:`stand.sim.canopen_emit`, whose set-up over SDO
:class:`~stand.sim.canopen_node.SimulatedModules` answers), each encoded by its family's
own codec; what the bus does to any of them is :mod:`stand.sim.bus_side`.  This package
sits between the core and the CLI: it may import the core, the config and the drivers.
"""

from stand.sim.canopen_node import SimulatedModules
from stand.sim.emit import Simulation, simulate
from stand.sim.hardware import scene_modules
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
