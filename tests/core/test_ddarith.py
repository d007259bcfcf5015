"""Double-double arithmetic: one number kept as Python floats gives the same bits as an
array of numbers (the same IEEE operations, in the same order)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.core import StandParameters, forward
from stand.core.ddarith import DD

FINITE = st.floats(-1e150, 1e150, allow_nan=False, allow_infinity=False).filter(
    lambda x: x == 0 or abs(x) > 1e-150
)


def _bits(x: DD) -> tuple[float, float]:
    return float(np.asarray(x.hi).ravel()[0]), float(np.asarray(x.lo).ravel()[0])


@settings(max_examples=200, deadline=None)
@given(a=FINITE, b=FINITE, c=FINITE.filter(lambda x: x != 0))
def test_a_scalar_is_computed_as_a_one_element_array(a: float, b: float, c: float) -> None:
    """``(a + b) * c - a / c`` and ``b / (a - c)``: exactly equal, hi and lo, whether the
    parts are floats or arrays (tolerance zero: the operations are the same)."""

    def expr(x: DD, y: DD, z: DD) -> DD:
        return (x + y) * z - x / z

    one = expr(DD(a), DD(b), DD(c))
    arr = expr(DD(np.array([a])), DD(np.array([b])), DD(np.array([c])))
    assert isinstance(one.hi, float) and isinstance(arr.hi, np.ndarray)
    assert _bits(one) == _bits(arr)
    if a != c:
        assert _bits(DD(b) / (DD(a) - c)) == _bits(DD(np.array([b])) / (DD(np.array([a])) - c))


@settings(max_examples=30, deadline=None)
@given(w=st.floats(1.0, 400.0), h=st.floats(0.0, 200.0))
def test_the_model_at_one_speed_is_the_model_at_an_array_of_it(w: float, h: float) -> None:
    """``forward`` at a scalar speed (floats) and at ``[w, 2w]`` (arrays): the same bits."""
    p = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, H1=h, H2=h, M3=60, J3=21,
                        a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)  # fmt: skip
    U = np.array([5e-3 + 1e-3j, -3e-3j])
    one = forward(p, w, U)
    both = forward(p, np.array([w, 2 * w]), U)
    assert np.array_equal(one, both[0])
