"""OPC UA methods that answer a bad call with the specification's status code.

asyncua answers any exception inside a method with ``BadUnexpectedError`` and logs
its traceback.  :func:`guarded` wraps a method so that a call answers as OPC 10000-4
(the Call service) says, and the server says it on one line of stderr:

- fewer input arguments than declared: ``BadArgumentsMissing``;
- more: ``BadTooManyArguments``;
- an argument of another type: ``BadInvalidArgument``, with ``BadTypeMismatch`` in that
  argument's ``InputArgumentResults``;
- a value the product refuses (a :class:`stand.errors.StandError`):
  ``BadInvalidArgument``;
- anything else: ``BadInternalError``, never a traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Awaitable, Callable, Sequence
from typing import Any

from stand.errors import StandError


def _say(name: str, code: str, why: str) -> None:
    print(f"stand opcua: {name}: {why} ({code})", file=sys.stderr, flush=True)


def _bad(name: str, code: str, why: str, per_argument: list[str] | None = None) -> Any:
    from asyncua import ua

    _say(name, code, why)
    res = ua.CallMethodResult()
    res.StatusCode = ua.StatusCode(getattr(ua.StatusCodes, code))
    if per_argument is not None:
        res.InputArgumentResults = [ua.StatusCode(getattr(ua.StatusCodes, c)) for c in per_argument]
    return res


def _kinds(declared: Any) -> tuple[Any, ...]:
    """The VariantTypes an argument may have."""
    return declared if isinstance(declared, tuple) else (declared,)


def guarded(
    name: str, inputs: Sequence[Any], method: Callable[..., Awaitable[list[Any]]]
) -> Callable[..., Awaitable[Any]]:
    """``method(*values)`` (the arguments' values, checked against ``inputs``, their
    ``ua.VariantType`` s, or for an argument several a tuple of them) as an asyncua method
    callback that never raises."""

    async def call(parent: Any, *args: Any) -> Any:
        if len(args) < len(inputs):
            return _bad(name, "BadArgumentsMissing", f"{len(args)} of {len(inputs)} arguments")
        if len(args) > len(inputs):
            return _bad(name, "BadTooManyArguments", f"{len(args)} arguments, it takes "
                        f"{len(inputs)}")  # fmt: skip
        wrong = [a.VariantType not in _kinds(t) for a, t in zip(args, inputs, strict=True)]
        if any(wrong):
            k = wrong.index(True)
            return _bad(
                name, "BadInvalidArgument",
                f"argument {k + 1} is a {args[k].VariantType.name}, not a "
                + " or ".join(t.name for t in _kinds(inputs[k])),
                ["BadTypeMismatch" if w else "Good" for w in wrong],
            )  # fmt: skip
        try:
            return await method(*(a.Value for a in args))
        except StandError as exc:
            return _bad(name, "BadInvalidArgument", str(exc))
        except Exception as exc:
            return _bad(name, "BadInternalError", f"{type(exc).__name__}: {exc}")

    return call
