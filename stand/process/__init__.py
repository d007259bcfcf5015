"""Process-level tricks, and only here: work forked beside the main process on the second
core (:class:`Beside`, where :func:`can_fork` says it is safe), glibc's free memory handed
back before that fork (or kept, by a process that solves run after run), and what the
program sets for itself (one BLAS thread) and skips at exit (the last collection), and
what is imported on a thread while a live measurement waits (:func:`warm_imports`).  Each
buys at least 5 % of a figure in ``docs/performance.md`` and is passed in or called
explicitly by its one user; nothing here keeps state between callers.  Pure standard
library: the core and the drivers may use it.
"""

from stand.process.allocator import keep_freed_memory, release_free_memory
from stand.process.beside import Beside, can_fork
from stand.process.program import one_blas_thread, skip_last_collection
from stand.process.warm import warm_imports

__all__ = [
    "Beside",
    "can_fork",
    "keep_freed_memory",
    "one_blas_thread",
    "release_free_memory",
    "skip_last_collection",
    "warm_imports",
]
