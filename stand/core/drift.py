"""The stand's calibration judged from production: each correction as a datum, drift alarms.

A rotor corrected as the software prescribed and checked after gives the
stand's response to a known unbalance: the initial run's support phasors
``A0``, the check's ``A1`` [m/s^2] and the correction ``dU`` put on [kg m]
(``U = q R e^{-i phi}``).  With the calibration right, ``A1 - A0 =
F(theta) dU`` (:func:`stand.core.model.forward` at the run's speed); the
residual::

    r = (A1 - A0) - F(theta) dU

is noise: the two runs' (their covariances) and the operator's placement
(each plane's mass off by ``sigma_m`` relative and its angle by
``sigma_phi``: ``dU_j (eps_m - i eps_phi)``).  Whitened by that covariance,
``z^T z`` is chi-square with 4 degrees of freedom.  A drifting stand adds
``J dtheta`` to ``r`` (``J``: the response's derivative with respect to each
parameter, relative for stiffnesses, masses and sensor gains, in radians for
the reference angle), so:

- the **alarm** is Page's CUSUM on ``z^T z``: ``S_k = max(0, S_{k-1} + z^T z -
  CUSUM_K)``, raised when ``S_k > CUSUM_H``; under a stable stand the chance
  of an alarm within :data:`RUN_LENGTH` data is at most :data:`FALSE_ALARM`
  (the constants are set by simulation, ``tests/core/test_drift.py`` checks them);
- **what moved** is the single parameter whose generalised least-squares fit
  explains the residuals best, with its interval; a support's stiffness and
  mass act alike at one speed (``C/w^2 - M``), and the answer says so.

Pure numerics: arrays in, arrays out.
"""

from __future__ import annotations

import cmath
import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from stand.core.model import StandParameters, forward
from stand.errors import ModelError

PARAMETERS = ("C1", "C2", "M1", "M2", "reference_angle", "gain1", "gain2")
"""What may drift: support stiffnesses and masses, the reference sensor's angle, the two
accelerometers' gains."""
WATCHED = ("C1", "C2", "reference_angle", "gain1", "gain2")
"""The directions the CUSUMs watch, each way (a support's mass acts as its stiffness at one
speed: watching C_i watches both)."""
CUSUM_K = 0.5
"""Each CUSUM's allowance [standard deviations per datum]: half the shift of a drift worth
catching (one standard deviation per datum: C1 -8 % on the demo stand with 2 %, 2 deg
placement scatter)."""
CUSUM_H = 12.0
"""The alarm threshold: with :data:`CUSUM_K`, at most :data:`FALSE_ALARM` chance of any of
the ten CUSUMs raising an alarm within :data:`RUN_LENGTH` data of a stable stand (by
simulation, ``tests/core/test_drift.py``)."""
FALSE_ALARM = 0.01
RUN_LENGTH = 1000
ALIKE = 0.99
"""Two parameters whose effects on the data correlate above this cannot be told apart."""
OUTLIER_CHANCE = 1e-6
"""A datum whose ``z^T z`` a stable stand exceeds with less than this chance is raised on its
own, whatever its direction (the CUSUMs watch five directions; a change the model has no
parameter for, or one so large that it leaves them, shows here): 1 % over 10,000 data."""


def outliers(zs: FloatArray) -> NDArray[np.intp]:
    """The indices of the data (``zs`` (n, 4), :func:`whitened`'s) beyond any chance of a
    stable stand: chi-square with 4 degrees of freedom, survival below
    :data:`OUTLIER_CHANCE` (``z^T z`` above about 33.4)."""
    from scipy.special import gammaincc

    z2 = np.sum(np.asarray(zs, dtype=float).reshape(-1, 4) ** 2, axis=1)
    beyond = ~np.isfinite(z2) | (
        gammaincc(2.0, np.where(np.isfinite(z2), z2, 0.0) / 2) < OUTLIER_CHANCE
    )
    return np.flatnonzero(beyond)


FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Datum:
    """One corrected and checked rotor: speed [rad/s], the phasors before and after
    [m/s^2] and their real covariances (4 x 4 on ``[Re A1, Im A1, Re A2, Im A2]``), and
    the correction put on per plane [kg m]."""

    omega_rad_s: float
    A0: NDArray[np.complex128]
    A1: NDArray[np.complex128]
    cov0: FloatArray
    cov1: FloatArray
    dU_kg_m: NDArray[np.complex128]


@dataclass(frozen=True)
class _Stack:
    """The data of a series as arrays, datum by datum along the first axis (n)."""

    omega: FloatArray  # (n,)
    dA: NDArray[np.complex128]  # (n, 2): A1 - A0
    cov: FloatArray  # (n, 4, 4): cov0 + cov1
    dU: NDArray[np.complex128]  # (n, 2)

    @classmethod
    def of(cls, data: Sequence[Datum]) -> _Stack:
        def rows(get: object) -> NDArray:  # type: ignore[type-arg]
            return np.array([get(d) for d in data])  # type: ignore[operator]

        return cls(
            rows(lambda d: float(d.omega_rad_s)).reshape(-1),
            rows(lambda d: np.asarray(d.A1) - np.asarray(d.A0)).reshape(-1, 2),
            rows(lambda d: np.asarray(d.cov0) + np.asarray(d.cov1)).reshape(-1, 4, 4),
            rows(lambda d: np.asarray(d.dU_kg_m, dtype=np.complex128)).reshape(-1, 2),
        )


def _real(z: NDArray[np.complex128]) -> FloatArray:
    """``[Re, Im]`` per support, ``[Re A1, Im A1, Re A2, Im A2]``: (..., 2) -> (..., 4)."""
    return np.stack([z.real, z.imag], -1).reshape(*z.shape[:-1], 4)


def _F(p: StandParameters, omega: FloatArray) -> NDArray[np.complex128]:
    """``forward`` as a 2 x 2 matrix per speed (rows: supports): (n, 2, 2), one call for the
    whole series."""
    F = np.asarray(forward(p, np.asarray(omega, float)[:, None], np.eye(2)), dtype=np.complex128)
    return np.swapaxes(F, -1, -2)


def _perturbed(p: StandParameters, name: str, x: float) -> StandParameters:
    return dataclasses.replace(p, **{name: getattr(p, name) * (1 + x)})


def response(
    p: StandParameters, omega: FloatArray, dU: NDArray[np.complex128], delta: dict[str, float]
) -> NDArray[np.complex128]:
    """The stand's response ``F dU`` [m/s^2] per datum, (n, 2), with the parameters moved by
    ``delta`` (relative for C, M and gains, radians for the reference angle)."""
    q = p
    for name in ("C1", "C2", "M1", "M2"):
        if delta.get(name):
            q = _perturbed(q, name, delta[name])
    out = np.einsum("nij,nj->ni", _F(q, omega), dU)
    out = out * np.array([1 + delta.get("gain1", 0.0), 1 + delta.get("gain2", 0.0)])
    # a reference mark seen later by ``d`` turns every phasor by e^{+i d} (the model's sense)
    turned: NDArray[np.complex128] = out * cmath.exp(1j * delta.get("reference_angle", 0.0))
    return turned


def _covariance(
    p: StandParameters, s: _Stack, scatter_rel: float, scatter_rad: float
) -> FloatArray:
    """The residuals' real covariances (n, 4, 4): both runs' noise and the operator's
    placement."""
    F = _F(p, s.omega)
    Fr = np.block([[F.real, -F.imag], [F.imag, F.real]])  # on [Re U, Im U] -> [Re A, Im A]
    cu = np.zeros((len(s.omega), 4, 4))
    for j in range(2):
        u = s.dU[:, j]
        a = np.stack([u.real, u.imag], -1)
        b = np.stack([u.imag, -u.real], -1)
        block = scatter_rel**2 * a[:, :, None] * a[:, None, :]
        block += scatter_rad**2 * b[:, :, None] * b[:, None, :]
        idx = [j, 2 + j]
        cu[:, np.array(idx)[:, None], np.array(idx)[None, :]] = block
    ca = Fr @ cu @ np.swapaxes(Fr, -1, -2)  # ordered [Re A1, Re A2, Im A1, Im A2]
    order = np.array([0, 2, 1, 3])
    return np.asarray(s.cov + ca[:, order[:, None], order[None, :]], dtype=float)


