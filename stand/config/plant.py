"""``[plant]``: how the stand hands its results to the plant's systems."""

from __future__ import annotations

import zoneinfo
from typing import Annotated

from pydantic import BaseModel, Field, field_validator

from stand.config.tables import STRICT

PORT = r"([1-9]\d{0,3}|[1-5]\d{4}|6[0-4]\d{3}|65[0-4]\d{2}|655[0-2]\d|6553[0-5])"
"""A TCP port, 1 to 65535, as a pattern."""
MQTT_URL = rf"^mqtts?://[A-Za-z0-9](?:[A-Za-z0-9.-]{{0,252}})(:{PORT})?/?$"
"""``mqtt[s]://host[:port][/]``: a host name or IPv4 address (letters, digits, dots, hyphens)."""


class PlantTable(BaseModel):
    """``[plant]``: the plant's systems that take each archived result."""

    model_config = STRICT

    mqtt_url: Annotated[str, Field(pattern=MQTT_URL)] | None = None
    """``mqtt://host[:port]`` (1883) or ``mqtts://`` (8883, TLS), the port 1 to 65535: each
    archived result is published as JSON on ``stand/<stand id>/result``."""
    qdas_timezone: Annotated[str, Field(min_length=1, max_length=64)] | None = None
    """The IANA time zone Q-DAS dates (K0004) are written in (``Europe/Berlin``); default
    the machine's own."""

    @field_validator("qdas_timezone")
    @classmethod
    def _known_zone(cls, v: str | None) -> str | None:
        if v is not None:
            try:
                zoneinfo.ZoneInfo(v)
            except (zoneinfo.ZoneInfoNotFoundError, ValueError) as exc:
                raise ValueError(f"no such IANA time zone: {v!r}") from exc
        return v
