r"""The stand model of seed 002: parameters, steady state, natural frequencies.

Pure numerics: arrays in, arrays out, SI units, no I/O.

Derivation (see docs/stand-model.md for the notation)
----------------------------------------------------------------
The seed's four equations, with the rigid-rotor constraints
``x1 = x3 + L1 phi`` and ``x2 = x3 - L2 phi`` (``L1 = a + b``, ``L2 = c + d``,
``L = L1 + L2``), and support damping ``H_i``.  Eliminating the support forces
``P_i = -(M_i x_i'' + H_i x_i' + C_i x_i)`` and writing the steady state at
speed ``w`` as ``x_i = Re(X_i e^{i w t})``, ``a_i = Re(A_i e^{i w t})``,
``A_i = -w^2 X_i``, leaves two complex equations (force, moment about the
centre of mass), divided through by ``w^2``::

    D' X = B U,     B = [[1, 1], [b, -c]],    U_i = q_i R_i e^{-i phi_i}

    D' = [[ g1 - M3 L2 / L,      g2 - M3 L1 / L     ],
          [ L1 g1 - J3 / L,    -L2 g2 + J3 / L     ]]

with the *apparent mass* of support i (kg)::

    g_i = C_i / w^2 - M_i + i H_i / w

Inverse: ``U = G A`` with ``G = -B^{-1} D' / w^2 = -N / (w^2 (b + c))``,
where ``N = [[c, 1], [b, -1]] D'`` multiplied out (row 1: moments about
plane 2; row 2: about plane 1) is::

    N = [[ (a+b+c) g1 - (M3 c L2 + J3)/L,   -d g2 - (M3 c L1 - J3)/L      ],
         [ -a g1 - (M3 b L2 - J3)/L,        (b+c+d) g2 - (M3 b L1 + J3)/L ]]

Forward: ``A = -w^2 D'^{-1} B U = w^2 adj(N) U / det D'``, with
``det D' = -L g1 g2 + (J3 + M3 L1^2) g1/L + (J3 + M3 L2^2) g2/L - M3 J3/L``.
Both directions use the same entries of ``N``, so a round trip is exact
to about ``eps * cond(G)``; neither divides by ``b + c`` on the way forward.

The entries are written with the lengths the user gave (``a + b + c``,
``-d``) rather than ``c + L1`` or ``c - L2``: the latter lose every digit of
``d`` when ``d`` is much smaller than ``c``.  Dividing by ``w^2`` before
anything else keeps the entries as masses (kg) and lengths, so that nothing
overflows or underflows between 60 and 30,000 rpm, grams and tonnes.

The mass matrix in the support coordinates ``(x1, x2)`` is symmetric
positive definite; its determinant is written as a sum of positive terms,
and the discriminant of the frequency equation as a sum of squares, so the
natural frequencies lose no precision to cancellation either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.ddarith import DD
from stand.errors import ModelError, ParameterError

ComplexArray = NDArray[np.complex128]
FloatArray = NDArray[np.float64]

#: Which table of the config file each parameter lives in.
STAND_KEYS = ("M1", "M2", "C1", "C2", "H1", "H2")
ROTOR_KEYS = ("M3", "J3", "a", "b", "c", "d", "R1", "R2")


@dataclass(frozen=True)
class StandParameters:
    """Every mass, stiffness and length of stand and rotor, SI units.

    Parameters
    ----------
    M1, M2 : float
        Moving mass of support 1, 2 [kg], >= 0.
    C1, C2 : float
        Stiffness of support 1, 2 along x [N/m], > 0.
    M3 : float
        Rotor mass [kg], > 0.
    J3 : float
        Rotor moment of inertia about a transverse axis through its centre
        of mass [kg m^2], > 0.
    a, b, c, d : float
        Support 1 -> plane 1 -> centre of mass -> plane 2 -> support 2 [m].
    R1, R2 : float
        Correction radius in plane 1, 2 [m], > 0.
    H1, H2 : float
        Viscous damping of support 1, 2 [N s/m], >= 0 (0 gives the seed).

    Raises
    ------
    ParameterError
        For a value the physics refuses (see :meth:`check`).

    Examples
    --------
    >>> p = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, M3=60, J3=21,
    ...                     a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)
    >>> round(p.L, 6), round(p.L1, 6)
    (1.9, 1.0)
    """

    M1: float
    M2: float
    C1: float
    C2: float
    M3: float
    J3: float
    a: float
    b: float
    c: float
    d: float
    R1: float
    R2: float
    H1: float = 0.0
    H2: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, float(getattr(self, f.name)))
        self.check()

    def check(self) -> None:
        """Refuse what the model cannot describe.

        - any value not finite;
        - ``M1, M2 < 0``, ``H1, H2 < 0`` (no negative mass or damping);
        - ``C1, C2, M3, J3, R1, R2 <= 0``;
        - ``a + b <= 0`` or ``c + d <= 0``: the centre of mass would not lie
          between the supports, and a rotor *lying* in its supports would
          lift off one of them;
        - ``b + c < 0``: plane 1 would lie beyond plane 2 (swap the planes).

        Allowed: ``a < 0`` or ``d < 0`` (a correction plane outside its
        support, an overhung rotor end); ``b < 0`` or ``c < 0`` (both planes
        on one side of the centre of mass); ``b + c = 0`` (the planes
        coincide: only the static resultant can be computed, see
        :func:`stand.core.inverse.solve_unbalance`).
        """
        for f in fields(self):
            if not math.isfinite(getattr(self, f.name)):
                raise ParameterError(
                    f.name, f"expected a finite number, got {getattr(self, f.name)}"
                )
        for key in ("M1", "M2", "H1", "H2"):
            if getattr(self, key) < 0:
                raise ParameterError(key, f"must be >= 0, got {getattr(self, key)}")
        for key in ("C1", "C2", "M3", "J3", "R1", "R2"):
            if getattr(self, key) <= 0:
                raise ParameterError(key, f"must be > 0, got {getattr(self, key)}")
        if self.a + self.b <= 0:
            raise ParameterError(
                "b",
                f"a + b = {self.a + self.b} m: the centre of mass must lie between the "
                "supports (a + b > 0), or the rotor lifts off support 2",
            )
        if self.c + self.d <= 0:
            raise ParameterError(
                "c",
                f"c + d = {self.c + self.d} m: the centre of mass must lie between the "
                "supports (c + d > 0), or the rotor lifts off support 1",
            )
        if self.b + self.c < 0:
            raise ParameterError(
                "c",
                f"b + c = {self.b + self.c} m: plane 1 lies beyond plane 2; number the "
                "planes from support 1 (b + c >= 0)",
            )

    @property
    def L1(self) -> float:
        """Support 1 -> centre of mass, ``a + b`` [m]."""
        return self.a + self.b

    @property
    def L2(self) -> float:
        """Centre of mass -> support 2, ``c + d`` [m]."""
        return self.c + self.d

    @property
    def L(self) -> float:
        """Support span ``a + b + c + d`` [m]."""
        return (self.a + self.b) + (self.c + self.d)

    @property
    def plane_separation(self) -> float:
        """Distance between the correction planes, ``b + c`` [m]."""
        return self.b + self.c


def _omega(omega_rad_s: ArrayLike) -> FloatArray:
    w = np.asarray(omega_rad_s, dtype=np.float64)
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ModelError(f"shaft speed must be finite and > 0 rad/s, got {omega_rad_s!r}")
    return w


class _Terms:
    """The model's coefficients at speeds ``w``, in double-double (see :mod:`.ddarith`)."""

    def __init__(self, p: StandParameters, w: FloatArray):
        W = DD(w)
        w2 = W * W
        self.g1r = DD(p.C1) / w2 - p.M1
        self.g2r = DD(p.C2) / w2 - p.M2
        self.g1i = DD(p.H1) / W
        self.g2i = DD(p.H2) / W
        self.L1 = DD(p.a) + p.b
        self.L2 = DD(p.c) + p.d
        self.L = self.L1 + self.L2

    @staticmethod
    def complex(re: DD, im: DD) -> ComplexArray:
        return np.asarray(re.hi + 1j * im.hi, dtype=np.complex128)


