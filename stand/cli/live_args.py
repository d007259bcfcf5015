"""What ``stand measure`` and ``stand balance`` share: their options and their live source."""

from __future__ import annotations

import argparse
import datetime as dt
import os
import sys
import time
from typing import Any

from stand.cli.common import (
    add_bus_arguments,
    add_live_arguments,
    add_measure_arguments,
    bus_kwargs,
)
from stand.errors import UsageError

DEFAULT_TARGET_PCT = 5.0


def add_arguments(p: argparse.ArgumentParser, *, default_target: str) -> None:
    """The source, the precision target, the limits, the run file."""
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--scene",
        metavar="SCENE",
        help="measure the simulated stand: a shipped scene or a scene file, "
        "played in real time on a private virtual bus",
    )
    p.add_argument("--config", metavar="CFG", help="stand configuration with its [bus] table")
    tgt = p.add_mutually_exclusive_group()
    tgt.add_argument(
        "--target-pct",
        type=float,
        help=f"stop when each plane's 95 %% interval is below this %% of its unbalance "
        f"(default: {default_target})",
    )
    tgt.add_argument(
        "--target-g-mm",
        type=float,
        help="stop when each plane's 95 %% interval is below this [g mm]",
    )
    p.add_argument(
        "--max-seconds",
        type=float,
        default=60.0,
        help="stop after this long in any case (default 60)",
    )
    p.add_argument(
        "--out", metavar="RUN.h5", help="run file to record into (default run-YYYYmmdd-HHMMSS.h5)"
    )
    add_live_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_measure_arguments(p)
    add_bus_arguments(p)


def check(args: argparse.Namespace, command: str) -> None:
    """Refuse targets and limits that are not positive."""
    for name in ("target_pct", "target_g_mm", "max_seconds", "timeout"):
        value = getattr(args, name)
        if value is not None and not value > 0:
            flag = "--" + name.replace("_", "-")
            raise UsageError(f"stand {command}: {flag} must be > 0, got {value}")


def source(args: argparse.Namespace, command: str) -> tuple[Any, Any, dict[str, Any], Any, str]:
    """Config, parameters, bus options, the frames to play (a scene) and the config text."""
    from stand.pipeline import load_config_text

    if args.scene:
        from stand.config import config_toml
        from stand.sim import load_scene, simulate

        scene, params, _ = load_scene(args.scene)
        frames = simulate(scene, params).frames
        channel = f"stand-{command}-{os.getpid()}-{time.monotonic_ns()}"
        cfg = scene.config()
        return cfg, params, {"interface": "virtual", "channel": channel}, frames, config_toml(cfg)
    if not args.config:
        raise UsageError(f"stand {command}: give --config CFG (with its [bus] table) or --scene")
    cfg, params, text = load_config_text(args.config)
    return cfg, params, bus_kwargs(args, cfg.bus), None, text


def run_path(args: argparse.Namespace) -> str:
    """The run file: ``--out`` or a timestamped name."""
    return str(args.out or f"run-{dt.datetime.now():%Y%m%d-%H%M%S}.h5")


def progress_line(p: Any) -> str:
    """One line of the live display."""
    from stand.core import rad_s_to_rpm

    m = p.measurement
    planes = "  ".join(
        f"plane {i + 1}: {abs(m.solution.U_kg_m[i]) * 1e6:.1f} "
        f"+- {m.radius95_kg_m[i] * 1e6:.1f} g mm (precision goal +- {p.targets_kg_m[i] * 1e6:.1f})"
        for i in range(2)
    )
    amps = " ".join(f"{abs(ph.A_m_s2):.3f}" for ph in m.supports)
    rpm = float(rad_s_to_rpm(m.omega_rad_s))
    return f"  {p.elapsed_s:5.1f} s  {rpm:7.1f} rpm  1x {amps} m/s2  {planes}"


def targets_from(args: argparse.Namespace, tolerance_share: float | None = None) -> Any:
    """``targets(cfg, params, U) -> (kg m, kg m)``: the precision the options ask for."""
    from stand.pipeline import precision_targets

    abs_kg_m = None if args.target_g_mm is None else args.target_g_mm * 1e-6

    def targets(cfg: Any, params: Any, U: Any) -> tuple[float, float]:
        return precision_targets(
            cfg, params, U,
            pct=args.target_pct,
            abs_kg_m=abs_kg_m,
            tolerance_share=tolerance_share,
            default_pct=DEFAULT_TARGET_PCT,
        )  # fmt: skip

    return targets


def measure_live(
    args: argparse.Namespace, command: str, targets: Any, options: Any
) -> tuple[Any, Any, Any]:
    """Run the live session until precise: the :class:`stand.result.Result`, config, parameters."""
    from stand.live import LiveSession, measure_until_precise

    check(args, command)
    cfg, params, kwargs, frames, text = source(args, command)
    path = run_path(args)
    quiet = args.quiet

    def show(p: Any) -> None:
        if not quiet:
            print(progress_line(p), file=sys.stderr)

    def wait(elapsed: float, why: str) -> None:
        if not quiet:
            print(f"  {elapsed:5.1f} s  waiting: {why}", file=sys.stderr)

    with LiveSession(
        kwargs, path, config_toml=text, scene_frames=frames, silence_timeout_s=args.timeout
    ) as session:
        if not quiet:
            print(
                f"measuring on {session.where}, recording into {path} (Ctrl-C stops)",
                file=sys.stderr,
            )
        result = measure_until_precise(
            session,
            cfg,
            params,
            options,
            lambda U: targets(cfg, params, U),
            max_seconds=args.max_seconds,
            on_progress=show,
            on_wait=wait,
        )
    if session.failure is not None and not quiet:
        print(f"stand: {session.failure}", file=sys.stderr)
    return result, cfg, params
