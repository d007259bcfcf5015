"""The ``stand`` command: one entry point, one module per subcommand.

Each subcommand module offers ``add_arguments(parser)`` and
``run(args) -> int``.  :func:`main` takes ``argv`` and returns the exit
code, so tests call it directly.  Bad input (any :class:`StandError`, any
argument error) is one line on stderr and exit code 2; ``--debug`` shows
the traceback instead.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import weakref
from collections.abc import Callable, Sequence
from types import FrameType

from stand import __version__
from stand.errors import CycleAbortedError, StandError, UsageError
from stand.process import one_blas_thread, skip_last_collection

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_BAD_INPUT = 2
EXIT_ABORTED = 4
"""The stand's cycle was aborted by its supervision (guard, emergency stop, fault,
over-speed): the run is kept, the reason said in one line."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, raised, not printed."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(f"{self.prog}: {message}")


SUBCOMMANDS: dict[str, str] = {
    "balance": "measure live until precise, then the correction per plane, the tolerance, "
    "the check",
    "measure": "measure live until the unbalance is precise enough, recording the run",
    "solve": "solve recorded runs: the unbalance of both planes, with its 95 % interval",
    "report": "write the balancing report of a run: one self-contained HTML file",
    "record": "record the sensor nodes from a CAN bus into an HDF5 run file",
    "inspect": "what a run file or CAN log holds: nodes, frames, losses, speed, warnings",
    "convert": "convert a run between a run file (.h5) and python-can logs",
    "simulate": "simulate a scene: write its run, or play it on a CAN bus in real time",
    "scenes": "list the shipped scenes of the simulated stand",
    "calibrate": "identify the stand (or a new rotor type) from runs with test masses",
    "influence": "influence coefficients (field balancing): corrections from trial runs",
    "advise": "natural frequencies and the recommended balancing speed range",
    "evaluate": "ISO 21940-21's machine tests (U_mar, URR, cross-effect) from a proving "
    "rotor's runs or a scene",
    "capability": "the stand's measurement capability on a master rotor's runs: Cg and Cgk "
    "for the vector unbalance",
    "residual": "a rotor's residual-unbalance check (API): a trial mass at 6 or 12 positions, "
    "the circle through the readings",
    "forward": "support accelerations for given unbalances, and the natural frequencies",
    "runup": "a recorded run-up read as the stand's response: resonances, damping, "
    "separation margins, Bode and polar plots",
    "archive": "the archive of runs: import runs recorded before, verify the run files",
    "history": "find archived runs by serial, rotor type, order, operator, date, verdict",
    "export": "export archived results for the plant's quality system (Q-DAS .dfq)",
    "stats": "production statistics of a rotor type: yield, spread, systematic unbalance",
    "station": "the operator station: a web screen at the stand (measure, correct, check)",
    "opcua": "the OPC UA result server: identification, state and latest result for the MES",
    "jobs": "the job orders the MES sent over OPC UA (OPC 40001-3): their rotors and states",
    "users": "the station's accounts and their roles (operator, setter, engineer, administrator)",
    "audit": "the audit trail of every change (configs, calibrations, matrices, toolings, "
    "accounts, evaluations): list it, verify its hash chain",
    "reprocess": "re-judge archived runs with a corrected config: what changed, the recall list",
    "health": "is the stand still as calibrated? drift alarms from the corrected rotors",
    "autobalance": "a ball balancer on the rotor: the speeds where it balances, what it leaves",
    "tooling": "the tooling's own unbalance (index runs at 0 and 180 deg), subtracted from "
    "every run",
}
"""Each subcommand and its one-line help; its module ``stand.cli.<name>`` is imported only
when it is the one chosen, so ``stand --help`` and ``stand --version`` import none."""


