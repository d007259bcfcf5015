"""What the ``stand`` program sets for itself before it works, and skips when it ends.

Both are called by the program's entry (:mod:`stand.cli`) and nowhere else; the tests
call :func:`stand.cli.main`, which sets the threads but freezes nothing.

- **One BLAS thread** unless the environment says how many: the arrays here are long
  and thin, so more threads only spin, and with a support measured in a forked process
  (:mod:`stand.process.beside`) they fight for the two cores.  ``stand solve`` of a
  600 s run: 0.58 s against 0.91 s with two threads; one hour: 2.1 against 5.8 s
  (medians, 2026-11-25).
- **The interpreter's last collection skipped**: at exit it visits every object the
  process made (pydantic's schemas, numpy's and h5py's modules ...) only to free memory
  the process hands back anyway.  A 3 s solve: 0.280 against 0.301 s (7 %); 600 s: 4 %.
"""

from __future__ import annotations

import gc
import os

BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""The variables OpenBLAS, OpenMP and MKL read for their thread count."""


def one_blas_thread() -> None:
    """One BLAS thread for numpy, unless the environment already says how many (call
    before numpy loads: BLAS reads the variables once)."""
    for var in BLAS_THREADS:
        os.environ.setdefault(var, "1")


def skip_last_collection() -> None:
    """Leave every object alive now out of the interpreter's collections (``gc.freeze``):
    for a program about to exit.  Files are written and closed before; finalizers
    registered with ``atexit`` or ``weakref.finalize`` still run."""
    gc.freeze()
