"""A progress line on stderr for work that takes longer than a few seconds.

Silent for the first :data:`AFTER_S` seconds (a short job prints nothing more than it
did), then one line at most every :data:`EVERY_S` seconds, each saying how far the work
has come and how long it has run: a user watching a 60 s ball balancer integrate, or a
series of 200 rotors, sees that it moves.  The clock is passed in, so a test drives it.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

AFTER_S = 3.0
"""No line before the work has run this long [s]."""
EVERY_S = 3.0
"""At most one line this often [s]."""


class ProgressLine:
    """Throttled progress lines ``"<what>: <how far> (<n> s)"`` on a stream.

    Parameters
    ----------
    what
        What runs (``"simulating demo-balls"``).
    stream
        Where the lines go (default stderr: stdout stays the answer).
    clock
        Seconds from any origin (default :func:`time.monotonic`).
    """

    def __init__(self, what: str, *, stream: TextIO | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:  # fmt: skip
        self.what = what
        self.stream = stream
        self.clock = clock
        self.start = clock()
        self.last = -float("inf")
        self.lines = 0

    def say(self, how_far: str) -> None:
        """Print ``how_far`` if the work has run :data:`AFTER_S` and no line came within
        :data:`EVERY_S`."""
        now = self.clock()
        if now - self.start < AFTER_S or now - self.last < EVERY_S:
            return
        self.last = now
        self.lines += 1
        print(f"{self.what}: {how_far} ({now - self.start:.0f} s)",
              file=self.stream or sys.stderr, flush=True)  # fmt: skip

    def simulated(self, t_s: float, end_s: float) -> None:
        """A simulation's physics time reached of its end [s] (a ``simulate`` progress)."""
        self.say(f"{min(max(t_s, 0.0), end_s):.0f} of {end_s:.0f} s simulated")

    def count(self, done: int, total: int, noun: str) -> None:
        """``done`` of ``total`` things (``"rotor"``) finished."""
        self.say(f"{noun} {done} of {total} done")
