"""Scenes: one simulated run, as a TOML file validated by pydantic.

A scene holds a configuration (``[stand]``, ``[rotor]``, optional ``[bus]``:
the same tables as a config file, so the config that solves the recording is
the scene's own) and::

    [run]        rpm, seconds, seed = 0, physics = "auto"
    [unbalance]  plane1 = { g_mm, angle_deg }, plane2 = { ... }   (the seed's phi)
                 distributed = { eccentricity_um, angle_deg, shape }  (with a shaft)
    [nodes]      rate_hz = 4000, scale_um_s2 = 100, first_seq = 0
    [effects.*]  each optional; an effect not named costs nothing

Per-node values (gains, delays, clock errors ...) are one number for both
nodes or a list ``[node1, node2]``.  Units are in the key names.  Every
table refuses unknown keys.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel

from stand.config.correction import check_correction
from stand.config.schema import (
    STRICT,
    Config,
    CorrectionTable,
    RotorTable,
    StandTable,
    ToleranceTable,
    parameters_of,
    read_toml,
    validate,
    with_shaft,
)
from stand.core import StandParameters
from stand.core.beam import beam_rotor, distributed_unbalance, node_at
from stand.errors import ConfigError
from stand.sim.hardware import simulated
from stand.sim.tables import (
    NODES as NODES,  # re-exported: the simulator's modules read it here
)
from stand.sim.tables import (
    AxialUnbalance,
    Effects,
    NodesTable,
    PlaneUnbalance,
    RunTable,
    UnbalanceTable,
)
from stand.sim.tables import per_node as per_node  # re-exported


class Scene(BaseModel):
    """A whole scene file."""

    model_config = STRICT

    description: str = ""
    stand: StandTable
    rotor: RotorTable
    bus: dict[str, str | int | float | bool | list[Any] | dict[str, Any]] | None = None
    tolerance: ToleranceTable | None = None
    correction: CorrectionTable = CorrectionTable()
    run: RunTable
    unbalance: UnbalanceTable
    nodes: NodesTable = NodesTable()
    effects: Effects = Effects()

    def config(self) -> Config:
        """The configuration part (what solves the recording)."""
        bus, keys = self.bus, simulated(self.nodes.protocol).bus_keys(self.nodes)
        if keys:  # the keys that decode the scene's hardware
            bus = {**(bus or {}), **keys}
        return Config(
            stand=self.stand,
            rotor=self.rotor,
            bus=bus,
            tolerance=self.tolerance,
            correction=self.correction,
            autobalancer=self.effects.autobalancer,
        )

    @property
    def needs_integration(self) -> bool:
        """Whether the physics path is time integration."""
        if self.run.physics != "auto":
            return self.run.physics == "integrate"
        e = self.effects
        return e.sweeps or e.nonlinear or e.autobalancer is not None


def _coasts_in_time(scene: Scene, source: str) -> None:
    """A coast-down's recording ends before the rotor stands (the nodes' reference mark
    stops with it: a recording past it would end in a silence no measurement reads)."""
    e = scene.effects
    if e.coast_down is None:
        return
    stands = (e.run_up.ramp_s if e.run_up else 0.0) + e.coast_down.after_s + e.coast_down.ramp_s
    if scene.run.seconds >= stands:
        raise ConfigError(
            f"the rotor stands still {stands:g} s into the recording (the coast-down's "
            f"after_s + ramp_s): [run] seconds = {scene.run.seconds:g} must end before",
            source=source,
            key="run.seconds",
        )


def scenes_dir() -> Path:
    """Where the shipped scenes are."""
    return Path(str(resources.files("stand") / "data" / "scenes"))


def shipped_scenes() -> dict[str, Path]:
    """The shipped scenes by name."""
    return {p.stem: p for p in sorted(scenes_dir().glob("*.toml"))}


def load_scene(name_or_path: str | Path) -> tuple[Scene, StandParameters, str]:
    """A scene by shipped name (``demo``) or path; return it, its parameters, its source.

    Raises
    ------
    ConfigError
        Unknown name, unreadable file, or a bad value (naming file and key).
    """
    text = str(name_or_path)
    shipped = shipped_scenes()
    if text in shipped:
        path = shipped[text]
    elif Path(text).exists() or text.endswith(".toml"):
        path = Path(text)
    else:
        raise ConfigError(
            f"no such scene: expected a file or one of {', '.join(shipped)}", source=text
        )
    _, data = read_toml(path)
    scene = validate(Scene, data, str(path))
    if scene.run.physics == "closed_form" and (scene.effects.sweeps or scene.effects.nonlinear):
        raise ConfigError(
            'physics = "closed_form" cannot simulate a run-up, a coast-down or a nonlinear support',
            source=str(path),
            key="run.physics",
        )
    _coasts_in_time(scene, str(path))
    # a shaft table gives the rotor's values (and the rotor bends)
    scene = scene.model_copy(update={"rotor": with_shaft(scene.config(), str(path)).rotor})
    for key in ("distributed", "axial"):
        if getattr(scene.unbalance, key) and scene.rotor.shaft is None:
            raise ConfigError(
                "an unbalance spread along the rotor or away from its two planes needs the "
                "shaft ([rotor.shaft])",
                source=str(path),
                key=f"unbalance.{key}",
            )
    check_correction(scene.correction, scene.rotor, str(path))
    params = parameters_of(scene.config(), str(path))
    return scene, params, str(path)


def unbalance_kg_m(scene: Scene) -> tuple[list[float], list[float]]:
    """``(q_i R_i [kg m], phi_i [deg])`` of both planes: the rotor's, and its tooling's
    (``[effects.tooling]``) at the rotor's index on it."""
    u, t = scene.unbalance, scene.effects.tooling
    planes = [u.plane1, u.plane2]
    if t is None:
        return [p.g_mm * 1e-6 for p in planes], [p.angle_deg for p in planes]
    # the rotor turned by delta on its tooling: the tooling's heavy spot is delta nearer the
    # mark, phi_t - delta, so U_t e^{+i delta}
    turn = cmath.exp(1j * math.radians(scene.run.index_deg))
    total = [
        p.g_mm * cmath.exp(-1j * math.radians(p.angle_deg))
        + q.g_mm * cmath.exp(-1j * math.radians(q.angle_deg)) * turn
        for p, q in zip(planes, (t.plane1, t.plane2), strict=True)
    ]
    return [abs(z) * 1e-6 for z in total], [-math.degrees(cmath.phase(z)) % 360.0 for z in total]