def apparent_masses(
    p: StandParameters, omega_rad_s: ArrayLike
) -> tuple[ComplexArray, ComplexArray]:
    """Apparent masses ``g_i = C_i / w^2 - M_i + i H_i / w`` of the supports [kg].

    ``-w^2 g_i`` is the dynamic stiffness of support i; ``g_i = 0`` at the
    support's own (uncoupled, undamped) resonance ``sqrt(C_i / M_i)``.
    """
    t = _Terms(p, _omega(omega_rad_s))
    return t.complex(t.g1r, t.g1i), t.complex(t.g2r, t.g2i)


def support_matrix(p: StandParameters, omega_rad_s: ArrayLike) -> ComplexArray:
    """The matrix ``D'`` of ``D' X = B U`` [kg], shape ``omega.shape + (2, 2)``."""
    t = _Terms(p, _omega(omega_rad_s))
    D = np.empty((*np.shape(t.g1r.hi), 2, 2), dtype=np.complex128)
    D[..., 0, 0] = t.complex(t.g1r - DD(p.M3) * t.L2 / t.L, t.g1i)
    D[..., 0, 1] = t.complex(t.g2r - DD(p.M3) * t.L1 / t.L, t.g2i)
    D[..., 1, 0] = t.complex(t.L1 * t.g1r - DD(p.J3) / t.L, t.L1 * t.g1i)
    D[..., 1, 1] = t.complex(-(t.L2 * t.g2r) + DD(p.J3) / t.L, -(t.L2 * t.g2i))
    return D


