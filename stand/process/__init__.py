"""Process-level tricks, and only here: work forked beside the main process on the second
core (:class:`Beside`, where :func:`can_fork` says it is safe) and glibc's allocator told
how to treat freed memory.  Each buys at least 5 % of a figure in ``docs/performance.md``
and is passed in or called explicitly by its one user; nothing here keeps state between
callers.  Pure standard library: the core and the drivers may use it.
"""

from stand.process.allocator import keep_freed_memory, release_free_memory
from stand.process.beside import Beside, can_fork

__all__ = ["Beside", "can_fork", "keep_freed_memory", "release_free_memory"]
