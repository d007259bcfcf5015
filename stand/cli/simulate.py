"""Simulate a scene: write its run as a recording, or play it on a CAN bus in real time."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from stand import __version__
from stand.actions import archive_run
from stand.archive import url_for
from stand.archive.production import simulate_series
from stand.cli.common import (
    actor_of,
    add_actor_arguments,
    add_archive_argument,
    add_bus_arguments,
    add_job_arguments,
    add_scene_arguments,
    bus_kwargs,
    job_from,
)
from stand.cli.panel import ProgressLine, scene_masses
from stand.config import config_toml
from stand.core import unbalance_from_polar
from stand.drivers.bus import describe_bus, keep_stamps, open_bus, open_player_bus, play
from stand.drivers.runs.recording import JOB_ATTR, STAND_ATTR, Recording, write_recording
from stand.drivers.runs.run_format import TEST_UNBALANCE_ATTR
from stand.errors import UsageError
from stand.files import check_output
from stand.sim import (
    Scene,
    load_scene,
    scene_modules,
    shipped_scenes,
    simulate,
    turned,
    with_masses,
)
from stand.sim.scene import unbalance_kg_m
from stand.solve import load_config_text
from stand.solve.acquisition import acquisition_of


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", metavar="SCENE", help="a shipped scene (see `stand scenes`) or a file")
    p.add_argument(
        "--out",
        metavar="FILE",
        help="write the run: .h5 run file, or a python-can log (.log .asc .blf ...)",
    )
    p.add_argument(
        "--bus",
        action="store_true",
        help="play the run in real time on a python-can bus (the scene's [bus] "
        "table, else the virtual bus 'stand-demo')",
    )
    p.add_argument(
        "--config",
        metavar="CFG",
        help="the configuration stored with the run: what the software believes about the "
        "simulated stand (default: the scene's own); with --series also its [stand] id and "
        "[archive] url",
    )
    p.add_argument("--seed", type=int, help="random seed (overrides [run] seed)")
    p.add_argument(
        "--series",
        type=int,
        metavar="N",
        help="a production series of N rotors, each run, corrected as prescribed (with "
        "[effects.placement]'s scatter) and checked, on a stand that may drift "
        "([effects.drift]); the runs go to --out-dir, results and calibration data to the "
        "archive",
    )
    p.add_argument(
        "--starts", type=int, metavar="N",
        help="N starts of a ball balancer's acceptance test: the scene run N times, its "
        "unbalance turned 180 deg from one start to the next, into --out-dir as "
        "start-01.h5 ... (for stand autobalance test)",
    )  # fmt: skip
    p.add_argument("--out-dir", metavar="DIR", help="with --series or --starts: where the runs go")
    add_archive_argument(p)
    add_actor_arguments(p)
    p.add_argument("--force", action="store_true", help="replace --out if it exists")
    add_scene_arguments(p)
    add_job_arguments(p)
    add_bus_arguments(p)


def run(args: argparse.Namespace) -> int:

    if args.series is not None and args.starts is not None:
        raise UsageError("stand simulate: --series (a production) or --starts (a balancer's "
                         "test), not both")  # fmt: skip
    if args.series is not None:
        return _series(args)
    if args.starts is not None:
        return _starts(args)
    if args.archive or args.out_dir:  # never ignored: they belong to --series
        raise UsageError(
            "stand simulate: --archive and --out-dir go with --series N (archive one run "
            "with stand archive import RUN)"
        )
    if not args.out and not args.bus:
        raise UsageError("stand simulate: give --out FILE, --bus, or both")
    if args.out:
        check_output(args.out, force=args.force)  # before the work, and again when written
    job_from(args)  # bad job fields are refused before the work
    stored, believed = None, None
    if args.config:
        believed, _, stored = load_config_text(args.config)
    scene, params, source = load_scene(args.scene)
    scene = with_masses(scene, scene_masses(args), args.rpm, args.index)
    if args.seed is not None:
        scene = scene.model_copy(update={"run": scene.run.model_copy(update={"seed": args.seed})})
    label = args.scene if args.scene in shipped_scenes() else source
    _same_family(believed, args.config, scene, label)
    sim = simulate(scene, params, progress=ProgressLine(f"simulating {label}").simulated)
    print(
        f"{Path(source).stem}: {len(sim.frames)} frames, {scene.run.seconds:g} s {_speed(scene)}"
        f" ({sim.physics.replace('_', ' ')}, {sim.wall_s:.2f} s)",
        file=sys.stderr,
    )
    if args.out:
        _write(args, scene, sim, label, stored, believed, source)
    if args.bus:
        _play(args, scene, sim)
    return 0


def _same_family(believed: Any, config: str | None, scene: Any, label: str) -> None:
    """A config stored with a scene's run reads the family of hardware the scene sends (and
    its description files read): else the run would decode to nothing."""
    if believed is not None:
        acquisition_of(believed, config, scene_bus=scene.config().bus, scene=label)


def _write(
    args: argparse.Namespace,
    scene: Any,
    sim: Any,
    label: str,
    stored: str | None,
    believed: Any,
    source: str,
    more: dict[str, str] | None = None,
    out: str | None = None,
) -> None:
    """The run written to ``out`` (default --out: a run file, or a python-can log by its
    extension), ``more`` attributes with it."""
    out = out or args.out

    job = job_from(args)
    # the run keeps the description files (DBC, EDS) its stored config reads
    kept = acquisition_of(believed or scene.config(), args.config).descriptions_attr()
    rec = Recording(
        path=source,
        frames=sim.frames,
        meta={
            "source": f"simulated scene {label} (seed {scene.run.seed})",
            "config_toml": stored or config_toml(scene.config()),
            "software": f"stand {__version__}",
            JOB_ATTR: job.to_text() if job else "",
            STAND_ATTR: (believed or scene).stand.stand_id(),
            **kept,
            **(more or {}),
        },
    )
    write_recording(
        rec,
        out,
        acquisition_of(scene.config(), None).streams(sim.frames, strict_status=False),
        force=args.force,
        inputs=[source, *([args.config] if args.config else [])],
    )
    print(f"wrote {out}", file=sys.stderr)


def _play(args: argparse.Namespace, scene: Any, sim: Any) -> None:
    """The run played on a python-can bus in real time; hardware that a host sets up over
    the bus (CANopen modules) answers that set-up and then each of the host's SYNCs."""

    table = scene.bus or {"interface": "virtual", "channel": "stand-demo"}
    kwargs = bus_kwargs(args, table)
    modules = scene_modules(scene)
    # modules answering SYNC send when they answer: the receiving side stamps those
    bus, stamps = open_player_bus(kwargs) if modules is None else (open_bus(kwargs), False)
    try:
        if modules is None:
            print(f"playing on {describe_bus(kwargs)} in real time (Ctrl-C stops)",
                  file=sys.stderr)  # fmt: skip
            sent = play(bus, sim.frames, wire_stamps=stamps)
        else:
            print(f"the scene's modules answer on {describe_bus(kwargs)}: set them up and "
                  "send SYNC (stand record --config CFG with the same bus options); Ctrl-C "
                  "stops", file=sys.stderr)  # fmt: skip
            sent = modules.serve(bus, sim.frames, scene.nodes.rate_hz,
                                 stamps=lambda: keep_stamps(bus, kwargs))  # fmt: skip
    finally:
        bus.shutdown()
    print(f"sent {sent} frames", file=sys.stderr)


