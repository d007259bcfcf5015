"""Units the operator sees: grams or ounces, millimetres or inches.

Inside, everything is SI; the JSON keeps g, mm and g mm (its keys say so).
Only the text, the live panel and the report convert, through
:class:`Display`, chosen by the config's ``[display]`` table.

>>> d = Display("oz", "in")
>>> d.mass(28.349523125), d.length(25.4), d.unbalance(720.077887375)
('1.000 oz', '1.000 in', '1.000 oz in')
>>> Display().unbalance(5000.0)
'5000.0 g mm'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

G_PER_OZ = 28.349523125
"""Grams in an avoirdupois ounce (exact by definition)."""
MM_PER_IN = 25.4
"""Millimetres in an inch (exact by definition)."""


@dataclass(frozen=True)
class Display:
    """How masses [g], lengths [mm] and unbalances [g mm] are shown."""

    mass_unit: str = "g"
    length_unit: str = "mm"

    @classmethod
    def of(cls, out: dict[str, Any]) -> Display:
        """The units a result's JSON form asks for (``display``; g and mm without)."""
        d = out.get("display") or {}
        return cls(d.get("mass", "g"), d.get("length", "mm"))

    @property
    def unbalance_unit(self) -> str:
        return f"{self.mass_unit} {self.length_unit}"

    def mass_value(self, g: float) -> float:
        return g / G_PER_OZ if self.mass_unit == "oz" else g

    def length_value(self, mm: float) -> float:
        return mm / MM_PER_IN if self.length_unit == "in" else mm

    def unbalance_value(self, g_mm: float) -> float:
        return self.length_value(self.mass_value(g_mm))

    def mass(self, g: float) -> str:
        """``55.55 g`` or ``1.959 oz``."""
        digits = 3 if self.mass_unit == "oz" else 2
        return f"{self.mass_value(g):.{digits}f} {self.mass_unit}"

    def length(self, mm: float) -> str:
        """``90 mm`` or ``3.543 in``."""
        if self.length_unit == "in":
            return f"{self.length_value(mm):.3f} in"
        return f"{mm:g} mm"

    def depth(self, mm: float) -> str:
        """A depth to machine: ``16.5 mm`` (to 0.01 mm) or ``0.6496 in``."""
        if self.length_unit == "in":
            return f"{self.length_value(mm):.4f} in"
        return f"{round(mm, 2):g} mm"

    def hole(self, h: dict[str, Any]) -> str:
        """One drilled hole of a result's JSON form, in the machinist's words."""
        return (
            f"hole {h['number']} at {h['angle_deg']:.1f} deg: {self.length(h['diameter_mm'])} "
            f"drill ({h['point_angle_deg']:g} deg point), {self.depth(h['depth_mm'])} deep to "
            f"the tip ({self.mass(h['mass_g'])})"
        )

    def slot(self, s: dict[str, Any]) -> str:
        """A milled slot of a result's JSON form, in the machinist's words."""
        return (
            f"slot centred at {s['angle_deg']:.1f} deg over {s['arc_deg']:.1f} deg "
            f"({self.depth(s['arc_length_mm'])} of arc): {self.length(s['width_mm'])} wide, "
            f"{self.depth(s['depth_mm'])} deep ({self.mass(s['mass_g'])})"
        )

    def cuts(self, plane: dict[str, Any]) -> str:
        """Where a plane's holes or slot go in: ``radial holes into radius 90 mm``."""
        holes, slot = plane.get("holes") or [], plane.get("slot")
        if slot:
            return f"mill into radius {self.length(slot['entry_radius_mm'])}"
        if not holes:
            return "no cut"
        n = len(holes)
        where = "into radius" if holes[0]["direction"] == "radial" else "parallel to the axis at"
        return (
            f"drill {n} {holes[0]['direction']} hole{'s' if n > 1 else ''} {where} "
            f"{self.length(holes[0]['entry_radius_mm'])}"
        )

    def unbalance(self, g_mm: float) -> str:
        """``5000.0 g mm``, or about as many digits in other units."""
        return f"{self.number(g_mm)} {self.unbalance_unit}"

    def number(self, g_mm: float) -> str:
        """An unbalance without its unit (for tables whose heading names it): 0.1 g mm, or
        about 4 significant digits in other units (0.0001 at least)."""
        value = self.unbalance_value(g_mm)
        if self.unbalance_unit == "g mm":
            return f"{value:.1f}"
        size = abs(value)
        digits = 1 if size >= 1000 else 2 if size >= 10 else 3 if size >= 1 else 4
        return f"{value:.{digits}f}"