def plane_matrix(p: StandParameters, omega_rad_s: ArrayLike) -> ComplexArray:
    """The matrix ``N = [[c, 1], [b, -1]] D'`` [kg m], shape ``omega.shape + (2, 2)``.

    Row 1 is the moment equation about plane 2, row 2 about plane 1 (sign
    aside), each entry written with the user's lengths so that no digit is
    lost to ``c + L1`` or ``c - L2``, and evaluated in double-double so that
    it is correct to the last place whatever its terms cancel.
    """
    return _plane_matrix(p, _Terms(p, _omega(omega_rad_s)))


def _plane_matrix(p: StandParameters, t: _Terms) -> ComplexArray:
    M3, J3 = DD(p.M3), DD(p.J3)
    abc = t.L1 + p.c
    bcd = DD(p.b) + p.c + p.d
    N = np.empty((*np.shape(t.g1r.hi), 2, 2), dtype=np.complex128)
    N[..., 0, 0] = t.complex(abc * t.g1r - (M3 * p.c * t.L2 + J3) / t.L, abc * t.g1i)
    N[..., 0, 1] = t.complex(-(DD(p.d) * t.g2r) - (M3 * p.c * t.L1 - J3) / t.L, -(DD(p.d) * t.g2i))
    N[..., 1, 0] = t.complex(-(DD(p.a) * t.g1r) - (M3 * p.b * t.L2 - J3) / t.L, -(DD(p.a) * t.g1i))
    N[..., 1, 1] = t.complex(bcd * t.g2r - (M3 * p.b * t.L1 + J3) / t.L, bcd * t.g2i)
    return N


def support_determinant(p: StandParameters, omega_rad_s: ArrayLike) -> ComplexArray:
    """``det D'`` [kg^2 m], expanded so that ``b + c`` does not enter.

    ``det D' = -L g1 g2 + (J3 + M3 L1^2) g1 / L + (J3 + M3 L2^2) g2 / L - M3 J3 / L``,
    which is ``-L det((K + i w H - w^2 M) / w^2)`` with ``M`` the mass matrix:
    zero at an undamped natural frequency, and nowhere else.  Evaluated in
    double-double: correct to the last place however close to resonance.
    """
    return _support_determinant(p, _Terms(p, _omega(omega_rad_s)))


