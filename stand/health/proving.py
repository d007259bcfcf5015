"""The proving rotor's runs for ISO 21940-21's tests: simulated from a scene, or recorded
on the real stand and named in a file.

Each run is a :class:`ProvingRun`: what the stand read (the unbalance and its 95 % radius
per plane) and what was applied to the proving rotor (its declared test masses), and its
part in the tests: ``reference`` (the balanced proving rotor, no test mass), ``umar``
(10 U_mar in both test planes at one of 12 positions) or ``urr`` (a known test
unbalance).  ``RUNS.toml`` names recorded runs as ``stand calibrate`` takes them::

    [[runs]]
    file = "umar-00.h5"
    test = "umar"
    masses = [{plane = 1, mass_g = 0.222, angle_deg = 0.0},
              {plane = 2, mass_g = 0.25, angle_deg = 0.0, radius_mm = 80.0}]

(angles from the reference mark, against the direction of rotation; the radius defaults
to the plane's correction radius).  :func:`scene_runs` makes the same runs on a scene and,
with ``record``, writes them and that file, so that the evaluation from files repeats
the scene's.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, Field, FiniteFloat

from stand.config import STRICT, Config, config_toml, validate
from stand.config.tolerance import check_mass_on_rotor
from stand.core import StandParameters, unbalance_from_polar, unbalance_to_polar
from stand.core.machine_tests import UMAR_POSITIONS, UMAR_TEST_FACTOR
from stand.drivers.runs.recording import Recording, write_recording
from stand.errors import ConfigError
from stand.files import not_regular
from stand.measuring import Measurement
from stand.sim import Scene, simulate
from stand.sim.tables import PlaneUnbalance, UnbalanceTable
from stand.solve import SolveOptions, measure_streams
from stand.solve.acquisition import acquisition_of
from stand.solve.recordings import read_run

URR_TEST_FACTOR = 20.0
"""The URR test's unbalances: 20 U_mar."""
URR_ARRANGEMENT = (
    (1.0, 0.0, 0.0, 0.0),
    (0.0, 0.0, 1.0, 90.0),
    (1.0, 180.0, 1.0, 180.0),
    (1.0, 270.0, 1.0, 90.0),
)
"""The URR runs: (plane 1 share, angle, plane 2 share, angle): plane 1 alone, plane 2
alone, static, couple."""
Kind = Literal["reference", "umar", "urr"]
PREPARATION_PASSES = 3
"""The proving rotor is corrected this many times, each by what it read, before the tests
(the standard asks for it balanced well: a stand whose correction misses by 10 % leaves
0.1 % after three)."""


@dataclass(frozen=True)
class ProvingRun:
    """One run of the proving rotor: its name, its part, the test unbalance applied and
    what the stand read, per plane [kg m]."""

    name: str
    kind: str
    applied_kg_m: tuple[complex, complex]
    U_kg_m: tuple[complex, complex]
    radius95_kg_m: tuple[float, float]


def _run(name: str, kind: str, applied: np.ndarray, m: Measurement) -> ProvingRun:
    U = m.solution.U_kg_m
    return ProvingRun(
        name,
        kind,
        (complex(applied[0]), complex(applied[1])),
        (complex(U[0]), complex(U[1])),
        (float(m.radius95_kg_m[0]), float(m.radius95_kg_m[1])),
    )


def with_unbalance(scene: Scene, U_kg_m: np.ndarray, seed: int) -> Scene:
    q, phi = unbalance_to_polar(U_kg_m)
    table = UnbalanceTable(
        plane1=PlaneUnbalance(g_mm=float(q[0]) * 1e6, angle_deg=float(phi[0])),
        plane2=PlaneUnbalance(g_mm=float(q[1]) * 1e6, angle_deg=float(phi[1])),
    )
    run = scene.run.model_copy(update={"seed": seed})
    return scene.model_copy(update={"unbalance": table, "run": run})


def scene_unbalance(scene: Scene) -> np.ndarray:
    """The scene's rotor unbalance per plane [kg m] (its ``[unbalance]`` table: what
    :func:`with_unbalance` writes)."""
    u1, u2 = scene.unbalance.plane1, scene.unbalance.plane2
    return unbalance_from_polar([u1.g_mm * 1e-6, u2.g_mm * 1e-6], [u1.angle_deg, u2.angle_deg])


