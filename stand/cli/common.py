"""Argument parsing and printing shared by the subcommands (units at the edge)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterable, Mapping

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


def add_bus_arguments(p: argparse.ArgumentParser) -> None:
    """python-can's usual bus options; they override the config's ``[bus]`` table."""
    g = p.add_argument_group("bus (override the config's [bus] table)")
    g.add_argument(
        "-i",
        "--interface",
        help="python-can interface: socketcan, pcan, kvaser, vector, slcan, virtual, ...",
    )
    g.add_argument("-c", "--channel", help="channel, e.g. can0, PCAN_USBBUS1, 0")
    g.add_argument("-b", "--bitrate", type=int, help="bit rate [bit/s]")
    g.add_argument("--fd", action="store_true", default=None, help="CAN FD interface mode")
    g.add_argument("--data-bitrate", type=int, help="CAN FD data-phase bit rate [bit/s]")
    g.add_argument(
        "--bus-option",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="any other can.Bus option (repeatable); VALUE is read as int, float, "
        "true/false, else text",
    )


def _option_value(text: str) -> str | int | float | bool:
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def bus_kwargs(args: argparse.Namespace, table: Mapping[str, object] | None) -> dict[str, object]:
    """The ``[bus]`` table with the command-line options applied (what goes to ``can.Bus``)."""
    kwargs = dict(table or {})
    for key in ("interface", "channel", "bitrate", "fd", "data_bitrate"):
        value = getattr(args, key, None)
        if value is not None:
            kwargs[key] = value
    for item in args.bus_option:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise UsageError(f"--bus-option: expected KEY=VALUE, got {item!r}")
        kwargs[key.strip()] = _option_value(value.strip())
    return kwargs


def add_live_arguments(p: argparse.ArgumentParser) -> None:
    """Options of every command that reads a live bus."""
    p.add_argument(
        "--timeout",
        type=float,
        default=2.0,
        metavar="S",
        help="end after S seconds without any frame (default 2)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines")
