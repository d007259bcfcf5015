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


def refused_in_one_line(argv: list[str], says: str, capsys: Any, limit_s: float) -> list[str]:
    """Run ``stand argv`` in this process and check it was refused as a hostile input must
    be: exit 2, its last stderr line ``stand: error: ...`` holding ``says``, no Python
    warning, no internal error or traceback, within ``limit_s`` (a hang guard); the
    lines of its stderr."""
    import time
    import warnings

    from stand.cli import main

    capsys.readouterr()
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(argv)
    took = time.perf_counter() - t0
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert not caught, [str(w.message) for w in caught]
    assert "internal error" not in err and "Traceback" not in err, err
    assert took < limit_s, f"{took:.1f} s"
    assert code == 2 and lines and lines[-1].startswith("stand: error: "), (code, err)
    assert says in lines[-1], err
    return lines