def _cholesky(cov: FloatArray) -> FloatArray:
    """Each datum's ``L`` (``L L^T = cov``); a datum whose covariance is not positive
    definite is named."""
    try:
        return np.asarray(np.linalg.cholesky(cov), dtype=np.float64)
    except np.linalg.LinAlgError:
        for k, c in enumerate(cov):
            try:
                np.linalg.cholesky(c)
            except np.linalg.LinAlgError as exc:
                raise ModelError(f"datum {k + 1}: its covariance is not positive definite") from exc
        raise


def _solve(L: FloatArray, x: FloatArray) -> FloatArray:
    """``L^-1 x`` per datum: ``x`` (n, 4) or (n, 4, k)."""
    out = np.linalg.solve(L, x[..., None])[..., 0] if x.ndim == 2 else np.linalg.solve(L, x)
    return np.asarray(out, dtype=np.float64)


def whitened(
    p: StandParameters, data: Sequence[Datum], scatter_rel: float, scatter_rad: float
) -> tuple[FloatArray, FloatArray]:
    """The whitened residuals ``z`` (n, 4) and Jacobians (n, 4, P) of a series: ``L^-1 r``,
    ``L^-1 J`` with ``L L^T`` each residual's covariance, ``r = (A1 - A0) - F dU`` and
    ``J = d [Re, Im] (F dU) / d theta`` at the calibration itself.  The model is evaluated
    once per parameter for the whole series, not per datum."""
    if not len(data):
        return np.zeros((0, 4)), np.zeros((0, 4, len(PARAMETERS)))
    s = _Stack.of(data)
    L = _cholesky(_covariance(p, s, scatter_rel, scatter_rad))
    r = _real(s.dA - response(p, s.omega, s.dU, {}))
    J = _columns(p, s, PARAMETERS, dict.fromkeys(PARAMETERS, 0.0))
    return _solve(L, r), _solve(L, J)


def scores(zs: FloatArray, Js: FloatArray) -> FloatArray:
    """Each datum's standardised score along each watched direction, both ways: ``(n, 10)``,
    each N(0, 1) on a stable stand (``J_k^T z / |J_k|``); ``zs`` (n, 4), ``Js`` (n, 4, P)
    as :func:`whitened` gives them."""
    cols = [PARAMETERS.index(n) for n in WATCHED]
    Jk = np.asarray(Js, dtype=float).reshape(-1, 4, len(PARAMETERS))[:, :, cols]
    z = np.asarray(zs, dtype=float).reshape(-1, 4)
    u = np.einsum("nik,ni->nk", Jk, z) / np.linalg.norm(Jk, axis=1)
    return np.concatenate([u, -u], axis=1)


@dataclass(frozen=True)
class Cusum:
    """The CUSUMs over a series: the largest path per datum, the first datum over the
    threshold (None: no alarm), and where the alarming stream last stood at zero before it
    (the change's estimated start: the first datum after that zero)."""

    top: FloatArray
    alarm_at: int | None
    change_at: int | None


def cusum(u: FloatArray, k: float = CUSUM_K, h: float = CUSUM_H) -> Cusum:
    """Page's one-sided CUSUMs of the scores ``u`` (n x streams)."""
    S = np.zeros(u.shape[1])
    last_zero = np.full(u.shape[1], -1)
    top = np.zeros(len(u))
    for i, x in enumerate(u):
        S = np.maximum(0.0, S + x - k)
        last_zero[S == 0.0] = i
        top[i] = float(S.max())
        if top[i] > h:
            stream = int(np.argmax(S))
            return Cusum(top[: i + 1], i, int(last_zero[stream]) + 1)
    return Cusum(top, None, None)


