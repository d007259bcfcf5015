"""A parsed TOML table validated against its pydantic model, the failure as one
:class:`~stand.errors.ConfigError` naming the file, the first bad key and what is wrong."""

from __future__ import annotations

from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from stand.errors import ConfigError

_UNION_MEMBERS = {"str", "int", "float", "bool"}
BUS_VALUE = "expected text, a number or true/false (a can.Bus option), got {got}"


SHOWN_CHARS = 80
"""A refused value is quoted up to this many characters (a 10^4-entry list is no message)."""


def shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= SHOWN_CHARS else text[: SHOWN_CHARS - 3] + "..."


def _describe(err: dict[str, Any]) -> tuple[str, str]:
    loc = [str(x) for x in err["loc"]]
    if err["type"] == "bus_value":
        return f"bus.{err['ctx']['key']}", str(err["msg"])
    if loc and loc[0] == "bus" and loc[-1] in _UNION_MEMBERS:  # one error per member of the union
        return ".".join(loc[:-1]), BUS_VALUE.format(got=shown(err["input"]))
    key = ".".join(loc)
    msg = str(err["msg"])
    if err["type"] == "extra_forbidden":
        msg = "unknown key (not part of the configuration)" if len(loc) > 1 else "unknown table"
    elif err["type"] == "value_error" and not loc:  # a whole table's check: its own words
        msg = msg.removeprefix("Value error, ")
    elif err["type"] != "missing":
        msg = f"{msg}, got {shown(err['input'])}"
    return key, msg


M = TypeVar("M", bound=BaseModel)


def validate(model: type[M], data: dict[str, Any], source: str, prefix: str = "") -> M:
    """Validate parsed TOML against a pydantic model; one :class:`ConfigError` if it fails.

    The error names ``source``, the first bad key and what is wrong with it;
    an unknown key is reported first (it is usually a typo, and the cause of
    a "missing" one).  ``prefix`` goes before the key (``"autobalancer."``: a table
    validated on its own, named as in the file).
    """
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        errors = sorted(exc.errors(), key=lambda e: e["type"] != "extra_forbidden")
        described = list(dict.fromkeys(_describe(dict(e)) for e in errors))
        key, msg = described[0]
        more = f" (and {len(described) - 1} more)" if len(described) > 1 else ""
        raise ConfigError(msg + more, source=source, key=(prefix + key).rstrip(".")) from None
