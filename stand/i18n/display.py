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

from dataclasses import dataclass, field
from typing import Any

from stand.i18n.language import ENGLISH, N_, Language

G_PER_OZ = 28.349523125
"""Grams in an avoirdupois ounce (exact by definition)."""
MM_PER_IN = 25.4
"""Millimetres in an inch (exact by definition)."""
SYMBOLS = (N_("g"), N_("mm"), N_("g mm"), N_("oz"), N_("in"), N_("oz in"))
"""The units' symbols, as each language writes them (Ukrainian in Cyrillic: г, мм)."""


@dataclass(frozen=True)
class Display:
    """How masses [g], lengths [mm] and unbalances [g mm] are shown: the units, the
    decimal sign of the reader's language (``1.5`` or ``1,5``) and its symbols for the
    units (``words``)."""

    mass_unit: str = "g"
    length_unit: str = "mm"
    decimal: str = "."
    words: Language = field(default=ENGLISH, compare=False)

    @classmethod
    def of(cls, out: dict[str, Any], _: Language = ENGLISH) -> Display:
        """The units a result's JSON form asks for (``display``; g and mm without), in the
        language ``_``."""
        d = out.get("display") or {}
        return cls(d.get("mass", "g"), d.get("length", "mm"), _.decimal, _)

    @classmethod
    def speaking(cls, _: Language, mass: str = "g", length: str = "mm") -> Display:
        """The units ``mass`` and ``length`` in the language ``_``."""
        return cls(mass, length, _.decimal, _)

    def symbol(self, unit: str) -> str:
        """A unit's symbol (``g``, ``mm``, ``g mm``, ...) as this display's language
        writes it."""
        return self.words(unit)

    def decimals(self, text: str) -> str:
        """Figures written with this display's decimal sign (``30.0`` -> ``30,0``)."""
        return text if self.decimal == "." else text.replace(".", self.decimal)

    @property
    def unbalance_unit(self) -> str:
        """The unbalance's unit as shown (``g mm``; Ukrainian ``г·мм``)."""
        return self.symbol(f"{self.mass_unit} {self.length_unit}")

    def mass_value(self, g: float) -> float:
        return g / G_PER_OZ if self.mass_unit == "oz" else g

    def length_value(self, mm: float) -> float:
        return mm / MM_PER_IN if self.length_unit == "in" else mm

    def unbalance_value(self, g_mm: float) -> float:
        return self.length_value(self.mass_value(g_mm))

    def mass(self, g: float) -> str:
        """``55.55 g`` or ``1.959 oz``."""
        digits = 3 if self.mass_unit == "oz" else 2
        return self.decimals(f"{self.mass_value(g):.{digits}f}") + f" {self.symbol(self.mass_unit)}"

    def length(self, mm: float) -> str:
        """``90 mm`` or ``3.543 in``."""
        if self.length_unit == "in":
            return self.decimals(f"{self.length_value(mm):.3f}") + f" {self.symbol('in')}"
        return self.decimals(f"{mm:g}") + f" {self.symbol('mm')}"

    def depth(self, mm: float) -> str:
        """A depth to machine: ``16.5 mm`` (to 0.01 mm) or ``0.6496 in``."""
        if self.length_unit == "in":
            return self.decimals(f"{self.length_value(mm):.4f}") + f" {self.symbol('in')}"
        return self.decimals(f"{round(mm, 2):g}") + f" {self.symbol('mm')}"

    def hole(self, h: dict[str, Any], _: Language = ENGLISH) -> str:
        """One drilled hole of a result's JSON form, in the machinist's words."""
        return _("hole {n} at {angle} deg: {diameter} drill ({point} deg point), {depth} deep "
                 "to the tip ({mass})").format(
            n=h["number"], angle=self.decimals(f"{h['angle_deg']:.1f}"),
            diameter=self.length(h["diameter_mm"]),
            point=f"{h['point_angle_deg']:g}", depth=self.depth(h["depth_mm"]),
            mass=self.mass(h["mass_g"]))  # fmt: skip

    def slot(self, s: dict[str, Any], _: Language = ENGLISH) -> str:
        """A milled slot of a result's JSON form, in the machinist's words."""
        return _("slot centred at {angle} deg over {arc} deg ({length} of arc): {width} wide, "
                 "{depth} deep ({mass})").format(
            angle=self.decimals(f"{s['angle_deg']:.1f}"), arc=self.decimals(f"{s['arc_deg']:.1f}"),
            length=self.depth(s["arc_length_mm"]), width=self.length(s["width_mm"]),
            depth=self.depth(s["depth_mm"]), mass=self.mass(s["mass_g"]))  # fmt: skip

    def cuts(self, plane: dict[str, Any], _: Language = ENGLISH) -> str:
        """Where a plane's holes or slot go in: ``radial holes into radius 90 mm``."""
        holes, slot = plane.get("holes") or [], plane.get("slot")
        if slot:
            return _("mill into radius {radius}").format(
                radius=self.length(slot["entry_radius_mm"])
            )
        if not holes:
            return _("no cut")
        n, radius = len(holes), self.length(holes[0]["entry_radius_mm"])
        radial = holes[0]["direction"] == "radial"
        if n == 1:
            text = (
                _("drill 1 radial hole into radius {radius}")
                if radial
                else _("drill 1 axial hole parallel to the axis at {radius}")
            )
        else:
            text = (
                _("drill {n} radial holes into radius {radius}")
                if radial
                else _("drill {n} axial holes parallel to the axis at {radius}")
            )
        return text.format(n=n, radius=radius)  # fmt: skip

    def unbalance(self, g_mm: float) -> str:
        """``5000.0 g mm``, or about as many digits in other units."""
        return f"{self.number(g_mm)} {self.unbalance_unit}"

    def number(self, g_mm: float) -> str:
        """An unbalance without its unit (for tables whose heading names it): 0.1 g mm, or
        about 4 significant digits in other units (0.0001 at least)."""
        value = self.unbalance_value(g_mm)
        if (self.mass_unit, self.length_unit) == ("g", "mm"):
            return self.decimals(f"{value:.1f}")
        size = abs(value)
        digits = 1 if size >= 1000 else 2 if size >= 10 else 3 if size >= 1 else 4
        return self.decimals(f"{value:.{digits}f}")
