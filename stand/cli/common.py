"""Argument parsing and printing shared by the subcommands (units at the edge)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterable

from stand.core import Diagnostic
from stand.errors import StandError


class UsageError(StandError, ValueError):
    """A command-line argument is missing or malformed."""


def parse_rpm(text: str) -> float:
    """``--rpm`` value: a finite speed > 0 [rpm]."""
    try:
        rpm = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a speed in rpm, got {text!r}") from None
    if not math.isfinite(rpm) or rpm <= 0:
        raise argparse.ArgumentTypeError(f"expected a finite speed > 0 rpm, got {text!r}")
    return rpm


def parse_unbalance(text: str) -> tuple[float, float]:
    """``G_MM@DEG``: unbalance ``q R`` [g mm] >= 0 at the seed's angle phi [deg]."""
    parts = text.split("@")
    try:
        if len(parts) != 2:
            raise ValueError
        g_mm, deg = float(parts[0]), float(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected G_MM@DEG (e.g. 5000@30), got {text!r}"
        ) from None
    if not (math.isfinite(g_mm) and math.isfinite(deg)) or g_mm < 0:
        raise argparse.ArgumentTypeError(
            f"expected a finite unbalance >= 0 g mm and a finite angle, got {text!r}"
        )
    return g_mm, deg


def print_warnings(warnings: Iterable[Diagnostic]) -> None:
    """Warnings to stderr, one line each."""
    for w in warnings:
        print(f"warning: {w.message}", file=sys.stderr)
