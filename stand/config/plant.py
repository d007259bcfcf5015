"""``[plant]``: how the stand hands its results to the plant's systems."""

from __future__ import annotations

import zoneinfo
from typing import Annotated

from pydantic import BaseModel, Field, field_validator, model_validator

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
    mqtt_password_file: Annotated[str, Field(min_length=1, max_length=4096)] | None = None
    """A file with the broker's user name (first line) and password (second line): never
    in the URL, never in the run files (only this path is)."""
    mqtt_ca_file: Annotated[str, Field(min_length=1, max_length=4096)] | None = None
    """With ``mqtts://``: the CA (PEM) the broker's certificate is checked against (else
    the system's trust store)."""
    mqtt_cert_file: Annotated[str, Field(min_length=1, max_length=4096)] | None = None
    """With ``mqtts://``: the stand's client certificate (PEM), with ``mqtt_key_file``."""
    mqtt_key_file: Annotated[str, Field(min_length=1, max_length=4096)] | None = None
    """The client certificate's private key (PEM)."""
    qdas_timezone: Annotated[str, Field(min_length=1, max_length=64)] | None = None
    """The IANA time zone Q-DAS dates (K0004) are written in (``Europe/Berlin``); default
    the machine's own."""

    @model_validator(mode="after")
    def _tls_files(self) -> PlantTable:
        if (self.mqtt_cert_file is None) != (self.mqtt_key_file is None):
            raise ValueError("mqtt_cert_file and mqtt_key_file go together")
        tls = (self.mqtt_url or "").startswith("mqtts://")
        if not tls and (self.mqtt_ca_file or self.mqtt_cert_file):
            raise ValueError("mqtt_ca_file, mqtt_cert_file and mqtt_key_file need mqtts://")
        if (self.mqtt_password_file or self.mqtt_ca_file) and not self.mqtt_url:
            raise ValueError("the broker's files need mqtt_url")
        return self

    @field_validator("qdas_timezone")
    @classmethod
    def _known_zone(cls, v: str | None) -> str | None:
        if v is not None:
            try:
                zoneinfo.ZoneInfo(v)
            except (zoneinfo.ZoneInfoNotFoundError, ValueError) as exc:
                raise ValueError(f"no such IANA time zone: {v!r}") from exc
        return v
