"""What a live measurement reads (:class:`LiveSource`): a config's CAN bus, or a simulated
scene played in real time on a private virtual bus, with the config the software
believes about it."""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.config import Config, config_toml
from stand.config.bus import bus_choice
from stand.config.drive import drive_choice
from stand.errors import UsageError
from stand.live.cycle import DriveLink
from stand.sim import load_scene, scene_modules, simulate, with_masses
from stand.sim.drives import simulated_drive
from stand.sim.shaft import drive_scene
from stand.solve.acquisition import Acquired, acquisition_of
from stand.solve.pipeline import load_config_text


@dataclass(frozen=True)
class LiveSource:
    """What a live measurement reads: the config, the parameters and the frames of a scene.

    ``bus_table`` is the config's ``[bus]`` table (None for a scene, which plays on a
    private virtual bus: ``scene_bus``); ``config_toml`` is stored in the run.
    """

    cfg: Config
    params: Any
    config_toml: str
    bus_table: dict[str, Any] | None = None
    scene_frames: Any = None
    scene_bus: dict[str, Any] | None = None
    acquisition: Acquired | None = None
    """The family the config reads and its layout (None: the default family's)."""
    modules: Any = None  # a CANopen scene's modules (stand.sim.canopen_node)
    scene_seed: int | None = None
    """The simulated run's noise seed (recorded with the run), None on a real bus."""
    drive: DriveLink | None = None
    """The drive the cycle commands (None: the operator spins the rotor)."""


def live_source(
    scene: str | None,
    config: str | None,
    command: str,
    masses: Sequence[Any] = (),
    rpm: float | None = None,
    index_deg: float | None = None,
    *,
    scene_hardware: bool = False,
    seed: int | None = None,
) -> LiveSource:
    """A simulated scene (played in real time on a private virtual bus), or a config's bus.

    With a scene, ``--config`` is what the software believes (calibration,
    correction, tolerance) and the scene is the physical stand and rotor: both
    are honoured.  ``masses`` (:class:`stand.sim.Mass`) and ``rpm`` change the
    simulated rotor and its speed.  A config that reads another protocol than the scene
    sends is refused, unless ``scene_hardware`` (the station's simulated sources): then
    the scene's sensors are the stand's and its ``[bus]`` table replaces the config's, in
    the run's stored config too.  ``seed``: the simulated run's noise seed (default: the
    scene's, or its own for a rotor carrying masses: :func:`stand.sim.scene.run_seed`).
    """

    if scene:
        sc, physical, _ = load_scene(scene)
        sc = with_masses(sc, masses, rpm, index_deg)
        if seed is not None:
            sc = sc.model_copy(update={"run": sc.run.model_copy(update={"seed": seed})})
        if config:
            cfg, params, text = load_config_text(config)
            sent = sc.config().bus
            if scene_hardware and bus_choice(cfg.bus, config).name != bus_choice(sent, scene).name:
                cfg = cfg.model_copy(update={"bus": sent})
                text = config_toml(cfg)
        else:
            cfg, params = sc.config(), physical
            text = config_toml(cfg)
        link = drive_link(cfg, config)
        if link is not None:  # the drive's shaft is the scene's: its run-up, its speed
            _damped(sc, scene)
            link.rpm = rpm or link.choice.drive.speed_rpm or sc.run.rpm
            stall = sc.effects.drive.stall_rpm if sc.effects.drive else None
            sc = drive_scene(sc, link.choice.drive.motor(), min(link.rpm, stall or link.rpm))
            link.sim = simulated_drive(link.choice.family.name, sc, link.choice.drive.motor(),
                                       link.choice.table)  # fmt: skip
        acq = acquisition_of(cfg, config, scene_bus=sc.config().bus, scene=scene)
        channel = f"stand-{command}-{os.getpid()}-{time.monotonic_ns()}"
        return LiveSource(
            cfg,
            params,
            text,
            scene_frames=simulate(sc, physical).frames,
            scene_bus={"interface": "virtual", "channel": channel},
            acquisition=acq,
            modules=scene_modules(sc),
            scene_seed=sc.run.seed,
            drive=link,
        )
    if masses or index_deg is not None:
        raise UsageError(f"stand {command}: --add, --apply and --index change a --scene's rotor")
    if not config:
        raise UsageError(f"stand {command}: give --config CFG (with its [bus] table) or --scene")
    cfg, params, text = load_config_text(config)
    link = drive_link(cfg, config)
    if rpm is not None and link is None:
        raise UsageError(f"stand {command}: --rpm sets a --scene's speed or a [drive]'s")
    return LiveSource(cfg, params, text, bus_table=cfg.bus,
                      acquisition=acquisition_of(cfg, config), drive=link)  # fmt: skip


def drive_link(cfg: Config, source: str | None) -> DriveLink | None:
    """The drive a config's ``[drive]`` names, when the product commands it."""
    if cfg.drive is None:
        return None
    where = source or "the config"
    choice = drive_choice(cfg.drive, where)
    base = Path(source).resolve().parent if source else Path.cwd()
    return DriveLink(choice, base=base, source=where, bus=cfg.bus) \
        if choice.family.commanded else None  # fmt: skip


def _damped(sc: Any, scene: str) -> None:
    """Refuse a scene whose supports have no damping for a drive: run up from rest through
    the supports' resonance, they would ring for ever and saturate the sensors."""
    if sc.stand.H1 == 0.0 and sc.stand.H2 == 0.0:
        raise UsageError(
            f"scene {scene}: its supports are undamped (H1 = H2 = 0 N s/m): run up by the "
            "drive through their resonance they would ring for ever and saturate the "
            "sensors; a drive needs a scene with damped supports (--scene demo-drive)"
        )
