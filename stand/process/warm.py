"""Modules imported on a thread while the main one waits on something else (a live
measurement's two seconds of physics): what comes after the answer (the archive with
SQLAlchemy and Alembic, the report's matplotlib) is ready when the answer is, instead of
costing its time after it.  Called explicitly by its one user (``stand balance``); the
thread holds no state but the interpreter's own module table."""

from __future__ import annotations

import importlib
import threading
from collections.abc import Sequence


def warm_imports(modules: Sequence[str]) -> threading.Thread:
    """Import ``modules`` on a daemon thread, started; an import that fails is left for the
    caller's own import to raise where it is needed."""

    def run() -> None:
        for name in modules:
            try:
                importlib.import_module(name)
            except Exception:  # the real import says it, where it is needed
                return

    thread = threading.Thread(target=run, name="warm-imports", daemon=True)
    thread.start()
    return thread