def _support_determinant(p: StandParameters, t: _Terms) -> ComplexArray:
    M3, J3 = DD(p.M3), DD(p.J3)
    P1 = (J3 + M3 * t.L1 * t.L1) / t.L
    P2 = (J3 + M3 * t.L2 * t.L2) / t.L
    re = -(t.L * (t.g1r * t.g2r - t.g1i * t.g2i)) + P1 * t.g1r + P2 * t.g2r - M3 * J3 / t.L
    im = -(t.L * (t.g1r * t.g2i + t.g1i * t.g2r)) + P1 * t.g1i + P2 * t.g2i
    return t.complex(re, im)


def inverse_matrix(p: StandParameters, omega_rad_s: ArrayLike) -> ComplexArray:
    """The matrix ``G = -N / (w^2 (b + c))`` of ``U = G A`` [kg m / (m/s^2)].

    Shape ``omega.shape + (2, 2)``.

    Raises
    ------
    ModelError
        If the planes coincide (``b + c = 0``): there is no two-plane split.
    """
    if p.plane_separation == 0:
        raise ModelError("the correction planes coincide (b + c = 0): no two-plane split")
    w = _omega(omega_rad_s)
    scale = -1.0 / (w * w * p.plane_separation)
    result: ComplexArray = plane_matrix(p, w) * scale[..., None, None]
    return result


def forward(p: StandParameters, omega_rad_s: ArrayLike, U_kg_m: ArrayLike) -> ComplexArray:
    """Support acceleration phasors for given unbalances, steady state.

    Computed as ``A = w^2 adj(N) U / det D'`` (``adj(D') B = -adj(N)``): the
    accurate entries of :func:`plane_matrix` and the expanded
    :func:`support_determinant`.  This is exact for any plane separation,
    and :func:`inverse_matrix` undoes it to about ``eps * cond(G)``, which
    a generic LU solve of the badly scaled ``D'`` does not.

    Parameters
    ----------
    p
        Stand and rotor.
    omega_rad_s
        Shaft speed [rad/s], scalar or array (broadcast against ``U_kg_m``).
    U_kg_m
        Complex unbalances ``U_i = q_i R_i e^{-i phi_i}`` [kg m], last axis 2
        (plane 1, plane 2).

    Returns
    -------
    numpy.ndarray of complex
        ``A_i`` [m/s^2], last axis 2 (support 1, support 2), such that
        ``a_i(t) = Re(A_i e^{i theta})`` with ``theta`` the shaft angle of the
        reference mark (the seed's ``w t``).

    Raises
    ------
    ModelError
        At an undamped natural frequency (no steady state exists there).

    Examples
    --------
    >>> p = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, M3=60, J3=21,
    ...                     a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)
    >>> U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    >>> A = forward(p, rpm_to_rad_s(900.0), U)
    >>> [round(float(x), 4) for x in abs(A)]
    [2.3904, 1.6446]
    """
    w = _omega(omega_rad_s)
    U = np.asarray(U_kg_m, dtype=np.complex128)
    if U.shape[-1:] != (2,):
        raise ModelError(f"unbalances need a last axis of length 2, got shape {U.shape}")
    terms = _Terms(p, w)
    N = _plane_matrix(p, terms)
    det = _support_determinant(p, terms)
    if np.any(det == 0):
        raise ModelError(
            "the speed is a natural frequency of the undamped stand: no steady state exists"
        )
    U1, U2 = U[..., 0], U[..., 1]
    A = np.stack(
        [N[..., 1, 1] * U1 - N[..., 0, 1] * U2, -N[..., 1, 0] * U1 + N[..., 0, 0] * U2], axis=-1
    )
    result: ComplexArray = A * ((w * w) / det)[..., None]
    return result


def mass_matrix(p: StandParameters) -> FloatArray:
    """Mass matrix of stand + rotor in the support coordinates ``(x1, x2)`` [kg]."""
    L2sq = p.L * p.L
    m11 = p.M1 + (p.M3 * p.L2 * p.L2 + p.J3) / L2sq
    m22 = p.M2 + (p.M3 * p.L1 * p.L1 + p.J3) / L2sq
    m12 = (p.M3 * p.L1 * p.L2 - p.J3) / L2sq
    return np.array([[m11, m12], [m12, m22]])


