"""The registry both hostile matrices fill: a named case per input, in order."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def registry() -> tuple[dict[str, Any], Callable[[str], Callable[[Any], Any]]]:
    """A fresh ``{name: case}`` and the decorator that files a case under a name."""
    cases: dict[str, Any] = {}

    def case(name: str) -> Callable[[Any], Any]:
        def put(fn: Any) -> Any:
            assert name not in cases, f"two cases named {name!r}"
            cases[name] = fn
            return fn

        return put

    return cases, case
