"""The rotor face the Correct screen draws (SVG text; no plotting library).

The face is seen from the end where the rotor turns counter-clockwise: the
reference mark at the top, angles counted clockwise from it (against the
direction of rotation, the arrow), the holes or blades numbered 1..N when the
correction uses positions, and each correction mass where it goes.  The
convention is the report's polar plots' (:mod:`stand.report.plots`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from html import escape

from stand.i18n.language import ENGLISH, N_, Language

SEEN_FROM = N_("seen from the end where the rotor turns counter-clockwise")
"""The stated end the face is drawn from (the arrow shows the rotation)."""
R_FACE = 150.0
"""The face's radius in the drawing's units (the view box is 480 wide)."""
LABEL = 38
"""The words' size in the drawing's units: drawn 13 rem wide on the Correct screen
(beside the instruction, so that both planes fit 1024 x 768), at least 16 px.  The
masses are the instruction's, in large type beside it: the face marks where (a dot at
each, its mass in the dot's tooltip), and numbers the holes."""


def _xy(angle_deg: float, r: float) -> tuple[float, float]:
    """A point at ``angle_deg`` clockwise from the top, ``r`` from the centre."""
    a = math.radians(angle_deg)
    return r * math.sin(a), -r * math.cos(a)


def _rotation_arrow(_: Language) -> str:
    """An arc outside the face, lower left, from 240 deg back to 200 deg: the rotor turns
    that way (against the angles)."""
    r = R_FACE + 20
    x0, y0 = _xy(240, r)
    x1, y1 = _xy(206, r)
    tip = _xy(198, r)
    wing1, wing2 = _xy(208, r - 9), _xy(208, r + 9)
    lx, ly = _xy(222, r + 16)
    word = escape(_("rotation"))
    return (
        f'<path d="M {x0:.1f} {y0:.1f} A {r} {r} 0 0 0 {x1:.1f} {y1:.1f}" fill="none" '
        f'stroke="#222" stroke-width="3"/>'
        f'<polygon points="{tip[0]:.1f},{tip[1]:.1f} {wing1[0]:.1f},{wing1[1]:.1f} '
        f'{wing2[0]:.1f},{wing2[1]:.1f}" fill="#222"/>'
        f'<text x="{lx + 10:.1f}" y="{ly + 44:.1f}" font-size="{LABEL}" text-anchor="middle">'
        f"{word}</text>"
    )


def face_svg(
    weights: Sequence[tuple[float, str]],
    *,
    positions: int = 0,
    position1_deg: float = 0.0,
    action: str = "add",
    title: str = "",
    words: Language = ENGLISH,
) -> str:
    """The face of one correction plane, as SVG text.

    Parameters
    ----------
    weights
        ``(angle_deg, label)`` per mass to add or remove, the angle from the reference
        mark against the direction of rotation [deg].
    positions, position1_deg
        The holes or blades (0: any angle) and the angle of hole 1 [deg].
    action
        ``add`` (a weight) or ``remove`` (drill): how the masses are drawn.
    title
        Text above the face.
    words
        The language of its words.
    """
    _ = words
    mark = escape(_("reference mark"))
    parts = [
        '<svg xmlns="http://www.w3.org/2000/svg" viewBox="-240 -228 480 456" '
        'role="img" font-family="sans-serif">',
        f"<title>{escape(title)} ({escape(_(SEEN_FROM))})</title>",
        f'<circle r="{R_FACE}" fill="#e8e8e8" stroke="#555" stroke-width="3"/>',
        '<circle r="28" fill="#bbb" stroke="#555" stroke-width="2"/>',
        # the reference mark: a triangle pointing at the face from outside, at the top
        f'<polygon points="0,{-R_FACE - 2} -11,{-R_FACE - 22} 11,{-R_FACE - 22}" fill="#c00"/>',
        f'<text x="0" y="{-R_FACE - 30}" font-size="{LABEL}" text-anchor="middle" fill="#c00">'
        f"{mark}</text>",
        _rotation_arrow(_),
    ]
    if positions:
        for k in range(positions):
            x, y = _xy(position1_deg + 360.0 * k / positions, R_FACE * 0.74)
            lx, ly = _xy(position1_deg + 360.0 * k / positions, R_FACE * 0.91)
            parts.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="9" fill="#fff" stroke="#333"/>')
            parts.append(
                f'<text x="{lx:.1f}" y="{ly + 10:.1f}" font-size="{LABEL}" text-anchor="middle" '
                f'font-weight="bold">{k + 1}</text>'
            )
    colour = "#0a5" if action == "add" else "#c60"
    for angle, label in weights:
        x, y = _xy(angle, R_FACE * 0.74)
        parts.append(
            f'<line x1="0" y1="0" x2="{x:.1f}" y2="{y:.1f}" stroke="{colour}" '
            f'stroke-width="3" stroke-dasharray="6 4"/>'
            f'<circle cx="{x:.1f}" cy="{y:.1f}" r="15" fill="{colour}" stroke="#111" '
            f'stroke-width="2"><title>{escape(label)}</title></circle>'
        )
    parts.append("</svg>")  # which end it is seen from: the title, and the screen's line
    return "".join(parts)