def mass_matrix_det(p: StandParameters) -> float:
    """``det`` of :func:`mass_matrix` [kg^2], as a sum of positive terms."""
    L2sq = p.L * p.L
    return (
        p.M1 * p.M2
        + (p.M1 * (p.M3 * p.L1 * p.L1 + p.J3) + p.M2 * (p.M3 * p.L2 * p.L2 + p.J3) + p.M3 * p.J3)
        / L2sq
    )


def natural_frequencies(p: StandParameters) -> FloatArray:
    """Undamped natural frequencies of stand + rotor [rad/s], ascending.

    The two rigid-body modes of the rotor on the elastic supports (bounce
    and rock, coupled).  Closed form of ``det(K - w^2 M) = 0``.

    Examples
    --------
    >>> p = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, M3=60, J3=21,
    ...                     a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)
    >>> [round(float(f), 3) for f in natural_frequencies(p) / (2 * math.pi)]
    [5.647, 7.799]
    """
    (m11, m12), (_, m22) = mass_matrix(p)
    s = p.C1 * m22 + p.C2 * m11
    root = math.hypot(p.C1 * m22 - p.C2 * m11, 2.0 * math.sqrt(p.C1 * p.C2) * m12)
    lam_high = (s + root) / (2.0 * mass_matrix_det(p))
    lam_low = 2.0 * p.C1 * p.C2 / (s + root)
    result: FloatArray = np.sqrt(np.array([lam_low, lam_high]))
    return result


MAX_SPEED_RPM = 1e6
"""No rotor on a balancing stand turns faster (dental turbines reach about 4e5 rpm); beyond
it the model's numbers overflow into meaninglessness, so a speed above it is refused."""


def rpm_to_rad_s(rpm: ArrayLike) -> FloatArray:
    """Shaft speed from rev/min to rad/s."""
    result: FloatArray = np.asarray(rpm, dtype=np.float64) * (2.0 * math.pi / 60.0)
    return result


def rad_s_to_rpm(omega_rad_s: ArrayLike) -> FloatArray:
    """Shaft speed from rad/s to rev/min."""
    result: FloatArray = np.asarray(omega_rad_s, dtype=np.float64) * (60.0 / (2.0 * math.pi))
    return result


def unbalance_from_polar(magnitude_kg_m: ArrayLike, angle_deg: ArrayLike) -> ComplexArray:
    """``U = q R e^{-i phi}`` from ``q R`` [kg m] and the seed's angle ``phi`` [deg].

    ``phi`` is counted from the reference mark against the direction of
    rotation (stand-model.md, Conventions).
    """
    phase = np.exp(-1j * np.deg2rad(np.asarray(angle_deg, dtype=np.float64)))
    result: ComplexArray = np.asarray(magnitude_kg_m, dtype=np.complex128) * phase
    return result


def unbalance_to_polar(U_kg_m: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``(q R [kg m], phi [deg] in [0, 360))`` from ``U = q R e^{-i phi}``."""
    U = np.asarray(U_kg_m, dtype=np.complex128)
    return np.abs(U), wrap_deg(-np.rad2deg(np.angle(U)))


def phasor_to_polar(A: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``(amplitude, phase [deg] in [0, 360))`` with ``a(t) = amplitude cos(theta + phase)``."""
    A = np.asarray(A, dtype=np.complex128)
    return np.abs(A), wrap_deg(np.rad2deg(np.angle(A)))


def wrap_deg(angle_deg: ArrayLike) -> FloatArray:
    """Angles into [0, 360) (``-1e-20 % 360`` would give 360.0: folded to 0)."""
    x = np.mod(np.asarray(angle_deg, dtype=np.float64), 360.0)
    result: FloatArray = np.where(x >= 360.0, 0.0, x)
    return result