def describe(scene: Scene) -> dict[str, Any]:
    """A short account of a scene (for ``stand scenes``)."""
    return {
        "description": scene.description,
        "rpm": scene.run.rpm,
        "seconds": scene.run.seconds,
        "effects": scene.effects.named(),
        "physics": "integrate" if scene.needs_integration else "closed_form",
    }


@dataclass(frozen=True)
class Mass:
    """A mass put on (grams > 0) or taken off (< 0) the simulated rotor.

    ``angle_deg`` in the sense and from the zero of the reported angles (from the
    reference mark, against the direction of rotation); ``radius_m`` None: the
    plane's correction radius.
    """

    plane: int
    grams: float
    angle_deg: float
    radius_m: float | None = None
    position_m: float | None = None
    """Along the shaft [m from its left end]: a plane of ``[[rotor.planes]]`` (balancing
    across speeds); None: plane 1 or 2 of the stand."""


def with_masses(
    scene: Scene,
    masses: Sequence[Mass] = (),
    rpm: float | None = None,
    index_deg: float | None = None,
) -> Scene:
    """The scene's rotor with masses added or removed, optionally at another speed and
    turned on its tooling by ``index_deg``.

    A rotor with masses put on is another run: it draws its own noise, from a seed derived
    from the scene's and the masses (:func:`run_seed`), so that a check run never replays
    the noise of the run it checks (it read exactly 0.0 g mm before).

    A mass ``m`` at radius ``r`` and angle ``a`` adds ``m r e^{-i a}`` to its
    plane's unbalance ``U = q R e^{-i phi}``: a mass put where the software says
    the unbalance is makes it larger, material taken off there makes it smaller.
    """
    U = [
        scene.unbalance.plane1.g_mm
        * cmath.exp(-1j * math.radians(scene.unbalance.plane1.angle_deg)),
        scene.unbalance.plane2.g_mm
        * cmath.exp(-1j * math.radians(scene.unbalance.plane2.angle_deg)),
    ]  # g mm
    radius_mm = (scene.rotor.R1 * 1e3, scene.rotor.R2 * 1e3)
    axial = list(scene.unbalance.axial)
    for m in masses:
        if m.position_m is not None:
            if scene.rotor.shaft is None or m.radius_m is None:
                raise ConfigError(
                    "a mass along the shaft needs the shaft ([rotor.shaft]) and a radius",
                    key="apply",
                )
            u = m.grams * m.radius_m * 1e3 * cmath.exp(-1j * math.radians(m.angle_deg))
            axial.append(
                AxialUnbalance(
                    position_m=m.position_m,
                    g_mm=abs(u),
                    angle_deg=float(-math.degrees(cmath.phase(u)) % 360.0),
                )
            )
            continue
        if m.plane not in (1, 2):
            raise ConfigError(f"plane {m.plane}: a rotor has planes 1 and 2", key="add")
        r = radius_mm[m.plane - 1] if m.radius_m is None else m.radius_m * 1e3
        U[m.plane - 1] += m.grams * r * cmath.exp(-1j * math.radians(m.angle_deg))
    planes: dict[str, Any] = {
        f"plane{i + 1}": PlaneUnbalance(
            g_mm=abs(u), angle_deg=float(-math.degrees(cmath.phase(u)) % 360.0)
        )
        for i, u in enumerate(U)
    }
    planes["distributed"] = scene.unbalance.distributed
    planes["axial"] = axial
    run = scene.run if rpm is None else scene.run.model_copy(update={"rpm": rpm})
    if masses:
        run = run.model_copy(update={"seed": run_seed(scene.run.seed, masses)})
    if index_deg is not None:
        run = run.model_copy(update={"index_deg": index_deg})
    return scene.model_copy(update={"unbalance": UnbalanceTable(**planes), "run": run})