def step_up(x: float) -> float:
    """The smallest 1-2-5 step >= x."""
    decade = 10.0 ** math.floor(math.log10(x))
    for m in (1, 2, 5, 10):
        if m * decade >= x * (1 - 1e-12):
            return m * decade
    return 10 * decade  # pragma: no cover


def _plan(u_mar: float) -> list[tuple[str, str, np.ndarray]]:
    """(name, kind, applied unbalance) of every run after the reference."""
    plan = []
    for k in range(UMAR_POSITIONS):
        t = UMAR_TEST_FACTOR * u_mar * np.exp(-1j * math.radians(30.0 * k))
        plan.append((f"umar-{k:02d}", "umar", np.array([t, t])))
    for k, (s1, a1, s2, a2) in enumerate(URR_ARRANGEMENT):
        u = URR_TEST_FACTOR * u_mar
        U = u * np.array([s1 * np.exp(-1j * math.radians(a1)), s2 * np.exp(-1j * math.radians(a2))])
        plan.append((f"urr-{k}", "urr", U))
    return plan


@dataclass(frozen=True)
class SceneRuns:
    """The scene's proving runs, the claim U_mar [kg m] and the preparation: the scene's
    unbalance, the reading it was first corrected by, and the reading after that
    correction (its check run) [kg m]."""

    runs: tuple[ProvingRun, ...]
    u_mar_kg_m: float
    initial_kg_m: tuple[complex, complex]
    first_reading_kg_m: tuple[complex, complex]
    first_check_kg_m: tuple[complex, complex]


def scene_runs(scene: Scene, p: StandParameters, record: Path | None = None) -> SceneRuns:
    """The proving runs on a scene: its unbalance measured and corrected exactly as read,
    :data:`PREPARATION_PASSES` times (the proving rotor balanced before the tests), the
    claim U_mar (five times one reading's 95 % radius, or the residual if larger, up to a
    1-2-5 step), then the reference run, the 12 U_mar runs and the URR runs.  ``record``:
    a folder the runs and ``runs.toml`` are written to."""
    cfg = scene.config()
    U0 = scene_unbalance(scene)
    m0 = measure_scene(with_unbalance(scene, U0, scene.run.seed), p, cfg, None)
    residual, seed = U0 - m0.solution.U_kg_m, scene.run.seed + 1
    checks = []
    for _ in range(PREPARATION_PASSES - 1):  # balanced as well as the stand can
        m = measure_scene(with_unbalance(scene, residual, seed), p, cfg, None)
        residual, seed = residual - m.solution.U_kg_m, seed + 1
        checks.append(m.solution.U_kg_m)
    ref_scene = with_unbalance(scene, residual, seed)
    ref = measure_scene(ref_scene, p, cfg, None if record is None else record / "reference.h5")
    u_mar = step_up(
        max(5 * float(np.max(ref.radius95_kg_m)), float(np.max(np.abs(ref.solution.U_kg_m))))
    )
    runs = [_run("reference", "reference", np.zeros(2, complex), ref)]
    for k, (name, kind, applied) in enumerate(_plan(u_mar)):
        sc = with_unbalance(scene, residual + applied, seed + 100 + k)
        m = measure_scene(sc, p, cfg, None if record is None else record / f"{name}.h5")
        runs.append(_run(name, kind, applied, m))
    if record is not None:
        write_runs_toml(record / "runs.toml", runs, p)
    return SceneRuns(
        tuple(runs),
        u_mar,
        (complex(U0[0]), complex(U0[1])),
        (complex(m0.solution.U_kg_m[0]), complex(m0.solution.U_kg_m[1])),
        (complex(checks[0][0]), complex(checks[0][1])),
    )


def measure_scene(scene: Scene, p: StandParameters, cfg: Config, out: Path | None) -> Measurement:
    """One simulated run measured as every run is; written to ``out`` when given."""
    frames = simulate(scene, p).frames
    streams = acquisition_of(cfg, None).streams(frames)
    if out is not None:
        meta = {
            "source": f"simulated proving run (seed {scene.run.seed})",
            "config_toml": config_toml(cfg),
            "software": "stand",
        }
        write_recording(Recording(path=str(out), frames=frames, meta=meta), str(out), streams)
    m: Measurement = measure_streams(streams, cfg, p, SolveOptions())
    return m


