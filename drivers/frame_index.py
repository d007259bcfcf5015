"""A node's sample index kept as its frames' numbers (8 bytes a frame, not 24).

Where each frame carries ``k`` samples (protocol v1's SAMPLES frame: 3), sample ``i`` of
a node's stream has the index ``k F[i // k] + i % k``, ``F`` the frame's unwrapped ``seq``.
When every sample is valid and the node never restarted (the common case:
one segment, ``F`` strictly increasing) that is all the index is, and
:class:`FrameIndex` keeps ``F`` alone: a one-hour node's index is 38 MB
instead of 115 MB, and it is never written out whole (on this project's
machine memory written for the first time costs about 2 ms a MB).

It offers what the measuring path asks of a node's index, and no more: ``len``, an
element, a slice (a view: nothing is computed), an integer or boolean array of
positions (an array), ``astype``, ``nbytes`` and ``searchsorted`` (also as ``np.searchsorted``);
``np.asarray`` gives the whole array, for anything else.  Arithmetic and comparisons
are not offered: a caller that needs them takes the array.
``tests/drivers/test_frame_index.py`` checks every one against the array itself.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


class FrameIndex:
    """``k F[i // k] + i % k`` (``k`` samples a frame) for samples ``lo <= i < hi`` (``F``
    strictly increasing)."""

    __slots__ = ("_F", "_hi", "_lo", "_per")

    def __init__(self, F: NDArray[np.int64], per: int, lo: int = 0, hi: int | None = None
                 ) -> None:  # fmt: skip
        self._F = F
        self._per = per
        self._lo = lo
        self._hi = per * len(F) if hi is None else hi

    def __len__(self) -> int:
        return self._hi - self._lo

    @property
    def nbytes(self) -> int:
        """What the array it stands for would take [B] (a run file's size bound)."""
        return 8 * len(self)

    def __repr__(self) -> str:
        return f"FrameIndex({np.asarray(self)!r})"

    def _at(self, g: NDArray[np.int64]) -> NDArray[np.int64]:
        """The values at absolute sample positions ``g``."""
        f, k = np.divmod(g, self._per)
        out: NDArray[np.int64] = self._per * self._F[f] + k
        return out

    def _range(self, lo: int, hi: int) -> NDArray[np.int64]:
        """The values of absolute samples ``lo:hi``, frame by frame (no division per sample)."""
        if hi <= lo:
            return np.zeros(0, np.int64)
        f0, f1 = lo // self._per, -(-hi // self._per)
        rows = np.empty((f1 - f0, self._per), np.int64)
        np.multiply(self._F[f0:f1], self._per, out=rows[:, 0])
        for k in range(1, self._per):
            np.add(rows[:, 0], k, out=rows[:, k])
        first = lo - self._per * f0
        return rows.reshape(-1)[first : first + hi - lo]

    def __array__(self, dtype: Any = None, copy: Any = None) -> NDArray[Any]:
        values = self._range(self._lo, self._hi)
        return values if dtype is None else values.astype(dtype)

    def astype(self, dtype: Any, copy: bool = True) -> NDArray[Any]:
        return np.asarray(self).astype(dtype)

    def __getitem__(self, key: Any) -> Any:
        n = len(self)
        if isinstance(key, (int, np.integer)):
            i = int(key) + (n if key < 0 else 0)
            if not 0 <= i < n:
                raise IndexError(f"index {int(key)} is out of bounds for size {n}")
            return self._at(np.array(self._lo + i))[()]
        if isinstance(key, slice) and key.step in (None, 1):
            start, stop, _ = key.indices(n)
            return FrameIndex(self._F, self._per, self._lo + start, self._lo + max(start, stop))
        k = np.asarray(key)
        if k.dtype.kind in "iu" and k.ndim == 1:
            if len(k) and (k.min() < -n or k.max() >= n):
                raise IndexError(f"an index is out of bounds for size {n}")
            return self._at(self._lo + np.where(k < 0, k + n, k).astype(np.int64))
        return np.asarray(self)[key]

    def searchsorted(self, v: Any, side: str = "left", sorter: None = None) -> Any:
        """Where ``v`` would go to keep the values sorted, as numpy's ``searchsorted``
        (``sorter`` is there for ``np.searchsorted``, which passes None: the values are
        sorted)."""
        keys = np.asarray(v, dtype=np.float64)
        # the values are integers: at or after k is at or after ceil(k); after k is at or
        # after floor(k) + 1
        whole = np.ceil(keys) if side == "left" else np.floor(keys) + 1
        finite = np.isfinite(whole)
        K = np.clip(np.where(finite, whole, 0), -(2**62), 2**62).astype(np.int64)  # past all
        # the first frame whose last sample reaches K, then the sample within it
        f = np.searchsorted(self._F, -((self._per - 1 - K) // self._per), side="left")
        F = self._F[np.minimum(f, len(self._F) - 1)] if len(self._F) else np.zeros_like(K)
        g = np.where(
            f < len(self._F), self._per * f + np.clip(K - self._per * F, 0, self._per - 1),
            self._per * len(self._F),
        )  # fmt: skip
        n = len(self)
        out = np.clip(g - self._lo, 0, n)
        out = np.where(finite, out, np.where(np.isnan(keys) | (whole > 0), n, 0))
        return out if np.ndim(v) else int(out)
