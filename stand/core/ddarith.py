"""Double-double arithmetic on numpy arrays (about 106 significant bits).

The model's coefficients are short sums of products of the parameters
(``C/w^2 - M``, ``(a+b+c) g - (M3 c L2 + J3)/L`` ...) whose terms may cancel:
near a support resonance, for a light rotor on heavy supports, for planes
close to a support.  Evaluated in plain doubles such a sum keeps only
``eps * (sum of |terms|)`` absolute accuracy; evaluated here and rounded once,
it is correct to about one unit in the last place of the result unless the
cancellation exceeds ``2**53``.

Error-free transformations of Knuth (two-sum) and Dekker (two-product with
Veltkamp splitting), vectorised; the algorithms of Hida, Li and Bailey's QD
library ("accurate" addition).  Inputs must stay below about ``1e300`` (the
split multiplies by ``2**27 + 1``).

Examples
--------
>>> x = DD(1.0) + DD(1e-20)
>>> float((x - DD(1.0)).hi)
1e-20
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

_SPLIT = 134217729.0  # 2**27 + 1


def _two_sum(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _quick_two_sum(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    s = a + b
    return s, b - (s - a)


def _split(a: FloatArray) -> tuple[FloatArray, FloatArray]:
    t = _SPLIT * a
    hi = t - (t - a)
    return hi, a - hi


def _two_prod(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


class DD:
    """An array of double-double numbers ``hi + lo`` with ``|lo| <= ulp(hi) / 2``.

    Supports ``+ - * /`` with another :class:`DD` or a float (array); ``hi``
    is the value rounded to double.
    """

    __slots__ = ("hi", "lo")

    def __init__(self, hi: ArrayLike, lo: ArrayLike | None = None):
        self.hi: FloatArray = np.asarray(hi, dtype=np.float64)
        self.lo: FloatArray = (
            np.zeros_like(self.hi) if lo is None else np.asarray(lo, dtype=np.float64)
        )

    @staticmethod
    def _of(x: DD | ArrayLike) -> DD:
        return x if isinstance(x, DD) else DD(x)

    def __add__(self, other: DD | ArrayLike) -> DD:
        y = DD._of(other)
        s, e = _two_sum(self.hi, y.hi)
        t, f = _two_sum(self.lo, y.lo)
        e = e + t
        s, e = _quick_two_sum(s, e)
        e = e + f
        return DD(*_quick_two_sum(s, e))

    __radd__ = __add__

    def __neg__(self) -> DD:
        return DD(-self.hi, -self.lo)

    def __sub__(self, other: DD | ArrayLike) -> DD:
        return self + (-DD._of(other))

    def __rsub__(self, other: DD | ArrayLike) -> DD:
        return DD._of(other) - self

    def __mul__(self, other: DD | ArrayLike) -> DD:
        y = DD._of(other)
        p, e = _two_prod(self.hi, y.hi)
        e = e + (self.hi * y.lo + self.lo * y.hi)
        return DD(*_quick_two_sum(p, e))

    __rmul__ = __mul__

    def __truediv__(self, other: DD | ArrayLike) -> DD:
        y = DD._of(other)
        q1 = self.hi / y.hi
        r = self - y * q1
        q2 = r.hi / y.hi
        r = r - y * q2
        q3 = r.hi / y.hi
        q1, q2 = _quick_two_sum(q1, q2)
        return DD(q1, q2) + q3

    def __rtruediv__(self, other: DD | ArrayLike) -> DD:
        return DD._of(other) / self

    def __float__(self) -> float:
        return float(self.hi)
