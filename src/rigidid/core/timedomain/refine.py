"""Output-error (maximum-likelihood) refinement of the rigid body on the impact records.

The body's physical parameters (CG, J/m, K/m, C/m) are fitted directly to the
free decays of every impact: the 12x12 state matrix of eq. (19) of [1] gives
the poles and the acceleration shapes at the sensors; each impact's complex
modal amplitudes and channel offsets enter linearly and are solved inside the
residual (variable projection); every channel is weighted by its noise level;
the Jacobian is analytic (eigenvalue and eigenvector derivatives). The
Cramér-Rao bound of every parameter follows from the same Jacobian.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import layout_frame, normalise_directions, sensor_matrix
from rigidid.core.linalg import pseudo_inverse
from rigidid.core.optimize import levenberg_marquardt
from rigidid.core.statespace import modal_from_poles
from rigidid.core.timedomain.acceptance import MisfitTest, misfit_test
from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH, decimate, fir_taps
from rigidid.errors import InputError

__all__ = [
    "MAX_ROWS",
    "N_PARAMETERS",
    "PreparedDecays",
    "RecordBound",
    "Refinement",
    "columns_of",
    "cut_decays",
    "fit_factor",
    "good_fit",
    "prepare_decays",
    "pretrigger_sigma",
    "record_bound",
    "refine_body",
    "refine_prepared",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

N_PARAMETERS = 51
"""CG (3), Cholesky factors of J/m (6), K/m (21) and C/m (21)."""

MAX_ROWS = 150_000
"""Largest number of residuals (samples x channels over all impacts) fitted; longer
records are cut (the end of a decay holds the least signal)."""

_TRIL3 = np.tril_indices(3)
_TRIL6 = np.tril_indices(6)
_MIN_PRETRIGGER = 32  # samples of pre-trigger needed to take the noise level from it
_Z95 = 1.959963984540054
_GOOD_COST = 2.0  # normalised cost 2 cost / n_residuals above this: a bad fit (about 1 at a good one)
_DECREMENT = 0.05  # converged: Gauss-Newton decrement below this many residual variances
_STALL = 1e-4  # converged at a bound of J, K, C > 0: a step lowers the cost by less (in variances)
_STALL_DECREMENT = 4.0  # ... while the Gauss-Newton step, out of reach, is below 2 standard errors
_GOLUB_PEREYRA = False  # the full variable-projection Jacobian (measured: benchmarks/refine_diagnose.py)
_GEODESIC_H = 0.1  # step fraction of the central difference for the second directional derivative


@dataclass(frozen=True)
class Refinement:
    """The body fitted to the records, its Cramér-Rao bound and how the fit went.

    Attributes
    ----------
    center_of_gravity : ndarray, shape (3,)
        CG in the layout's axes (length).
    inertia_per_mass : ndarray, shape (3, 3)
        Inertia tensor about the CG over mass (length^2).
    stiffness_per_mass, damping_per_mass : ndarray, shape (6, 6)
        Support stiffness and damping at the CG over mass, DOF order x, y, z,
        rx, ry, rz.
    poles : ndarray of complex, shape (6,)
        Poles of the fitted model (rad/s), ascending frequency.
    std : dict of str to ndarray
        Standard errors at the estimate (the Cramér-Rao bound made robust: sandwich
        covariance of :mod:`rigidid.core.timedomain.intervals`), same keys and shapes as the
        values: ``"center_of_gravity"``, ``"inertia_per_mass"``,
        ``"stiffness_per_mass"``, ``"damping_per_mass"``, ``"frequency_hz"``,
        ``"damping_ratio"``.
    normalised_cost : float
        ``2 cost / n_residuals`` in noise-weighted units: about 1 at a good fit
        when the noise levels come from the pre-trigger.
    noise_from : str
        ``"pretrigger"`` or ``"residual"``: where the channel noise levels came from.
    residuals : int
        Number of residuals fitted.
    evaluations : int
        Residual evaluations of the optimiser.
    converged : bool
        Whether the optimiser met its convergence test (Gauss-Newton decrement below
        0.05 residual variances or below the rounding floor of the data, or the cost
        stalled at the boundary of positive definite J, K, C with the decrement below 4)
        rather than stopping at its evaluation budget; False when the start was only
        evaluated.
    """

    center_of_gravity: Array
    inertia_per_mass: Array
    stiffness_per_mass: Array
    damping_per_mass: Array
    poles: CArray
    std: dict[str, Array]
    normalised_cost: float
    noise_from: str
    residuals: int
    evaluations: int
    converged: bool = False
    misfit: MisfitTest | None = None

    @property
    def frequency_hz(self) -> Array:
        """Undamped natural frequencies of the fitted model (Hz)."""
        return modal_from_poles(self.poles)[0]

    @property
    def damping_ratio(self) -> Array:
        """Damping ratios of the fitted model."""
        return modal_from_poles(self.poles)[1]


# --- parameterisation ---------------------------------------------------------------------


@dataclass(frozen=True)
class _Frame:
    centre: Array
    scale: float
    omega: float  # time scale (rad/s)

    def to_theta(self, g: Array, jm: Array, km: Array, cm: Array) -> Array:
        e = np.diag([1.0, 1.0, 1.0, 1.0 / self.scale, 1.0 / self.scale, 1.0 / self.scale])
        gl = (g - self.centre) / self.scale
        jl = jm / self.scale**2
        kl = e @ km @ e / self.omega**2
        cl = e @ cm @ e / self.omega
        return np.concatenate([gl, _chol(jl)[_TRIL3], _chol(kl)[_TRIL6], _chol(cl)[_TRIL6]])

    def physical(self, theta: Array) -> tuple[Array, Array, Array, Array]:
        gl, jl, kl, cl = _local(theta)
        s = self.scale
        ei = np.diag([1.0, 1.0, 1.0, s, s, s])
        return gl * s + self.centre, jl * s**2, ei @ kl @ ei * self.omega**2, ei @ cl @ ei * self.omega


def _chol(a: Array) -> Array:
    """Lower Cholesky factor of the symmetric `a`, its eigenvalues made at least 1e-3 of the largest.

    A negative eigenvalue (a structured estimate of C is often slightly indefinite: a weakly
    damped direction estimated below zero) is reflected to its magnitude rather than set
    near zero: a factor with a near-zero diagonal sits at the fold of ``L L^T``, where the
    cost's derivative along that direction vanishes and the fit stalled (``benchmarks/
    refine_diagnose.py``: 4 of 6 seeds at 5 % noise).
    """
    a = 0.5 * (a + a.T)
    w, v = np.linalg.eigh(a)
    floor = 1e-3 * max(float(np.max(np.abs(w))), 1e-300)
    result: Array = np.linalg.cholesky((v * np.maximum(np.abs(w), floor)) @ v.T)
    return result


def _lower(values: Array, n: int) -> Array:
    out = np.zeros((n, n))
    out[np.tril_indices(n)] = values
    return out


def _local(theta: Array) -> tuple[Array, Array, Array, Array]:
    lj, lk, lc = _lower(theta[3:9], 3), _lower(theta[9:30], 6), _lower(theta[30:51], 6)
    return theta[:3], lj @ lj.T, lk @ lk.T, lc @ lc.T


def _state(jl: Array, kl: Array, cl: Array) -> tuple[Array, Array]:
    """State matrix A (12x12) of eq. (19) and M^-1 (6x6), per mass, local units."""
    minv = np.zeros((6, 6))
    minv[:3, :3] = np.eye(3)
    minv[3:, 3:] = np.linalg.solve(jl, np.eye(3))
    a = np.zeros((12, 12))
    a[:6, :6] = -minv @ cl
    a[:6, 6:] = -minv @ kl
    a[6:, :6] = np.eye(6)
    return a, minv


def _dstate(theta: Array, minv: Array, a: Array) -> list[Array]:
    """dA/dtheta_j for j = 3..50 (the 48 parameters A depends on)."""
    lj, lk, lc = _lower(theta[3:9], 3), _lower(theta[9:30], 6), _lower(theta[30:51], 6)
    out: list[Array] = []
    top = a[:6, :]  # [-M^-1 C, -M^-1 K]
    for i, j in zip(*_TRIL3, strict=True):
        e = np.zeros((3, 3))
        e[i, j] = 1.0
        dj = e @ lj.T + lj @ e.T
        dm = np.zeros((6, 6))
        dm[3:, 3:] = dj
        da = np.zeros((12, 12))
        da[:6, :] = -minv @ dm @ top  # d(M^-1) X = -M^-1 dM M^-1 X
        out.append(da)
    for block, lower in ((6, lk), (0, lc)):
        for i, j in zip(*_TRIL6, strict=True):
            e = np.zeros((6, 6))
            e[i, j] = 1.0
            dx = e @ lower.T + lower @ e.T
            da = np.zeros((12, 12))
            da[:6, block : block + 6] = -minv @ dx
            out.append(da)
    return out


# --- the model at the sensors -----------------------------------------------------------


def _modes(theta: Array, pos: Array, dirs: Array, with_derivatives: bool) -> tuple[CArray, CArray, CArray, CArray]:
    """Poles (6,), shapes (p, 6), and their derivatives (51, 6), (51, p, 6)."""
    gl, jl, kl, cl = _local(theta)
    a, minv = _state(jl, kl, cl)
    lam, vec = np.linalg.eig(a)
    keep = np.flatnonzero(lam.imag > 0.0)
    if keep.size != 6:
        raise np.linalg.LinAlgError("the model has not six underdamped modes")
    keep = keep[np.argsort(np.abs(lam[keep]))]
    t_g = sensor_matrix(pos, dirs, gl)
    lam_k = lam[keep]
    accel = vec[:6, keep] * lam_k  # acceleration of the CG in each mode
    phi = t_g @ accel
    if not with_derivatives:
        return lam_k, phi, np.zeros((0, 6), complex), np.zeros((0, *phi.shape), complex)
    left = np.linalg.solve(vec, np.eye(12))
    dlam = np.zeros((N_PARAMETERS, 6), complex)
    dphi = np.zeros((N_PARAMETERS, pos.shape[0], 6), complex)
    # CG: only the sensor matrix moves: d/dg_j of (r - g) x n = -(e_j x n)
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1.0
        dt = np.hstack([np.zeros_like(dirs), -np.cross(np.broadcast_to(e, dirs.shape), dirs)])
        dphi[j] = dt @ accel
    gap = lam[None, :] - lam[:, None]  # gap[i, k] = lam_k - lam_i
    np.fill_diagonal(gap, 1.0)
    for j, da in enumerate(_dstate(theta, minv, a), start=3):
        f = left @ da @ vec
        dl = np.diag(f)[keep]
        coef = f[:, keep] / gap[:, keep]
        coef[keep, np.arange(6)] = 0.0
        dv = vec @ coef  # (12, 6)
        dlam[j] = dl
        dphi[j] = t_g @ (dv[:6] * lam_k + vec[:6, keep] * dl)
    return lam_k, phi, dlam, dphi


# --- data preparation -------------------------------------------------------------------


@dataclass(frozen=True)
class PreparedDecays:
    """What the refit fits: the decays at the fit's rate and each channel's noise level.

    Attributes
    ----------
    decays : list of ndarray, shape (n_i, p)
        Per impact, the free decay from its start, decimated by the fit's
        factor (:func:`fit_factor`) and cut to :data:`MAX_ROWS` values in all.
    sigma : ndarray, shape (p,)
        Noise level of each channel at the fit's rate (ones when unknown).
    dt : float
        Sample interval of `decays` (s).
    noise_from : {"pretrigger", "residual"}
        Where `sigma` comes from ("residual": the refit measures it).
    drift : bool
        Whether the model has a linear drift per channel and impact beside the
        offset (records whose DC offset and drift were taken out,
        :mod:`rigidid.core.timedomain.trend`).
    pre_counts : tuple of int
        Pre-trigger samples of each record (raw rate; empty when unknown).
    pre_m2 : ndarray, shape (records, p), or None
        Their squared deviations from the record's pre-trigger mean, per channel
        (for the acceptance test, :mod:`rigidid.core.timedomain.acceptance`).
    """

    decays: list[Array]  # (n_i, p)
    sigma: Array  # (p,) noise level of each channel in the decays fitted
    dt: float
    noise_from: str
    drift: bool = False
    pre_counts: tuple[int, ...] = ()
    pre_m2: Array | None = None


_Data = PreparedDecays


def columns_of(data: PreparedDecays, channels: Sequence[int]) -> PreparedDecays:
    """`data` with only the given channels (e.g. the clipped ones left out).

    Parameters
    ----------
    data : PreparedDecays
    channels : sequence of int
        Columns kept, in order.

    Returns
    -------
    PreparedDecays
    """
    cols = list(channels)
    m2 = None if data.pre_m2 is None else data.pre_m2[:, cols]
    return replace(data, decays=[d[:, cols] for d in data.decays], sigma=data.sigma[cols], pre_m2=m2)


def pretrigger_sigma(counts: Sequence[int], squares: Sequence[Array], n_records: int, factor: int) -> tuple[Array, str]:
    """Each channel's noise level at the fit's rate from the pre-trigger statistics.

    Parameters
    ----------
    counts : sequence of int
        Pre-trigger samples of each record.
    squares : sequence of ndarray, shape (p,)
        Per record, the sum of squared deviations from its own mean, per channel.
    n_records : int
        Number of records (at least :data:`_MIN_PRETRIGGER` samples each, on average, are needed).
    factor : int
        The fit's decimation: white noise's variance after its filter is
        ``sum h^2`` of :func:`~rigidid.core.timedomain.preprocess.fir_taps`.

    Returns
    -------
    sigma : ndarray, shape (p,)
    noise_from : {"pretrigger", "residual"}
        "residual" (and ones) when the pre-trigger is too short or silent.
    """
    p = squares[0].shape[0] if len(squares) else 0
    if sum(counts) >= _MIN_PRETRIGGER * n_records:
        used = [(n, m2) for n, m2 in zip(counts, squares, strict=True) if n > 1]
        s = np.sqrt(sum(m2 for _, m2 in used) / sum(n for n, _ in used))
        if factor > 1:
            s = s * math.sqrt(float(np.sum(fir_taps(factor) ** 2)))
        if np.all(s > 0.0):
            return s, "pretrigger"
    return np.ones(p), "residual"


def cut_decays(decays: list[Array], p: int) -> list[Array]:
    """`decays` cut to :data:`MAX_ROWS` values in all (the same rows of each); too short ones refused.

    Raises
    ------
    InputError
        A decay shorter than ``4 FIR_HALF_LENGTH`` samples.
    """
    total = sum(d.shape[0] for d in decays) * p
    if total > MAX_ROWS:
        keep = MAX_ROWS // (p * len(decays))
        decays = [d[:keep] for d in decays]
    if min(d.shape[0] for d in decays) < 4 * FIR_HALF_LENGTH:
        raise InputError("records too short for the refinement")
    return decays


def prepare_decays(
    records: Sequence[Array],
    dt: float,
    starts: Sequence[int],
    onsets: Sequence[int],
    factor: int,
) -> PreparedDecays:
    """The refit's data from whole records (:func:`refine_body`'s first step).

    Parameters
    ----------
    records : sequence of ndarray, shape (n_i, p)
        The records, samples by sensors.
    dt : float
        Sample interval (s).
    starts, onsets : sequence of int
        Per record, the first sample of the free decay and of the impact.
    factor : int
        The modal estimate's decimation: the fit's is the smallest up to it
        whose decays fit :data:`MAX_ROWS` (:func:`fit_factor`).
    Returns
    -------
    PreparedDecays

    Notes
    -----
    The pre-trigger is ``r[:onset - 2]``; its level per channel is the
    RMS about each record's mean, scaled by the fit filter's noise gain
    (:func:`pretrigger_sigma`). :mod:`rigidid.io.records.refit` builds the same
    from record files read in row blocks.
    """
    p = records[0].shape[1]
    pre = [r[: max(0, o - 2)] for r, o in zip(records, onsets, strict=True)]
    factor = fit_factor([r.shape[0] - s for r, s in zip(records, starts, strict=True)], p, factor)
    decays = []
    for rec, start in zip(records, starts, strict=True):
        d = rec[start:]
        d = decimate(d, factor) if factor > 1 else d
        decays.append(np.asarray(d, dtype=float))
    decays = cut_decays(decays, p)
    squares = [((x - x.mean(axis=0)) ** 2).sum(axis=0) if x.shape[0] > 1 else np.zeros(p) for x in pre]
    counts = [x.shape[0] for x in pre]
    sigma, noise_from = pretrigger_sigma(counts, squares, len(records), factor)
    return PreparedDecays(decays, sigma, dt * factor, noise_from, pre_counts=tuple(counts), pre_m2=np.array(squares))


_prepare = prepare_decays

_SAFE_PEAK = 2.0**200


def _in_range(records: list[Array]) -> list[Array]:
    """The records scaled together by a power of two when their largest value is outside ``[2^-200, 2^200]``
    (squares of 1e300 overflow, of 1e-300 underflow); the fit's body does not depend on a common factor."""
    top = max((float(np.max(np.abs(r))) if r.size else 0.0 for r in records), default=0.0)
    if top == 0.0 or not math.isfinite(top) or 1.0 / _SAFE_PEAK <= top <= _SAFE_PEAK:
        return records
    k = -math.frexp(top)[1]
    return [np.ldexp(r, k) for r in records]