def _chosen(argv: Sequence[str]) -> str | None:
    """The subcommand named in ``argv`` (the first word that is not an option)."""
    for a in argv:
        if not a.startswith("-"):
            return a if a in SUBCOMMANDS else None
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser; with ``command``, that subcommand's arguments too."""
    common = _Parser(add_help=False)
    common.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    parser = _Parser(
        prog="stand",
        description="Host software of a soft-bearing rotor balancing stand (two or more "
        "correction planes).",
        parents=[common],
    )
    parser.add_argument("--version", action="version", version=f"stand {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, doc in SUBCOMMANDS.items():
        help_text = doc.replace("%", "%%")  # argparse
        p = sub.add_parser(name, help=help_text, description=help_text, parents=[common])
        if name == command:
            module = importlib.import_module(f"stand.cli.{name}")
            module.add_arguments(p)
            p.set_defaults(handler_=module.run)  # not `run`: a subcommand may take a RUN
    return parser


INTERRUPT_AGAIN_S = 0.005
"""An interrupt that came inside a finalizer is delivered again this much later [s]."""


def swallowed_there(frame: FrameType | None) -> bool:
    """Whether an exception raised at ``frame`` would be swallowed: inside a weakref
    callback or a ``__del__``, Python prints "Exception ignored" and carries on."""
    while frame is not None:
        code = frame.f_code
        if code.co_name == "__del__" or code.co_filename == weakref.__file__:
            return True
        frame = frame.f_back
    return False


def _interrupt(signum: int, frame: FrameType | None) -> None:
    """Ctrl-C as KeyboardInterrupt, but not where it would be swallowed: there it comes
    again :data:`INTERRUPT_AGAIN_S` later (SIGALRM), so a long command (``stand
    reprocess`` solving run after run) never runs on to its end after an interrupt."""
    if swallowed_there(frame):
        signal.setitimer(signal.ITIMER_REAL, INTERRUPT_AGAIN_S)
        return
    raise KeyboardInterrupt


def entry() -> int:
    """The ``stand`` program (its console script and ``python -m stand.cli``): Ctrl-C that
    always counts (:func:`_interrupt`, unless the program started with SIGINT ignored, as
    under ``nohup``), :func:`main`, then the interpreter's last collection skipped
    (:func:`stand.process.program.skip_last_collection`: 7 % of a 3 s solve)."""
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGALRM, _interrupt)
        signal.signal(signal.SIGINT, _interrupt)
    code = main()
    skip_last_collection()
    return code


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``stand`` command with ``argv`` (default ``sys.argv[1:]``); return the exit code."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args_list
    one_blas_thread()
    chosen = _chosen(args_list)
    try:
        parser = build_parser(chosen)
        args = parser.parse_args(args_list)
        run: Callable[[argparse.Namespace], int] | None = getattr(args, "handler_", None)
        if run is None:
            parser.print_help(sys.stderr)
            return EXIT_BAD_INPUT
        if not debug:  # python-can's readers log a line per line they skip: we count them
            import logging  # here, not at the top: --help and --version need none of it

            logging.getLogger("can").setLevel(logging.ERROR)
            # the 402 profile says "not a configured TPDO, fallback to SDO" at every read of
            # a drive that maps none: the product reads it over SDO on purpose
            logging.getLogger("canopen").setLevel(logging.ERROR)
        return run(args)
    except StandError as exc:
        if debug:
            import traceback

            traceback.print_exc()
        message = str(exc)  # "stand balance: ..." reads "stand: error: balance: ..."
        print(f"stand: error: {message.removeprefix('stand ')}", file=sys.stderr)
        return EXIT_ABORTED if isinstance(exc, CycleAbortedError) else EXIT_BAD_INPUT
    except BrokenPipeError:  # `stand inspect RUN | head -1`: the reader left; end quietly
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_OK
    except KeyboardInterrupt:
        print("stand: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug: say so in one line, keep the traceback for --debug
        if debug:
            import traceback

            traceback.print_exc()
        what = f"{type(exc).__name__}: {exc}"
        print(
            f"stand: internal error: {what} (run with --debug for the traceback)", file=sys.stderr
        )
        return EXIT_INTERNAL
