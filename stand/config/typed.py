"""Values a user types: speeds, masses, angles, unbalances, positive numbers, dates.

Each parser gives the value in the units it names, or one line naming what is wrong
(raised as argparse's ``ArgumentTypeError``, so a parser is an argument's ``type=``).
Not part of the CLI's modules: the subcommands parse with them, as a screen could.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math

from stand.core.model import MAX_SPEED_RPM


def parse_rpm(text: str) -> float:
    """``--rpm`` value: a finite speed > 0 [rpm], at most the model's ``MAX_SPEED_RPM``."""

    try:
        rpm = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a speed in rpm, got {text!r}") from None
    if not math.isfinite(rpm) or rpm <= 0:
        raise argparse.ArgumentTypeError(f"expected a finite speed > 0 rpm, got {text!r}")
    if rpm > MAX_SPEED_RPM:
        raise argparse.ArgumentTypeError(
            f"{text} rpm is beyond any balancing stand (at most {MAX_SPEED_RPM:g} rpm)"
        )
    return rpm


def positive_float(text: str) -> float:
    """A finite number > 0 (a mass, a length)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def parse_mass(text: str) -> tuple[int, float, float, float | None]:
    """``PLANE:GRAMS@DEG[:RADIUS_MM]``: a mass on (grams > 0) or off (< 0) the simulated
    rotor, at an angle from the reference mark against the direction of rotation."""
    try:
        plane_text, rest = text.split(":", 1)
        mass_text, angle_text = rest.split("@", 1)
        angle_text, _, radius_text = angle_text.partition(":")
        plane, grams, deg = int(plane_text), float(mass_text), float(angle_text)
        radius = float(radius_text) if radius_text else None
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected PLANE:GRAMS@DEG[:RADIUS_MM] (e.g. 1:20@90), got {text!r}"
        ) from None
    if plane not in (1, 2) or not all(map(math.isfinite, (grams, deg))):
        raise argparse.ArgumentTypeError(f"expected plane 1 or 2 and finite numbers, got {text!r}")
    if radius is not None and not (math.isfinite(radius) and radius > 0):
        raise argparse.ArgumentTypeError(f"expected a radius > 0 mm, got {text!r}")
    return plane, grams, deg, radius


def parse_angle(text: str) -> float:
    """An angle [deg], finite."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an angle in degrees, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite angle, got {text!r}")
    return value


def parse_unbalance(text: str) -> tuple[float, float]:
    """``G_MM@DEG``: unbalance ``q R`` [g mm] >= 0 at an angle [deg] from the reference mark,
    against the direction of rotation (the model's ``phi``)."""
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
    if g_mm > MAX_UNBALANCE_G_MM:
        raise argparse.ArgumentTypeError(
            f"{g_mm:g} g mm is beyond any rotor (at most {MAX_UNBALANCE_G_MM:g} g mm: a tonne "
            "at a metre)"
        )
    return g_mm, deg


MAX_UNBALANCE_G_MM = 1e9
"""The largest unbalance typed in: 1 t at 1 m (the model's arithmetic stays meaningful)."""


def parse_date(text: str) -> dt.date:
    """A calendar day typed as ``YYYY-MM-DD`` (ISO 8601): the archive's ``--since`` and
    ``--until``."""
    try:
        return dt.date.fromisoformat(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a date YYYY-MM-DD, got {text!r}") from None
