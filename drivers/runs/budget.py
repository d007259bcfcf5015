"""Memory budgets: what a command will need, estimated from a file's size or a scene, and
refused before anything is allocated when this machine does not have it.

The figures per frame and per byte are measured (``tests/bench/bench_long.py`` and the
scene simulator on the demo stand, peak resident memory over the size) and rounded up;
the check is against the memory the kernel reports available (``MemAvailable``), less a
quarter kept for everything else.
"""

from __future__ import annotations

import os
from pathlib import Path

from stand.errors import TooLargeError

HEADROOM = 0.75
"""The share of the available memory one command may plan to use."""
BYTES_PER_FRAME = 400
"""Peak memory per frame of a run read into streams and measured (measured: see module)."""
CANDUMP_LINE_BYTES = 38
"""The shortest candump line of a sensor frame (``(s.us) c ID#16hex``): frames per byte."""
SLOW_TEXT_FACTOR = 12
"""The regular-expression reader of an unusual text log: peak memory over the file's size."""


def available_bytes() -> int:
    """Memory available to a new allocation [bytes] (``MemAvailable``; else the physical
    memory)."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 1 << 62


def check_budget(need_bytes: float, what: str, doing: str) -> None:
    """Refuse (:class:`TooLargeError`) work that needs more than :data:`HEADROOM` of the
    available memory."""
    have = available_bytes()
    if need_bytes > HEADROOM * have:
        raise TooLargeError(doing, what=what, needed_bytes=int(need_bytes), available_bytes=have)


def frames_budget(frames: float, what: str, doing: str = "to read and measure") -> None:
    """A run of ``frames`` frames, read and measured (or made: ``doing``)."""
    check_budget(frames * BYTES_PER_FRAME, what, f"{frames:.3g} frames {doing}")


def log_budget(path: Path) -> None:
    """A candump log of its size (as many frames as its bytes allow)."""
    size = path.stat().st_size
    frames_budget(size / CANDUMP_LINE_BYTES, f"{path} ({size / 1e9:.3g} GB)")


def slow_text_budget(path: Path) -> None:
    """An unusual text log read whole by the regular expression."""
    size = path.stat().st_size
    check_budget(size * SLOW_TEXT_FACTOR, f"{path} ({size / 1e9:.3g} GB)",
                 "a log of an unusual layout, read whole")  # fmt: skip
