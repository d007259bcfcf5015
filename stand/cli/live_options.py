"""The options of every command that reads a live bus: how long it waits for the first
frame and lets the bus be silent after, and the checks of its targets and limits."""

from __future__ import annotations

import argparse

from stand.errors import UsageError

FIRST_FRAME_S = 30.0
"""How long a live command waits for the first frame by default [s]."""
SILENCE_S = 2.0
"""How long a live command lets the bus be silent once frames came, by default [s]."""


def add_live_arguments(p: argparse.ArgumentParser) -> None:
    """Options of every command that reads a live bus."""
    p.add_argument(
        "--timeout",
        type=float,
        default=None,
        metavar="S",
        help=f"end after S seconds without any frame (default {SILENCE_S:g})",
    )
    p.add_argument(
        "--wait",
        type=float,
        default=None,
        metavar="S",
        help=f"wait up to S seconds for the first frame (default {FIRST_FRAME_S:g}, time to "
        "start the rotor or the simulator in another terminal; with --timeout, that)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines")


def silences(args: argparse.Namespace) -> tuple[float, float]:
    """The silence a live command ends after, and the wait for its first frame [s]:
    ``--timeout`` (:data:`SILENCE_S`) and ``--wait`` (:data:`FIRST_FRAME_S`, or the
    ``--timeout`` given: a script that asked for a short one keeps it)."""
    silence = SILENCE_S if args.timeout is None else args.timeout
    if args.wait is not None:
        return silence, args.wait
    return silence, FIRST_FRAME_S if args.timeout is None else args.timeout


def check_live_arguments(args: argparse.Namespace, command: str) -> None:
    """Refuse targets and limits that are not positive."""
    for name in ("target_pct", "target_g_mm", "max_seconds", "timeout", "wait"):
        value = getattr(args, name)
        if value is not None and not value > 0:
            flag = "--" + name.replace("_", "-")
            raise UsageError(f"stand {command}: {flag} must be > 0, got {value}")
