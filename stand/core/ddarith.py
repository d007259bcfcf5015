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
Real = FloatArray | float
"""A value of :class:`DD`'s parts: an array, or one number as a Python float (the same
IEEE operations as a 0-d array without numpy's per-call cost: the model at one speed, as
most of its callers ask for it, about 3x quicker, docs/performance.md)."""

_SPLIT = 134217729.0  # 2**27 + 1


def _two_sum(a: Real, b: Real) -> tuple[Real, Real]:
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _quick_two_sum(a: Real, b: Real) -> tuple[Real, Real]:
    s = a + b
    return s, b - (s - a)


def _split(a: Real) -> tuple[Real, Real]:
    t = _SPLIT * a
    hi = t - (t - a)
    return hi, a - hi


def _two_prod(a: Real, b: Real) -> tuple[Real, Real]:
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


class DD:
    """An array of double-double numbers ``hi + lo`` with ``|lo| <= ulp(hi) / 2``.

    Supports ``+ - * /`` with another :class:`DD` or a float (array); ``hi``
    is the value rounded to double.  A scalar is kept as two Python floats: the same
    bits as a one-element array, except that dividing by zero raises
    ``ZeroDivisionError`` where numpy gives ``inf`` (the model divides only by speeds and
    lengths it has checked to be positive).
    """

    __slots__ = ("hi", "lo")

    hi: Real
    lo: Real

    def __init__(self, hi: ArrayLike, lo: ArrayLike | None = None):
        h = np.asarray(hi, dtype=np.float64)
        if h.ndim == 0:
            self.hi = float(h)
            self.lo = 0.0 if lo is None else float(np.asarray(lo, dtype=np.float64))
        else:
            self.hi = h
            self.lo = np.zeros_like(h) if lo is None else np.asarray(lo, dtype=np.float64)

    @staticmethod
    def _made(hi: Real, lo: Real) -> DD:
        """Parts that are already a double-double's, taken as they are."""
        x = object.__new__(DD)
        x.hi, x.lo = hi, lo
        return x

    @staticmethod
    def _of(x: DD | ArrayLike) -> DD:
        if isinstance(x, DD):
            return x
        return DD._made(x, 0.0) if type(x) is float else DD(x)

    def __add__(self, other: DD | ArrayLike) -> DD:
        y = DD._of(other)
        s, e = _two_sum(self.hi, y.hi)
        t, f = _two_sum(self.lo, y.lo)
        e = e + t
        s, e = _quick_two_sum(s, e)
        e = e + f
        return DD._made(*_quick_two_sum(s, e))

    __radd__ = __add__

    def __neg__(self) -> DD:
        return DD._made(-self.hi, -self.lo)

    def __sub__(self, other: DD | ArrayLike) -> DD:
        return self + (-DD._of(other))

    def __rsub__(self, other: DD | ArrayLike) -> DD:
        return DD._of(other) - self

    def __mul__(self, other: DD | ArrayLike) -> DD:
        y = DD._of(other)
        p, e = _two_prod(self.hi, y.hi)
        e = e + (self.hi * y.lo + self.lo * y.hi)
        return DD._made(*_quick_two_sum(p, e))

    __rmul__ = __mul__

    def __truediv__(self, other: DD | ArrayLike) -> DD:
        y = DD._of(other)
        q1 = self.hi / y.hi
        r = self - y * q1
        q2 = r.hi / y.hi
        r = r - y * q2
        q3 = r.hi / y.hi
        q1, q2 = _quick_two_sum(q1, q2)
        return DD._made(q1, q2) + q3

    def __rtruediv__(self, other: DD | ArrayLike) -> DD:
        return DD._of(other) / self

    def __float__(self) -> float:
        return float(self.hi)
