"""Why a live run goes on, in the operator's words (``stand.live.loop.waiting_for``): the
Measure screen says it instead of "precise" beside "measure longer"."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from stand.live.loop import waiting_for
from stand.measuring.measure import MIN_REVS


def _m(short: bool, radii: list[float]) -> SimpleNamespace:
    warnings = [SimpleNamespace(code="short_window")] if short else []
    windows = [SimpleNamespace(revolutions=12.7), SimpleNamespace(revolutions=14.0)]
    return SimpleNamespace(warnings=warnings, windows=windows, radius95_kg_m=np.array(radii))


def test_each_reason_in_words_and_none_when_done() -> None:
    got = waiting_for(_m(True, [1.0, 3.0]), (2.0, 2.0), settled=False)
    assert got == (f"more revolutions (12 of {MIN_REVS})",
                   "plane 2's 95 % interval to shrink to its goal",
                   "the ball balancer's balls to settle")  # fmt: skip
    assert waiting_for(_m(False, [1.0, 2.0]), (2.0, 2.0), settled=True) == ()
    # precise in both planes but too few revolutions: that alone keeps it measuring
    assert waiting_for(_m(True, [1.0, 1.0]), (2.0, 2.0), settled=True) == (
        f"more revolutions (12 of {MIN_REVS})",
    )
