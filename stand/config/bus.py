"""``[bus]``: which family of acquisition hardware reads the stand (``protocol``, a name
of :data:`stand.drivers.family.FAMILIES`) and that family's own ``[bus.<name>]`` table,
checked by its model when the config is loaded; every other key of ``[bus]`` is
python-can's, passed on to ``can.Bus`` as it is (:func:`stand.drivers.bus.open_bus`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from stand.config.validation import validate
from stand.drivers.family import DEFAULT, Acquisition, family_of
from stand.errors import ConfigError


@dataclass(frozen=True)
class BusChoice:
    """The family a ``[bus]`` table names, and its checked ``[bus.<name>]`` table (None for
    a family that takes none)."""

    family: Acquisition
    table: Any

    @property
    def name(self) -> str:
        return self.family.name


def bus_choice(bus: dict[str, Any] | None, source: str) -> BusChoice:
    """The ``[bus]`` table's family and its checked table.

    Raises
    ------
    ConfigError
        An unknown family, its table missing or wrong, or a table of another family.
    """
    bus = bus or {}
    name = bus.get("protocol", DEFAULT)
    if not isinstance(name, str):
        raise ConfigError(f"expected a family name, got {name!r}", source=source,
                          key="bus.protocol")  # fmt: skip
    fam = family_of(name, source)
    tables = [k for k, v in bus.items() if isinstance(v, dict)]
    others = [k for k in tables if k != name]
    if others:
        raise ConfigError(f"[bus.{others[0]}] is read by protocol = {others[0]!r}, but the "
                          f"config says protocol = {name!r}", source=source)  # fmt: skip
    if fam.table is None:
        return BusChoice(fam, None)
    table = bus.get(name)
    if not isinstance(table, dict):
        raise ConfigError(f"[bus] protocol = {name!r} needs a [bus.{name}] table",
                          source=source)  # fmt: skip
    return BusChoice(fam, validate(fam.table, table, source, prefix=f"bus.{name}."))
