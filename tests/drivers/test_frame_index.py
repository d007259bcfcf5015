"""A :class:`FrameIndex` reads as the int64 array it stands for, exactly.

Frames numbered with gaps (lost frames) of any size, views of any slice,
every kind of key and search the measuring path takes: each answer is compared
with the same call on the array itself (integers: no tolerance).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.drivers.frame_index import FrameIndex


@st.composite
def frames(draw: st.DrawFn) -> np.ndarray:
    first = draw(st.integers(0, 10**6))
    gaps = draw(st.lists(st.integers(1, 40), min_size=0, max_size=60))
    return first + np.concatenate(([0], np.cumsum(gaps))).astype(np.int64)


def _array(F: np.ndarray) -> np.ndarray:
    return (3 * F[:, None] + np.arange(3)).ravel()


@settings(max_examples=300, deadline=None)
@given(frames(), st.integers(-5, 200), st.integers(-5, 200), st.data())
def test_a_frame_index_is_its_array(F: np.ndarray, a: int, b: int, data: st.DataObject) -> None:
    full, lazy = _array(F), FrameIndex(F, 3)
    want, got = full[a:b], lazy[a:b]  # a view of a view, as the passes take them
    assert isinstance(got, FrameIndex) and len(got) == len(want)
    assert np.array_equal(np.asarray(got), want)
    assert np.array_equal(got.astype(np.float64), want.astype(np.float64))
    assert got.nbytes == want.nbytes
    if len(want):
        i = data.draw(st.integers(-len(want), len(want) - 1))
        assert got[i] == want[i]
        idx = np.array(data.draw(st.lists(st.integers(-len(want), len(want) - 1), max_size=9)))
        assert np.array_equal(got[idx.astype(np.int64)], want[idx.astype(np.int64)])
        mask = np.array(data.draw(st.lists(st.booleans(), min_size=len(want), max_size=len(want))))
        assert np.array_equal(got[mask], want[mask])
        assert np.array_equal(got[::2], want[::2])
    lo = int(3 * F[0]) - 7
    hi = int(3 * F[-1]) + 9
    keys = data.draw(st.lists(st.integers(lo, hi), min_size=1, max_size=20))
    halves = [k + 0.5 for k in keys]
    for v in (np.array(keys), np.array(halves), np.array([-np.inf, np.inf, np.nan, 1e300])):
        for side in ("left", "right"):
            found = np.searchsorted(got, v, side=side)  # type: ignore[call-overload]
            assert np.array_equal(found, np.searchsorted(want, v, side=side))  # type: ignore[call-overload]
    assert got.searchsorted(keys[0]) == want.searchsorted(keys[0])
    # numpy's functions see the array; arithmetic is not offered (take the array)
    assert np.array_equal(np.diff(got), np.diff(want))
    assert np.array_equal(np.isin(want, got), np.ones(len(want), bool))
    with pytest.raises(TypeError):
        got / 4000.0  # type: ignore[operator]


def test_out_of_bounds_is_an_index_error_as_for_the_array() -> None:
    lazy = FrameIndex(np.array([4, 5, 9], np.int64), 3)
    with pytest.raises(IndexError):
        lazy[9]
    with pytest.raises(IndexError):
        lazy[np.array([0, 9])]
    assert lazy[-1] == 29 and len(lazy[5:2]) == 0 and np.asarray(lazy[5:2]).dtype == np.int64