def run_seed(seed: int, masses: Sequence[Mass]) -> int:
    """A seed of its own for the run of a rotor carrying ``masses``: numpy's
    ``SeedSequence`` of the scene's seed and each mass (to the microgram and the
    micro-degree), so the same masses give the same run and other masses another."""
    words = [seed & 0xFFFFFFFF]
    for m in masses:
        words += [m.plane & 0xFFFF, round(m.grams * 1e6) & 0xFFFFFFFF,
                  round(m.angle_deg * 1e6) & 0xFFFFFFFF]  # fmt: skip
    return int(np.random.SeedSequence(words).generate_state(1)[0])


def node_unbalance(scene: Scene, beam: Any) -> Any:
    """The scene's unbalance along the shaft per node of ``beam`` [kg m]: the spread one and
    those at other places (None without either, or without a beam)."""
    d = scene.unbalance.distributed
    if (d is None and not scene.unbalance.axial) or beam is None:
        return None

    x = beam.x_m
    out = np.zeros(len(x), complex)
    if d is not None:
        e = np.full(len(x), d.eccentricity_um * 1e-6)
        if d.shape == "bow":
            e = e * np.sin(math.pi * (x - x[0]) / (x[-1] - x[0]))
        out += distributed_unbalance(beam, e, d.angle_deg)
    for a in scene.unbalance.axial:
        out[node_at(beam, a.position_m)] += (
            a.g_mm * 1e-6 * cmath.exp(-1j * math.radians(a.angle_deg))
        )
    return out


def scene_beam(scene: Scene) -> Any:
    """The scene's beam model with a node at every place an unbalance sits (None for a
    rigid rotor)."""
    if scene.rotor.shaft is None:
        return None

    at = [pl.position_m for pl in scene.rotor.planes] + [
        a.position_m for a in scene.unbalance.axial
    ]
    return beam_rotor(*scene.rotor.shaft.core_args(), extra_positions_m=at)


def turned(scene: Scene, deg: float, seed: int) -> Scene:
    """The scene with both planes' unbalance turned ``deg`` (the angles' sense: a test mass
    moved round the rotor) and another random seed: one start of a balancer's test."""
    u = scene.unbalance
    planes = {
        f"plane{i}": p.model_copy(update={"angle_deg": (p.angle_deg + deg) % 360.0})
        for i, p in ((1, u.plane1), (2, u.plane2))
    }
    return scene.model_copy(update={
        "unbalance": u.model_copy(update=planes),
        "run": scene.run.model_copy(update={"seed": seed}),
    })  # fmt: skip
