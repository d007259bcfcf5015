"""A simulated production series: rotor after rotor balanced, corrected and checked.

``stand simulate SCENE --series N --out-dir DIR``: each rotor (serial ``S-00001`` ...) gets a random
initial unbalance (each plane's size between 0.3 and 1 times
the scene's, at a random angle), a run, the correction the software
prescribes (with the runs' stored calibration: the scene's config), put on
with the operator's scatter (``[effects.placement]``), and a check run (archived as the
check of the first, with its URR);
both runs are archived, and the pair stored as a calibration datum
(:mod:`stand.health.monitor`, confirmed "as shown").  From rotor ``from_rotor`` on,
``[effects.drift]`` moves one of the stand's parameters: the physics
changes, the calibration the software believes does not.  Offline (not in
real time): a series of 200 rotors takes about a minute.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from stand import __version__
from stand.archive.results import file_digest
from stand.archive.store import Archive
from stand.config import Config, config_toml
from stand.drivers.runs.recording import JOB_ATTR, STAND_ATTR, Recording, write_recording
from stand.errors import UsageError
from stand.health import datum_row
from stand.sim import Mass, load_scene, simulate, with_masses
from stand.sim.tables import PlaneUnbalance
from stand.solve import Job, Result, solve_check, solve_recording
from stand.solve.acquisition import acquisition_of
from stand.solve.recordings import result_masses


def _write(scene: Any, params: Any, path: Path, believed: tuple[Config, str], force: bool,
           job: Job) -> None:  # fmt: skip
    """One rotor's run: the scene's physics, the believed config stored with it and its
    stand's id (what the software thinks; the runs are solved and archived by it)."""
    sim = simulate(scene, params)
    rec = Recording(
        path=str(path),
        frames=sim.frames,
        meta={
            "source": f"simulated production series (seed {scene.run.seed})",
            "config_toml": believed[1],
            "software": f"stand {__version__}",
            STAND_ATTR: believed[0].stand.stand_id(),
            JOB_ATTR: job.to_text(),
        },
    )
    streams = acquisition_of(scene.config(), None).streams(sim.frames, strict_status=False)
    write_recording(rec, path, streams, force=force)


def _rotor(scene: Any, rng: np.random.Generator, index: int) -> Any:
    """The scene with this rotor's random initial unbalance, its own noise seed."""

    u = scene.unbalance
    planes = {
        name: PlaneUnbalance(
            g_mm=getattr(u, name).g_mm * float(rng.uniform(0.3, 1.0)),
            angle_deg=float(rng.uniform(0.0, 360.0)),
        )
        for name in ("plane1", "plane2")
    }
    run = scene.run.model_copy(update={"seed": scene.run.seed * 100_003 + index})
    return scene.model_copy(update={"unbalance": u.model_copy(update=planes), "run": run})


def simulate_series(
    scene_name: str,
    count: int,
    out_dir: str,
    url: str,
    archive_run: Callable[[Result], int],
    *,
    seed: int = 0,
    force: bool = False,
    on_rotor: Callable[[int], None] | None = None,
    believed: tuple[Config, str] | None = None,
) -> int:
    """Simulate ``count`` rotors (see the module docstring); the data stored.  A run file
    already in ``out_dir`` is refused before the first rotor (replaced with ``force``).
    ``believed``: the config the software believes and its text, stored with each run (its
    ``[stand] id`` the runs' stand); default the scene's own.  ``archive_run`` archives a
    run and journals it (:func:`stand.actions.runs.archive_run`, bound to the archive
    ``url`` and to who simulates)."""

    scene, params, _ = load_scene(scene_name)
    believed = believed or (scene.config(), config_toml(scene.config()))
    drift, place = scene.effects.drift, scene.effects.placement
    rng = np.random.default_rng(seed)
    folder = Path(out_dir)
    there = [p for i in range(1, count + 1) for p in folder.glob(f"S-{i:05d}-?.h5")]
    if there and not force:
        raise UsageError(
            f"{there[0]} exists already (a series there before): another --out-dir, or --force"
        )
    stored = 0
    with Archive(url) as archive:  # one archive opened for the whole series
        for i in range(1, count + 1):
            truth = params
            if drift is not None:
                factors = {
                    n: getattr(params, n) * drift.factor(n, i) for n in ("C1", "C2", "M1", "M2")
                }
                truth = dataclasses.replace(params, **factors)
            rotor, serial = _rotor(scene, rng, i), f"S-{i:05d}"
            first, check = folder / f"{serial}-a.h5", folder / f"{serial}-b.h5"
            _write(rotor, truth, first, believed, force, Job(serial=serial, note="first run"))
            before = solve_recording(str(first))
            archive_run(before)
            masses = result_masses(before)
            sm = 0.0 if place is None else place.mass_pct / 100
            sa = 0.0 if place is None else place.angle_deg
            put = [
                Mass(p, g * (1 + sm * float(rng.normal())), a + sa * float(rng.normal()), r)
                for p, g, a, r in masses
            ]
            _write(
                with_masses(rotor, put), truth, check, believed, force,
                Job(serial=serial, note="check run"),
            )  # fmt: skip
            after = solve_check(str(check), str(first))
            archive_run(after)
            row = datum_row(
                before,
                after,
                masses,
                initial_sha256=file_digest(first),
                check_sha256=file_digest(check),
                confirmed_by="simulated operator",
                applied="as shown",
            )
            archive.add_correction(row)
            stored += 1
            if on_rotor is not None:
                on_rotor(i)
    return stored