def fit_factor(lengths: Sequence[int], p: int, factor: int) -> int:
    """The smallest decimation factor up to `factor` whose decays fit :data:`MAX_ROWS`.

    Decimation keeps the band, but its filter loses ``FIR_HALF_LENGTH q`` samples at the
    start of each decay, the part of a decay that holds the most signal (a 7 %-damped
    26 Hz mode loses more than half its energy in 20 samples at 512 Hz): the fit runs on
    the raw samples when they fit, and decimates only as much as memory requires.
    """
    for q in range(1, max(1, factor) + 1):
        if sum(n // q for n in lengths) * p <= MAX_ROWS:
            return q
    return max(1, factor)


_fit_factor = fit_factor


# --- variable projection ----------------------------------------------------------------


def _design(lam: CArray, phi: CArray, t: Array, drift: bool = False) -> tuple[Array, CArray]:
    """Real design matrix (n p, 12 + p, or 12 + 2 p with a drift per channel) of one impact, and exp(lam t) (n, 6)."""
    n, p = t.shape[0], phi.shape[0]
    ex = np.exp(np.outer(t, lam))  # (n, 6)
    u = ex[:, None, :] * phi[None, :, :]  # (n, p, 6)
    cols = np.concatenate([u.real, -u.imag], axis=2).reshape(n * p, 12)
    offs = np.tile(np.eye(p), (n, 1))
    if not drift:
        return np.hstack([cols, offs]), ex
    ramp = offs * np.repeat(t / max(float(t[-1]), 1e-300), p)[:, None]
    return np.hstack([cols, offs, ramp]), ex


def _projector(design: Array) -> Any:
    """``x -> (coefficients, x - design coefficients)``: least squares on `design`'s columns.

    ``project(x, out)`` writes the negated residual ``design coefficients - x`` into `out`
    (the refit's projected Jacobian, filled in place).

    From the Gram matrix of the column-normalised design (``(n, 12 + p)``: cost
    ``n (12 + p)^2``, a small fraction of a QR), by Cholesky; a QR where the Gram
    matrix is too ill-conditioned for that (condition above 1e10).
    """
    norms = np.sqrt(np.einsum("ij,ij->j", design, design))
    norms = np.where(norms > 0.0, norms, 1.0)
    scaled = design / norms
    gram = scaled.T @ scaled
    try:
        if np.linalg.cond(gram) > 1e10:
            raise np.linalg.LinAlgError("ill-conditioned")
        chol = np.linalg.cholesky(gram)
    except np.linalg.LinAlgError:
        q, rr = np.linalg.qr(scaled)

        def by_qr(x: Array, out: Array | None = None) -> tuple[Array, Array]:
            qx = q.T @ x
            return np.linalg.solve(rr, qx) / (norms if x.ndim == 1 else norms[:, None]), _minus(x, q, qx, out)

        return by_qr

    def by_gram(x: Array, out: Array | None = None) -> tuple[Array, Array]:
        c = np.linalg.solve(chol.T, np.linalg.solve(chol, scaled.T @ x))
        return c / (norms if x.ndim == 1 else norms[:, None]), _minus(x, scaled, c, out)

    return by_gram


def _minus(x: Array, basis: Array, coef: Array, out: Array | None) -> Array:
    """``x - basis coef``; with `out`, its negative ``basis coef - x`` written there (no temporary)."""
    if out is None:
        result: Array = x - basis @ coef
        return result
    np.matmul(basis, coef, out=out)
    out -= x
    return out


def _levenberg_marquardt(
    fun: Any,
    jacobian: Any,
    theta0: Array,
    max_evaluations: int,
    residuals: int,
    scale: float | None = None,
    constant: float = 0.0,
    damping: float = 1e-3,
) -> tuple[Array, int, Array, Array, bool]:
    """Minimise ``|r(theta)|^2`` by :func:`rigidid.core.optimize.levenberg_marquardt` with geodesic acceleration.

    `fun(theta)` gives the residual, `jacobian(theta)` the residual and its Jacobian (computed
    only at accepted points: the expensive call; `fun` costs about a fifteenth of it here).
    The geodesic acceleration's second directional derivative ``r''_v`` is a central
    difference along the step ``v`` (two residual evaluations).

    Stops, converged, when the Gauss-Newton decrement ``g^T (J^T J)^+ g`` (``g = J^T r``)
    over the residual variance ``|r|^2 / (n - n_theta)`` falls below :data:`_DECREMENT`:
    the remaining Gauss-Newton step, in standard-error units, is below about 0.2 of one
    standard error; or when the decrement is below 4 and the last step lowered the cost by
    less than :data:`_STALL` variances: a minimum on the boundary of the positive
    (semi-)definite J, K, C, where the Gauss-Newton step points out of the parameterisation's
    reach (a weakly damped direction whose estimate would be negative); or when the
    decrement is below the rounding floor of `scale` (``|y|^2`` of the weighted data; the
    cost at the start by default): exact data. Stops unconverged after `max_evaluations`
    residual evaluations (may overrun by three) or when no step lowers the cost.
    `residuals` is the length of ``r`` (the variance's degrees of freedom); `constant` is added
    to every cost (the part of ``|r|^2`` that no parameter moves, when `fun` gives the rest:
    :func:`_reduced`); `damping` is the initial Levenberg-Marquardt damping.

    Returns
    -------
    theta, evaluations, residual, jacobian, converged
    """
    last: dict[str, Array] = {}

    def normal(x: Array, index: Any) -> tuple[Array, Array, Array]:
        r, jm = jacobian(x[0])
        last.update(theta=x[0].copy(), r=r, jm=jm)
        return np.array([r @ r + constant]), (jm.T @ r)[None], (jm.T @ jm)[None]

    def residual(theta: Array) -> Array | None:
        try:
            return np.asarray(fun(theta))
        except np.linalg.LinAlgError:
            return None

    def cost(x: Array, index: Any) -> Array:
        r = residual(x[0])
        return np.array([math.inf if r is None else float(r @ r) + constant])

    def acceleration(x: Array, step: Array, index: Any) -> Array:
        h = _GEODESIC_H
        ahead, behind = residual(x[0] + h * step[0]), residual(x[0] - h * step[0])
        if ahead is None or behind is None:
            return np.zeros_like(step)
        out: Array = (last["jm"].T @ ((ahead - 2.0 * last["r"] + behind) / h**2))[None]
        return out

    best = levenberg_marquardt(
        normal, cost, theta0[None], max_evaluations=max_evaluations, scale=None if scale is None else np.array([scale]),
        residuals=residuals, decrement=_DECREMENT, stall=(_STALL, _STALL_DECREMENT), acceleration=acceleration,
        damping=damping,
    )  # fmt: skip
    return best.x[0], int(best.evaluations[0]), last["r"], last["jm"], bool(best.converged[0])


def _dropped_term(design: Array, res: Array, ex: CArray, t: Array, phiw: CArray, dphiw: CArray, dlam: CArray) -> Array:
    """The term of the full (Golub-Pereyra) variable-projection Jacobian that Kaufman's drops.

    ``(A^+)^T dA_j^T r = A (A^T A)^-1 dA_j^T r`` for every parameter j, shape (n p, 51);
    ``dA_j^T r`` from ``dU_jnck = e^{lambda_k t_n} (dphi_jck + phi_ck t_n dlambda_jk)``.
    """
    e1 = res.T @ ex  # (p, 6): sum_n r_nc e^{lambda_k t_n}
    e2 = res.T @ (ex * t[:, None])
    s = np.einsum("ck,jck->jk", e1, dphiw) + dlam * np.einsum("ck,ck->k", phiw, e2)[None, :]
    z = np.zeros((N_PARAMETERS, design.shape[1]))
    z[:, :6], z[:, 6:12] = s.real, -s.imag
    coef = np.linalg.lstsq(design.T @ design, z.T, rcond=None)[0]  # (A^T A)^-1 z^T
    out: Array = design @ coef
    return out


def _model_derivative(ex: CArray, t: Array, g1: CArray, g2: CArray) -> Array:
    """``Re sum_k e^{lambda_k t_n} (g1_jck + t_n g2_jck)`` as one real matrix product, shape (n, p, 51).

    The complex product ``[E, t E] [G1; G2]`` has real part ``[Re, Im] [Re G; -Im G]``: one BLAS
    call on (n, 24) by (24, 51 p), and no (n, 51, p) complex temporaries.
    """
    n, p = t.shape[0], g1.shape[1]
    e = np.hstack([ex, ex * t[:, None]])  # (n, 12)
    g = np.concatenate([g1, g2], axis=2).transpose(2, 1, 0).reshape(12, p * N_PARAMETERS)  # (12, p 51)
    left = np.hstack([e.real, e.imag])
    right = np.vstack([g.real, -g.imag])
    out: Array = (left @ right).reshape(n, p, N_PARAMETERS)
    return out


def _evaluate(
    theta: Array, data: _Data, pos: Array, dirs: Array, omega: float, jac: bool, mix: Array | None = None
) -> tuple[Array, Array]:
    """Weighted residual (n p,) and its projected Jacobian (n p, 51); with `mix` (m, p) the shapes are ``mix phi``
    (the decays then hold the channels' combinations, :func:`_reduced`)."""
    lam, phi, dlam, dphi = _modes(theta, pos, dirs, jac)
    if mix is not None:
        phi = mix @ phi
        dphi = np.matmul(mix, dphi) if jac else dphi
    w = 1.0 / data.sigma
    res_parts = []
    j_all = np.empty((sum(d.size for d in data.decays) if jac else 0, N_PARAMETERS))
    row = 0
    for y in data.decays:
        n, p = y.shape
        t: Array = np.arange(n, dtype=float) * (data.dt * omega)
        design, ex = _design(lam, phi * w[:, None], t, data.drift)
        yw = (y * w).reshape(-1)
        project = _projector(design)
        beta, r = project(yw)
        res_parts.append(r)
        if jac:
            amp = beta[:6] + 1j * beta[6:12]  # columns Re u and -Im u: model Re(u (a_re + i a_im))
            # d model = Re( sum_k a_k (dphi_k + phi_k t dlam_k) e^{lam_k t} )
            wd = dphi * w[None, :, None]  # (51, p, 6)
            g1 = wd * amp  # (51, p, 6)
            g2 = (phi * w[:, None])[None, :, :] * (dlam * amp)[:, None, :]
            dm = _model_derivative(ex, t, g1, g2).reshape(n * p, N_PARAMETERS)  # d model / d theta
            jp = project(dm, j_all[row : row + n * p])[1]  # minus the projected derivative, in place
            del dm
            if _GOLUB_PEREYRA:
                jp -= _dropped_term(design, r.reshape(n, p), ex, t, phi * w[:, None], wd, dlam)
        row += n * p
    r_all = np.concatenate(res_parts)
    return r_all, j_all


def refine_body(
    records: Sequence[ArrayLike],
    dt: float,
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    starts: Sequence[int],
    onsets: Sequence[int],
    decimation: int,
    center_of_gravity: ArrayLike,
    inertia_per_mass: ArrayLike,
    stiffness_per_mass: ArrayLike,
    damping_per_mass: ArrayLike,
    max_evaluations: int = 240,
    drift: bool = False,
) -> Refinement:
    """Fit CG, J/m, K/m and C/m to the free decays of every impact (output error).

    Parameters
    ----------
    records : sequence of array_like, shape (n_k, p)
        The raw records, samples by sensors (sensor reading along its axis).
    dt : float
        Sample interval (s).
    positions, directions : array_like, shape (p, 3)
        The sensors (length; directions normalised here).
    starts, onsets : sequence of int
        Per record, the first sample of the free decay and of the impact
        (:class:`~rigidid.core.timedomain.preprocess.Impact`); samples before
        the onset are the pre-trigger the noise levels come from.
    decimation : int
        Decimation factor applied to the decays before the fit (the modal
        estimate's: it keeps the band with the anti-alias margin).
    center_of_gravity, inertia_per_mass, stiffness_per_mass, damping_per_mass
        The start: the structured identification from the estimated modes
        (layout units, per mass, at the CG).
    max_evaluations : int
        Largest number of residual evaluations (three per iteration of the
        optimiser, plus one Jacobian per accepted step); 0 evaluates the start only
        (its Cramér-Rao bound, e.g. at the truth of a simulation).
    drift : bool
        Fit a linear drift per channel and impact beside the offset
        (:attr:`PreparedDecays.drift`).

    Returns
    -------
    Refinement

    Raises
    ------
    InputError
        Records too short.
    numpy.linalg.LinAlgError
        When the start has not six underdamped modes.

    Notes
    -----
    Model: the state matrix ``A = [[-M^-1 C, -M^-1 K], [I, 0]]`` of eq. (19),
    per mass, in the layout's dimensionless frame (length over the RMS sensor
    radius, time times the median natural frequency). ``J/m``, ``K/m`` and
    ``C/m`` are ``L L^T`` of lower-triangular factors, so they stay positive
    (semi-)definite. Channel ``c`` of impact ``i`` reads
    ``y(t) = 2 Re sum_k a_ik phi_ck exp(lambda_k t) + o_ic + noise`` with
    ``phi_k = T_g (lambda_k v_k)``. The amplitudes ``a_ik`` and offsets
    ``o_ic`` are solved by linear least squares inside the residual; the
    Jacobian is Kaufman's projected one, from the eigenvalue and eigenvector
    derivatives ``dlambda_k = (V^-1 dA V)_kk``, ``dV = V C``,
    ``C_jk = (V^-1 dA V)_jk / (lambda_k - lambda_j)``. Residuals are divided
    by each channel's noise level: from the pre-trigger (at least 32 samples
    per record; scaled by the anti-alias filter's noise gain), otherwise from
    the start's own residual, then from the fit's. The Cramér-Rao bound is
    ``(J^T J)^-1`` in whitened units, mapped to the physical values by their
    derivatives (delta method). At most :data:`MAX_ROWS` residuals are fitted
    (memory about ``80 MAX_ROWS`` bytes per 51 parameters), the end of long
    decays cut. Limits: modes must be distinct (the eigenvector derivative
    divides by pole gaps); noise assumed white and independent between
    channels; a start more than about the frequency resolution ``1 /
    duration`` away falls into a local minimum, which a normalised cost well
    above 1 exposes (the caller falls back).
    """
    recs = _in_range([np.asarray(r, dtype=float) for r in records])
    data = _prepare(recs, float(dt), starts, onsets, max(1, int(decimation)))
    del recs
    if drift:
        data = replace(data, drift=True)
    return refine_prepared(
        data, dt, positions, directions, center_of_gravity=center_of_gravity, inertia_per_mass=inertia_per_mass,
        stiffness_per_mass=stiffness_per_mass, damping_per_mass=damping_per_mass, max_evaluations=max_evaluations,
    )  # fmt: skip


def refine_prepared(
    data: PreparedDecays,
    dt: float,
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    center_of_gravity: ArrayLike,
    inertia_per_mass: ArrayLike,
    stiffness_per_mass: ArrayLike,
    damping_per_mass: ArrayLike,
    max_evaluations: int = 240,
    drift: bool | None = None,
) -> Refinement:
    """:func:`refine_body` on decays already prepared (:func:`prepare_decays`, or read in row blocks).

    Parameters
    ----------
    data : PreparedDecays
        The decays at the fit's rate and the channels' noise levels.
    dt : float
        Sample interval of the records the decays came from (s): the fit's
        factor is ``data.dt / dt``.
    positions, directions, center_of_gravity, inertia_per_mass, stiffness_per_mass, damping_per_mass, max_evaluations
        As for :func:`refine_body`.
    drift : bool, optional
        Overrides ``data.drift``.

    Returns
    -------
    Refinement

    Raises
    ------
    numpy.linalg.LinAlgError
        When the start has not six underdamped modes.

    Notes
    -----
    The model, the fit and the bound are :func:`refine_body`'s (eq. (19)).
    """
    if drift is not None and drift != data.drift:
        data = replace(data, drift=drift)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    lf = layout_frame(pos)
    pos_l = lf.to_local(pos)
    frame0 = _Frame(lf.centre, lf.scale, 1.0)
    theta_unit = frame0.to_theta(
        np.asarray(center_of_gravity, float), np.asarray(inertia_per_mass, float),
        np.asarray(stiffness_per_mass, float), np.asarray(damping_per_mass, float),
    )  # fmt: skip
    lam0, *_ = _modes(theta_unit, pos_l, dirs, False)
    omega = float(np.median(np.abs(lam0)))
    frame = _Frame(lf.centre, lf.scale, omega)
    theta0 = frame.to_theta(
        np.asarray(center_of_gravity, float), np.asarray(inertia_per_mass, float),
        np.asarray(stiffness_per_mass, float), np.asarray(damping_per_mass, float),
    )  # fmt: skip
    if data.noise_from == "residual":
        r0, _ = _evaluate(theta0, data, pos_l, dirs, omega, False)
        per = r0.reshape(-1, pos.shape[0])
        sigma = np.sqrt(np.mean(per**2, axis=0))
        data = replace(data, sigma=np.where(sigma > 0, sigma, 1.0))

    if max_evaluations > 0:
        theta, nfev, r, jm, converged = _fit(data, pos_l, dirs, omega, theta0, max_evaluations)
    else:
        theta, nfev, converged = theta0, 0, False
        r, jm = _evaluate(theta, data, pos_l, dirs, omega, True)
    n_res = r.size
    dof = max(n_res - N_PARAMETERS - len(data.decays) * _linear_per_impact(pos.shape[0], data.drift), 1)
    cost = float(r @ r) / dof if data.noise_from == "pretrigger" else 1.0
    s2 = float(r @ r) / dof
    g, j, k, c = frame.physical(theta)
    lam, *_ = _modes(theta, pos_l, dirs, False)
    q_fit = max(1, round(data.dt / float(dt)))  # _prepare may decimate less than `decimation`
    std = _bound(theta, jm, s2, frame, pos_l, dirs, r, [d.shape[0] for d in data.decays], q_fit, data.drift)
    misfit = _misfit(r, data, dof / n_res, q_fit)
    return Refinement(
        center_of_gravity=g,
        inertia_per_mass=j,
        stiffness_per_mass=k,
        damping_per_mass=c,
        poles=lam * omega,
        std=std,
        normalised_cost=cost,
        noise_from=data.noise_from,
        residuals=n_res,
        evaluations=nfev,
        converged=converged,
        misfit=misfit,
    )


_COARSE_ROWS = 24_000
"""Residuals (samples x channel combinations) of the coarse fit that starts the full one (:func:`_fit`)."""
_COARSE_STEP = 3  # the coarse fit runs only when it takes at most every third sample
_FINE_DAMPING = 1e-9  # initial damping of the full fit after the coarse one (Gauss-Newton steps from a near start)


@dataclass(frozen=True)
class _Reduced:
    """The fit's problem on fewer columns (:func:`_reduced`)."""

    data: PreparedDecays  # the columns fitted, weights one
    mix: Array | None  # (m, p): the channels' shapes to the columns' (None: the channels themselves)
    constant: float  # the part of |r|^2 no parameter moves


def _channel_basis(sigma: Array, pos: Array, dirs: Array) -> Array | None:
    """Orthonormal basis (p, 6) of the span of ``diag(1/sigma) T_0`` (eq. (3)); None for p <= 6 or rank < 6."""
    if pos.shape[0] <= 6:
        return None
    q, rr = np.linalg.qr(sensor_matrix(pos, dirs) / sigma[:, None])
    d = np.abs(np.diag(rr))
    return q if float(d.min()) > 1e-8 * float(d.max()) else None


def _reduced(data: PreparedDecays, basis: Array | None, step: int = 1) -> _Reduced:
    """Every `step`-th sample of the decays, their weighted channels projected on `basis` (:func:`_channel_basis`).

    Every CG ``g`` gives shapes ``T_g (lambda v)`` in the span of ``T_0``'s columns
    (``T_g = T_0 [[I, G], [0, I]]``, ``G`` the skew matrix of ``g``, eq. (3)), so the model's
    weighted shapes lie in the span of ``Q`` (`basis`) whatever the parameters. The offsets
    (and drifts) are free per channel: the weighted data's part orthogonal to ``Q`` is fitted
    by them alone, and its least-squares ``|.|^2`` is `constant`. The rest is the same problem
    on the six columns ``Y W Q`` with shapes ``Q^T W phi``: the same cost (plus `constant`),
    gradient and ``J^T J``, exactly, at ``6 / p`` of the work.
    """
    if basis is None:
        return _Reduced(replace(data, decays=[d[::step] for d in data.decays], dt=data.dt * step), None, 0.0)
    w = 1.0 / data.sigma
    decays, constant = [], 0.0
    for y in data.decays:
        yw = y[::step] * w
        cols = yw @ basis
        rest = yw - cols @ basis.T
        n = rest.shape[0]
        trend = np.column_stack([np.ones(n), np.arange(n, dtype=float)]) if data.drift else np.ones((n, 1))
        coef = np.linalg.lstsq(trend, rest, rcond=None)[0]
        constant += float(np.sum((rest - trend @ coef) ** 2))
        decays.append(cols)
    reduced = replace(data, decays=decays, sigma=np.ones(basis.shape[1]), dt=data.dt * step, pre_m2=None)
    return _Reduced(reduced, basis.T * w[None, :], constant)


def _fit(
    data: PreparedDecays, pos: Array, dirs: Array, omega: float, theta0: Array, max_evaluations: int
) -> tuple[Array, int, Array, Array, bool]:
    """:func:`_levenberg_marquardt` on the channels' rigid combinations (:func:`_reduced`), from a coarse fit's end.

    When the decays hold more than ``3 _COARSE_ROWS`` residuals, a fit on every k-th sample
    (about :data:`_COARSE_ROWS` residuals: the model is exact at any sample times) gives the
    full fit its start, a fraction of a standard error from the minimum, so the full fit ends
    in a few iterations. The full fit's end, its convergence test and the cost are those of the
    fit on every channel and sample; its residual and Jacobian are evaluated there on every
    channel (the intervals and the acceptance test are per channel).

    Returns
    -------
    theta, evaluations, residual, jacobian, converged
        Evaluations of both fits.
    """
    basis = _channel_basis(data.sigma, pos, dirs)
    columns = data.sigma.size if basis is None else basis.shape[1]
    step = sum(d.shape[0] for d in data.decays) * columns // _COARSE_ROWS
    scale = sum(float(np.sum((d / data.sigma) ** 2)) for d in data.decays)
    theta, nfev, converged = theta0, 0, False
    r, jm = np.zeros(0), np.zeros((0, N_PARAMETERS))
    for k in [step, 1] if step >= _COARSE_STEP else [1]:
        red = _reduced(data, basis, k)
        budget = max_evaluations - nfev if k > 1 else max(max_evaluations - nfev, max_evaluations // 4)

        def both(th: Array, red: _Reduced = red) -> tuple[Array, Array]:
            return _evaluate(th, red.data, pos, dirs, omega, True, red.mix)

        def fun(th: Array, red: _Reduced = red) -> Array:
            return _evaluate(th, red.data, pos, dirs, omega, False, red.mix)[0]

        n_k = sum(d.shape[0] for d in red.data.decays) * data.sigma.size
        damping = _FINE_DAMPING if nfev else 1e-3
        theta, used, r, jm, converged = _levenberg_marquardt(
            fun, both, theta, budget, n_k, scale / k, red.constant, damping
        )
        nfev += used
    if basis is not None:
        r, jm = _evaluate(theta, data, pos, dirs, omega, True)
    return theta, nfev, r, jm, converged


def _misfit(r: Array, data: PreparedDecays, dof_fraction: float, factor: int) -> MisfitTest | None:
    """:func:`~rigidid.core.timedomain.acceptance.misfit_test` of the fit's residual against the pre-trigger."""
    if data.noise_from != "pretrigger" or data.pre_m2 is None or len(data.pre_counts) != len(data.decays):
        return None
    from rigidid.core.timedomain.intervals import noise_correlation

    gain = float(np.sum(fir_taps(factor) ** 2)) if factor > 1 else 1.0
    counts = np.asarray(data.pre_counts, dtype=float)
    variance = data.pre_m2 / np.maximum(counts - 1.0, 1.0)[:, None] * gain / data.sigma[None, :] ** 2
    lengths = [d.shape[0] for d in data.decays]
    return misfit_test(r, lengths, data.sigma.size, dof_fraction, data.pre_counts, variance, noise_correlation(factor))


def _linear_per_impact(p: int, drift: bool) -> int:
    """Linear unknowns per impact: 12 modal amplitudes, an offset per channel (and a drift)."""
    return 12 + (2 if drift else 1) * p


def _outputs(theta: Array, frame: _Frame, pos_l: Array, dirs: Array) -> Array:
    g, j, k, c = frame.physical(theta)
    lam, *_ = _modes(theta, pos_l, dirs, False)
    w = np.abs(lam)
    return np.concatenate([g, j.ravel(), k.ravel(), c.ravel(), w * frame.omega / (2 * np.pi), -lam.real / w])


def _bound(
    theta: Array,
    jm: Array,
    s2: float,
    frame: _Frame,
    pos_l: Array,
    dirs: Array,
    residual: Array | None = None,
    lengths: Sequence[int] | None = None,
    factor: int = 1,
    drift: bool = False,
) -> dict[str, Array]:
    """Standard errors of the physical values (delta method) from the parameters' covariance.

    With `residual` and `lengths` (decimated samples per impact): the calibrated
    covariance of :func:`rigidid.core.timedomain.intervals.parameter_covariance`
    (sandwich from the residual per impact and channel, the decimation filter's
    correlation, the remaining Gauss-Newton step). Without: the textbook bound
    ``s2 (J^T J)^+``.
    """
    if residual is not None and lengths is not None:
        from rigidid.core.timedomain.intervals import parameter_covariance

        n_linear = len(lengths) * _linear_per_impact(pos_l.shape[0], drift)
        cov = parameter_covariance(jm, residual, lengths, pos_l.shape[0], factor, n_linear).matrix
    else:
        cov = s2 * pseudo_inverse(jm.T @ jm, symmetric=True)[0]  # pseudo-inverse of the information
    base = _outputs(theta, frame, pos_l, dirs)
    grad = np.zeros((base.size, N_PARAMETERS))
    for i in range(N_PARAMETERS):
        h = 1e-6 * max(1.0, abs(theta[i]))
        step = theta.copy()
        step[i] += h
        back = theta.copy()
        back[i] -= h
        grad[:, i] = (_outputs(step, frame, pos_l, dirs) - _outputs(back, frame, pos_l, dirs)) / (2 * h)
    var = np.einsum("ij,jk,ik->i", grad, cov, grad)
    sd = np.sqrt(np.maximum(var, 0.0))
    return {
        "center_of_gravity": sd[:3],
        "inertia_per_mass": sd[3:12].reshape(3, 3),
        "stiffness_per_mass": sd[12:48].reshape(6, 6),
        "damping_per_mass": sd[48:84].reshape(6, 6),
        "frequency_hz": sd[84:90],
        "damping_ratio": sd[90:96],
    }


def good_fit(refinement: Refinement) -> bool:
    """Whether the normalised cost says the fit is at the global minimum (below 2)."""
    return bool(np.isfinite(refinement.normalised_cost) and refinement.normalised_cost < _GOOD_COST)


@dataclass(frozen=True)
class RecordBound:
    """Cramér-Rao intervals of the refined body, in the form of the other record intervals.

    Attributes
    ----------
    center_of_gravity, inertia, principal_moments, stiffness_diagonal : IntervalEstimate
        Estimate, standard error and 95 % interval (estimate +- 1.96 std) of
        each quantity (:class:`rigidid.core.uncertainty.IntervalEstimate`).
    per_mass : bool
        Whether inertia and stiffness are per mass (no mass given).
    normalised_cost : float
        See :class:`Refinement`.
    noise_from : str
        See :class:`Refinement`.
    residuals : int
        Number of residuals fitted.
    variance_from : str
        How the standard errors were estimated: ``"sandwich"``, the calibrated
        covariance of :func:`rigidid.core.timedomain.intervals.parameter_covariance`
        (the fit's residual per impact and channel, the decimation filter's
        correlation, the remaining Gauss-Newton step).
    evaluations : int or None
        Residual evaluations of the optimiser (:class:`Refinement`).
    converged : bool or None
        Whether the optimiser met its convergence test (:class:`Refinement`);
        when False the intervals include the remaining Gauss-Newton step.
    sensor_budget, tolerances
        See :func:`record_bound`.
    misfit : MisfitTest or None
        The refit's acceptance test (:class:`Refinement`).
    """

    center_of_gravity: Any
    inertia: Any
    principal_moments: Any
    stiffness_diagonal: Any
    per_mass: bool
    normalised_cost: float
    noise_from: str
    residuals: int
    variance_from: str = "sandwich"
    evaluations: int | None = None
    converged: bool | None = None
    sensor_budget: dict[str, dict[str, Array]] | None = None
    tolerances: dict[str, float] | None = None
    misfit: MisfitTest | None = None


def record_bound(
    refinement: Refinement,
    mass: float | None,
    sensor_std: dict[str, dict[str, Array]] | None = None,
    tolerances: dict[str, float] | None = None,
) -> RecordBound:
    """95 % intervals from the calibrated standard errors of a refinement.

    Parameters
    ----------
    refinement : Refinement
    mass : float or None
        Scales inertia and stiffness to absolute values when given.
    sensor_std : dict, optional
        Per type-B source (:data:`rigidid.core.sensor_budget.SOURCES`), the
        standard deviations ``"center_of_gravity"``, ``"inertia_per_mass"``,
        ``"stiffness_per_mass"`` (:attr:`rigidid.core.sensor_budget.SensorBudget.std`):
        combined with the noise's in quadrature (GUM 5.1.2).
    tolerances : dict, optional
        The bounds the budget used, recorded in the result.

    Returns
    -------
    RecordBound
        Normal intervals ``estimate +- 1.96 std``; the principal moments'
        standard errors come from the inertia tensor's by first-order
        perturbation of its eigenvalues. With `sensor_std`, ``sensor_budget``
        holds each source's std (``"noise"`` first) of the CG and the inertia.

    Notes
    -----
    ``refinement.std`` is the sandwich covariance of
    :func:`rigidid.core.timedomain.intervals.parameter_covariance` mapped to the
    physical values: on samples/four-mounts (two impacts, 8 s at 512 Hz) the
    textbook bound ``s^2 (J^T J)^-1`` covered the truth in about 0.8 of the
    cases, because the noise level differs between impacts while the weights pool
    them, and because fits stopped by the evaluation budget lie off the minimum
    (``benchmarks/coverage.py``).
    """
    from rigidid.core.timedomain.intervals import VARIANCE_FROM
    from rigidid.core.uncertainty import IntervalEstimate

    scale = 1.0 if mass is None else float(mass)

    def interval(estimate: Array, std: Array) -> IntervalEstimate:
        return IntervalEstimate(estimate, std, estimate - _Z95 * std, estimate + _Z95 * std)

    moments, axes = np.linalg.eigh(refinement.inertia_per_mass)
    std = dict(refinement.std)
    budget = None
    if sensor_std is not None:
        budget = {"noise": {"center_of_gravity": std["center_of_gravity"],
                            "inertia_per_mass": scale * std["inertia_per_mass"]}}  # fmt: skip
        for source, parts in sensor_std.items():
            budget[source] = {"center_of_gravity": parts["center_of_gravity"],
                              "inertia_per_mass": scale * parts["inertia_per_mass"]}  # fmt: skip
        for key in ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass"):
            std[key] = np.sqrt(std[key] ** 2 + sum(parts[key] ** 2 for parts in sensor_std.values()))
    sj = std["inertia_per_mass"]
    # var(lambda_i) ~ sum_ab (u_ai u_bi)^2 var(J_ab), entries treated independent
    pm_std = np.sqrt(np.einsum("ai,bi,ab->i", axes**2, axes**2, sj**2))
    return RecordBound(
        center_of_gravity=interval(refinement.center_of_gravity, std["center_of_gravity"]),
        inertia=interval(scale * refinement.inertia_per_mass, scale * sj),
        principal_moments=interval(scale * moments, scale * pm_std),
        stiffness_diagonal=interval(
            scale * np.diag(refinement.stiffness_per_mass), scale * np.diag(std["stiffness_per_mass"])
        ),
        per_mass=mass is None,
        normalised_cost=refinement.normalised_cost,
        noise_from=refinement.noise_from,
        residuals=refinement.residuals,
        variance_from=VARIANCE_FROM,
        evaluations=refinement.evaluations,
        converged=refinement.converged,
        sensor_budget=budget,
        tolerances=tolerances,
        misfit=refinement.misfit,
    )