def _series(args: argparse.Namespace) -> int:
    """``--series N``: a simulated production series into the archive."""

    if args.series < 1:
        raise UsageError("stand simulate: --series N needs N >= 1")
    folder = _out_dir(args, "--series N")
    believed = None
    if args.config:  # what the software believes: stored with each run, its stand and archive
        cfg, _, text = load_config_text(args.config)
        base, _, _ = load_scene(args.scene)
        _same_family(cfg, args.config, base, args.scene)
        believed = (cfg, text)
    url = url_for(args.archive, believed[0] if believed else None)
    line = ProgressLine(f"simulating a series of {args.series}")
    actor = actor_of(args, url)
    done = simulate_series(
        args.scene,
        args.series,
        str(folder),
        url,
        lambda result: archive_run(result, url, actor),
        seed=args.seed or 0,
        force=args.force,
        on_rotor=lambda i: line.count(i, args.series, "rotor"),
        believed=believed,
    )
    print(f"{done} rotors balanced, corrected and checked; their data in {url}")
    return 0


def _speed(scene: Scene) -> str:
    """The scene's speed in words: steady, run up, braked."""
    e, rpm = scene.effects, scene.run.rpm
    said = f"at {rpm:g} rpm"
    if e.run_up is not None:
        said = f"run up to {rpm:g} rpm in {e.run_up.ramp_s:g} s"
    if e.coast_down is not None:
        said += (f", braked to standstill in {e.coast_down.ramp_s:g} s after "
                 f"{e.coast_down.after_s:g} s at the top")  # fmt: skip
    return said