def write_runs_toml(path: Path, runs: list[ProvingRun], p: StandParameters) -> None:
    """The ``RUNS.toml`` of recorded proving runs (masses at the correction radii)."""
    lines = []
    for r in runs:
        lines += ["[[runs]]", f'file = "{r.name}.h5"', f'test = "{r.kind}"']
        masses = []
        for i, U in enumerate(r.applied_kg_m):
            if abs(U) > 0:
                R = (p.R1, p.R2)[i]
                (q,), (phi,) = unbalance_to_polar([U])
                g, deg = float(q / R * 1e3), float(phi)
                masses.append(f"{{plane = {i + 1}, mass_g = {g!r}, angle_deg = {deg!r}}}")
        lines += [f"masses = [{', '.join(masses)}]", ""]
    path.write_text("\n".join(lines))


class TestMass(BaseModel):
    """One declared test mass of a proving run."""

    model_config = STRICT
    plane: Annotated[int, Field(ge=1, le=2)]
    mass_g: Annotated[FiniteFloat, Field(gt=0.0, le=1e6)]
    angle_deg: Annotated[FiniteFloat, Field(ge=-360.0, le=720.0)]
    radius_mm: Annotated[FiniteFloat, Field(gt=0.0, le=1e4)] | None = None


class ProvingEntry(BaseModel):
    model_config = STRICT
    file: Annotated[str, Field(min_length=1, max_length=4000)]
    test: Kind | None = None
    """The run's part in ``stand evaluate`` (``stand residual`` takes none)."""
    masses: Annotated[list[TestMass], Field(max_length=8)] = []


class ProvingFile(BaseModel):
    model_config = STRICT
    runs: Annotated[list[ProvingEntry], Field(min_length=1, max_length=200)]


def read_spec(path: str) -> ProvingFile:
    """A ``RUNS.toml`` of proving or trial runs, validated (ConfigError naming the key)."""
    if (kind := not_regular(path)) is not None:  # a FIFO would wait forever
        raise ConfigError(f"is {kind}, not a TOML file", source=path)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"not a readable TOML file ({exc})", source=path) from exc
    return validate(ProvingFile, data, path)


def file_runs(
    path: str, config: str | None
) -> tuple[list[ProvingRun], Config, StandParameters, bool]:
    """The recorded proving runs ``path`` names, each read and measured as ``stand solve``
    reads it (relative files from the file's folder); the config and parameters (the
    given config, or the first run's stored one: its ``M3`` the proving rotor's mass); and
    whether any run came from the simulator."""
    spec = read_spec(path)
    out: list[ProvingRun] = []
    first: tuple[Config, StandParameters] | None = None
    simulated = False
    for k, e in enumerate(spec.runs):
        run = Path(e.file) if Path(e.file).is_absolute() else Path(path).parent / e.file
        read = read_run(str(run), config)
        m, p = measure_streams(read.streams, read.cfg, read.params, SolveOptions()), read.params
        first = first or (read.cfg, p)
        source = str(read.rec.meta.get("source", ""))
        simulated = simulated or source.startswith(("simulated", "virtual:"))
        applied = np.zeros(2, complex)
        for j, t in enumerate(e.masses):
            R = t.radius_mm * 1e-3 if t.radius_mm else (p.R1, p.R2)[t.plane - 1]
            check_mass_on_rotor(t.mass_g * 1e-3, R, p, path, f"runs[{k}].masses[{j}]")
            applied[t.plane - 1] += t.mass_g * 1e-3 * R * np.exp(-1j * math.radians(t.angle_deg))
        if e.test is None:
            raise ConfigError("name the run's test: reference, umar or urr", source=path,
                              key=f"runs[{k}].test")  # fmt: skip
        if e.test != "reference" and not e.masses:
            raise ConfigError(
                "a umar or urr run declares its test masses", source=path, key=f"runs[{k}].masses"
            )
        out.append(_run(e.file, e.test, applied, m))
    assert first is not None  # the file holds at least one run
    return out, first[0], first[1], simulated
