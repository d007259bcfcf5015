"""``[drive] family = "none"``: no drive the product commands (the operator brings the
rotor to speed by other means, presses Start, stops and turns it by hand), as a config
without ``[drive]``."""

from __future__ import annotations

from typing import Any

from stand.errors import UsageError


class NoDrive:
    """The family of stands whose rotor the operator spins: nothing to connect."""

    name = "none"
    table = None
    commanded = False

    def connect(self, table: Any, ctx: Any) -> Any:
        raise UsageError("[drive] family = \"none\": the operator spins the rotor, there "
                         "is no drive to connect to")  # fmt: skip


FAMILY = NoDrive()
