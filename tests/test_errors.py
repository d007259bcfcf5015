"""The exception tree: every error is a StandError and a stdlib type, and pickles whole
(batch workers send them to the parent process)."""

from __future__ import annotations

import inspect
import pickle

import pytest

from stand import errors

SAMPLES = {
    "ConfigError": {"source": "cfg.toml", "key": "stand.C1"},
    "JobOrderError": {"bits": 16},
    "ParameterError": {"key": "C1", "message": "must be > 0"},
    "PlanesTooCloseError": {"split_condition": 2e3, "limit": 1e3, "separation_m": 1e-4,
                            "static_unbalance_kg_m": 1e-3 + 2e-3j},
    "NoStatusError": {"node": 2, "frame": 7},
    "RecordingError": {"path": "run.h5", "line": 3},
    "UnusualLogError": {"path": "run.log"},
    "WriteError": {"path": "out.html"},
    "DiskFullError": {"path": "run.h5", "needed_bytes": 10, "free_bytes": 1},
    "BusError": {"channel": "virtual:x", "frames_received": 5},
    "BusTimeoutError": {"channel": "virtual:x", "timeout_s": 2.0},
    "ArchiveError": {"url": "sqlite:///a.sqlite"},
    "ArchiveRowError": {"url": "sqlite:///a.sqlite", "table": "runs", "row": "run 17",
                        "column": "verdict"},
    "ClusterError": {"address": "tcp://10.0.0.1:8786"},
    "StationBusyError": {"running": "the check run of A-1"},
    "RefusedError": {"who": "os:kim", "right": "accounts"},
    "ThrottledError": {"who": "kim", "right": "log in"},
    "KeyFileError": {"path": "audit/stand-key.pem"},
    "TooLargeError": {"what": "run.log", "needed_bytes": 10**11, "available_bytes": 10**10},
    "DriveError": {"where": "modbus 127.0.0.1:502 unit 1"},
    "CycleAbortedError": {"reason": "guard opened at 2.1 s", "run_file": "r.h5"},
}  # fmt: skip
CLASSES = [
    c for _, c in inspect.getmembers(errors, inspect.isclass) if issubclass(c, errors.StandError)
]


def _make(cls: type[errors.StandError]) -> errors.StandError:
    """One instance with every figure set (the message first, where it takes one)."""
    kwargs = SAMPLES.get(cls.__name__, {})
    takes_message = "message" in inspect.signature(cls.__init__).parameters
    if cls.__name__ in ("ParameterError", "PlanesTooCloseError"):
        return cls(**kwargs)
    if cls.__name__ in ("UnusualLogError", "CycleAbortedError"):
        return cls(**kwargs)
    if takes_message or cls.__init__ is Exception.__init__:
        return cls("what went wrong", **kwargs)
    return cls(**kwargs)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_error_pickles_whole_and_is_a_stdlib_type(cls: type[errors.StandError]) -> None:
    err = _make(cls)
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is cls and str(back) == str(err) and back.__dict__ == err.__dict__
    assert (
        any(
            issubclass(cls, t)
            for t in (ValueError, OSError, ConnectionError, RuntimeError, MemoryError)
        )
        or cls is errors.StandError
    )