def _out_dir(args: argparse.Namespace, what: str) -> Path:
    """``--out-dir``, made if missing (one line if it cannot be)."""
    if not args.out_dir:
        raise UsageError(f"stand simulate: {what} needs --out-dir DIR")
    if args.out or args.bus:
        raise UsageError(f"stand simulate: {what} writes --out-dir only")
    folder = Path(args.out_dir)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"stand simulate: --out-dir {folder}: not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"stand simulate: --out-dir {folder}: cannot make it "
                         f"({exc.strerror})") from exc  # fmt: skip
    return folder


def _starts(args: argparse.Namespace) -> int:
    """``--starts N``: a ball balancer's test starts, the unbalance turned 180 deg each."""
    if args.starts < 1 or args.starts > 99:
        raise UsageError(f"stand simulate: --starts takes 1 to 99, got {args.starts}")
    folder = _out_dir(args, "--starts N")
    names = [folder / f"start-{k + 1:02d}.h5" for k in range(args.starts)]
    for name in names:
        check_output(str(name), force=args.force)  # before the work
    stored, believed = None, None
    if args.config:
        believed, _, stored = load_config_text(args.config)
    base, params, source = load_scene(args.scene)
    base = with_masses(base, scene_masses(args), args.rpm, args.index)
    if base.effects.autobalancer is None:
        raise UsageError(f"stand simulate: {args.scene} has no [effects.autobalancer]: "
                         "--starts simulates a ball balancer's test")  # fmt: skip
    label = args.scene if args.scene in shipped_scenes() else source
    _same_family(believed, args.config, base, label)
    line = ProgressLine(f"simulating {args.starts} starts of {label}")
    for k, name in enumerate(names):
        scene = turned(base, 180.0 * k, (args.seed if args.seed is not None else base.run.seed) + k)

        def told(t: float, end: float, k: int = k) -> None:
            line.say(f"start {k + 1} of {args.starts}: {t:.0f} of {end:.0f} s simulated")

        sim = simulate(scene, params, progress=told)
        test = [[u.real, u.imag] for u in unbalance_from_polar(*unbalance_kg_m(scene))]
        _write(args, scene, sim, label, stored, believed, source,
               {TEST_UNBALANCE_ATTR: json.dumps(test)}, out=str(name))  # fmt: skip
    print(f"{args.starts} starts of {Path(source).stem} in {folder}, the unbalance turned 180 "
          "deg each: stand autobalance test " + " ".join(str(n) for n in names) + " --config "
          f"CFG (stand inspect {names[0]} --config-out CFG writes theirs)")  # fmt: skip
    return 0
