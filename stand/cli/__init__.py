"""The ``stand`` command: one entry point, one module per subcommand.

Each subcommand module offers ``add_arguments(parser)`` and
``run(args) -> int``.  :func:`main` takes ``argv`` and returns the exit
code, so tests call it directly.  Bad input (any :class:`StandError`, any
argument error) is one line on stderr and exit code 2; ``--debug`` shows
the traceback instead.
"""

from __future__ import annotations

import argparse
import sys
import traceback
from collections.abc import Callable, Sequence
from types import ModuleType

from stand import __version__
from stand.errors import StandError, UsageError

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_BAD_INPUT = 2


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, raised, not printed."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(f"{self.prog}: {message}")


def _subcommands() -> dict[str, ModuleType]:
    from stand.cli import (
        advise,
        balance,
        calibrate,
        convert,
        evaluate,
        forward,
        influence,
        inspect,
        measure,
        record,
        report,
        scenes,
        simulate,
        solve,
    )

    return {
        "balance": balance,
        "advise": advise,
        "calibrate": calibrate,
        "evaluate": evaluate,
        "forward": forward,
        "influence": influence,
        "solve": solve,
        "measure": measure,
        "simulate": simulate,
        "scenes": scenes,
        "record": record,
        "inspect": inspect,
        "convert": convert,
        "report": report,
    }


def build_parser() -> argparse.ArgumentParser:
    """The whole argument parser (subcommands included)."""
    common = _Parser(add_help=False)
    common.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    parser = _Parser(
        prog="stand",
        description="Host software of a soft-bearing two-plane rotor balancing stand.",
        parents=[common],
    )
    parser.add_argument("--version", action="version", version=f"stand {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, module in _subcommands().items():
        doc = (module.__doc__ or "").strip().splitlines()[0].replace("%", "%%")  # argparse
        p = sub.add_parser(name, help=doc, description=doc, parents=[common])
        module.add_arguments(p)
        p.set_defaults(handler_=module.run)  # not `run`: a subcommand may take a RUN
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``stand`` command with ``argv`` (default ``sys.argv[1:]``); return the exit code."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args_list
    try:
        parser = build_parser()
        args = parser.parse_args(args_list)
        run: Callable[[argparse.Namespace], int] | None = getattr(args, "handler_", None)
        if run is None:
            parser.print_help(sys.stderr)
            return EXIT_BAD_INPUT
        return run(args)
    except StandError as exc:
        if debug:
            traceback.print_exc()
        print(f"stand: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("stand: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug: say so in one line, keep the traceback for --debug
        if debug:
            traceback.print_exc()
        what = f"{type(exc).__name__}: {exc}"
        print(
            f"stand: internal error: {what} (run with --debug for the traceback)", file=sys.stderr
        )
        return EXIT_INTERNAL
