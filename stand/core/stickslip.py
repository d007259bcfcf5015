"""The balls of a ball balancer sticking and rolling on their race (with rolling
resistance, :attr:`stand.core.balls.Balls.rolling`): which balls are held at rest, the
events that end a mode (a held ball lets go, a rolling one stops), and the modes after
one.  ``sys`` is :mod:`stand.core.balls`' system: its ``b`` (the balls), ``locked`` and
``holding(t, y, held)`` (the force each ball needs to be held, and the most its rolling
resistance gives).

Pure numerics: arrays in, arrays out.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core.model import FloatArray

MAX_SWITCHES = 20_000
"""More stick-slip switches than this in one run are refused: balls chattering on their
race (a rolling resistance at the edge of what holds them) cost a step each."""


def modes_at(sys: Any, t: float, y: FloatArray, held: NDArray[np.bool_],
              slip: FloatArray) -> tuple[NDArray[np.bool_], FloatArray]:  # fmt: skip
    """At rest on the race, each ball is held if its rolling resistance holds it, else
    rolls the way the rest of its forces push it (only with rolling resistance)."""
    if sys.b.rolling <= 0 or sys.locked:
        return held, slip
    need, most = sys.holding(np.array([t]), y[:, None], np.ones(sys.b.n, bool))
    at_rest = np.abs(y[4 + sys.b.n :]) == 0
    keep = at_rest & (np.abs(need[:, 0]) <= most[:, 0])
    rolls = np.where(at_rest, -np.sign(need[:, 0]), np.sign(y[4 + sys.b.n :]))
    return keep, np.where(keep, 0.0, rolls)


def events_of(sys: Any, held: NDArray[np.bool_], slip: FloatArray) -> list[Any]:
    """Per ball: a held one lets go when the force that holds it reaches its rolling
    resistance; a rolling one stops when its speed on the race comes to 0."""
    if sys.b.rolling <= 0 or sys.locked:
        return []
    n, out = sys.b.n, []
    for j in range(n):
        if held[j]:

            def let_go(t: float, z: FloatArray, j: int = j) -> float:
                need, most = sys.holding(np.array([t]), z[:, None], held)
                return float(most[j, 0] - abs(need[j, 0]))

            let_go.terminal, let_go.direction = True, -1  # type: ignore[attr-defined]
            out.append(let_go)
        else:

            def stop(t: float, z: FloatArray, j: int = j) -> float:
                return float(z[4 + n + j])

            stop.terminal, stop.direction = True, -slip[j]  # type: ignore[attr-defined]
            out.append(stop)
    return out


def switch(sys: Any, t: float, y: FloatArray, held: NDArray[np.bool_], slip: FloatArray,
            k: int) -> tuple[NDArray[np.bool_], FloatArray]:  # fmt: skip
    """The modes after ball ``k``'s event: a held ball rolls off, a stopped one is held if
    its resistance holds it, else rolls on the way its forces push it."""
    n = sys.b.n
    held, slip = held.copy(), slip.copy()
    if held[k]:
        need, _ = sys.holding(np.array([t]), y[:, None], held)
        held[k], slip[k] = False, -np.sign(need[k, 0]) or 1.0
        return held, slip
    y[4 + n + k] = 0.0
    trial = held.copy()
    trial[k] = True
    need, most = sys.holding(np.array([t]), y[:, None], trial)
    if abs(need[k, 0]) <= most[k, 0]:
        return trial, np.where(trial, 0.0, slip)
    slip[k] = -np.sign(need[k, 0]) or 1.0
    return held, slip