@dataclass(frozen=True)
class Fit:
    """One parameter fitted alone: its change (relative, or radians), 95 % half-width,
    the chi-square left, and the parameters it cannot be told apart from."""

    name: str
    change: float
    interval95: float
    chi2: float
    alike: tuple[str, ...]


def single_fits(zs: FloatArray, Js: FloatArray) -> list[Fit]:
    """Each parameter fitted alone to the whitened residuals (:func:`whitened`'s), best
    (least chi-square) first."""
    z = np.asarray(zs, dtype=float).reshape(-1)
    J = np.asarray(Js, dtype=float).reshape(len(z), len(PARAMETERS))
    norms = np.linalg.norm(J, axis=0)
    corr = (J.T @ J) / np.outer(norms, norms)
    fits = []
    for k, name in enumerate(PARAMETERS):
        jk = J[:, k]
        info = float(jk @ jk)
        if info <= 0:
            continue
        change = float(jk @ z) / info
        left = z - jk * change
        alike = tuple(
            PARAMETERS[m] for m in range(len(PARAMETERS)) if m != k and abs(corr[k, m]) > ALIKE
        )
        fits.append(Fit(name, change, 1.96 / math.sqrt(info), float(left @ left), alike))
    return sorted(fits, key=lambda f: f.chi2)


def fit(
    p: StandParameters,
    data: Sequence[Datum],
    name: str,
    scatter_rel: float,
    scatter_rad: float,
    iterations: int = 5,
) -> Fit:
    """``name`` alone fitted to the data (:func:`fit_many`)."""
    return fit_many(p, data, (name,), scatter_rel, scatter_rad, iterations)[0]


def fit_many(
    p: StandParameters,
    data: Sequence[Datum],
    names: Sequence[str],
    scatter_rel: float,
    scatter_rad: float,
    iterations: int = 5,
) -> list[Fit]:
    """``names`` fitted together to the data by Gauss-Newton (the response is not linear in
    them: an 8 % stiffness change seen through the old one's slope reads 7 %), each with its
    95 % half-width from the information matrix."""
    change = dict.fromkeys(names, 0.0)
    s = _Stack.of(data)
    L = _cholesky(_covariance(p, s, scatter_rel, scatter_rad))
    for _ in range(iterations):
        q = p
        for n in names:
            q = _moved(q, n, change[n]) if n in ("C1", "C2", "M1", "M2") else q
        extra = {n: v for n, v in change.items() if n not in ("C1", "C2", "M1", "M2")}
        z = _solve(L, _real(s.dA - response(q, s.omega, s.dU, extra))).reshape(-1)
        J = _solve(L, _columns(p, s, names, change)).reshape(-1, len(names))
        info = J.T @ J
        try:
            cov = np.linalg.inv(info)
        except np.linalg.LinAlgError as exc:
            raise ModelError(f"the data cannot tell {', '.join(names)} apart") from exc
        step = cov @ (J.T @ z)
        for n, dx in zip(names, step, strict=True):
            change[n] += float(dx)
            if n in ("C1", "C2", "M1", "M2") and not 1 + change[n] > 0:
                raise ModelError(
                    f"no change of {n} explains the data: its fit passes -100 % "
                    f"({100 * change[n]:+.3g} %)"
                )
    left = z - J @ step
    chi2 = float(left @ left)
    return [
        Fit(n, change[n], 1.96 * math.sqrt(float(cov[k, k])), chi2, ()) for k, n in enumerate(names)
    ]


def _columns(
    p: StandParameters, s: _Stack, names: Sequence[str], at: dict[str, float]
) -> FloatArray:
    """The response's derivative with respect to each of ``names`` at ``at``, per datum:
    (n, 4, len(names)), by central differences (1e-6)."""
    h = 1e-6
    cols = []
    for n in names:
        up = response(p, s.omega, s.dU, {**at, n: at[n] + h})
        down = response(p, s.omega, s.dU, {**at, n: at[n] - h})
        cols.append(_real((up - down) / (2 * h)))
    return np.stack(cols, -1)


def _moved(p: StandParameters, name: str, change: float) -> StandParameters:
    return _perturbed(p, name, change) if name in ("C1", "C2", "M1", "M2") else p
