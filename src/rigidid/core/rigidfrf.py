"""The exact rigid-body fit of accelerance FRFs: mass, stiffness and damping matrices at once.

The mass line (:mod:`rigidid.core.massline`) expands the accelerance of a body
on mounts in powers of ``1/w`` and keeps the first correction only, which is
wrong when the band lies near the support modes. This module fits the rigid-body
model itself, eq. (1) of [1] in the frequency domain: the rigid coordinates
``X(w) = T^+ H(w)`` (``6 x q`` per line, ``q`` references) of the accelerance
``H = -w^2 T (K - w^2 M + i w C)^-1 T_f^T`` satisfy, for every line,

``K X + i w C X - w^2 M X = -w^2 T_f^T``

which is **linear** in the ten inertial parameters of ``M`` (``m``, ``m c``, the
inertia about the origin) and in the symmetric ``K`` and ``C`` (21 each). Elastic
modes above the band add an upper residual ``R(w) = sum_b R_b phi_b(w)`` to
``X``; in the equation error it enters as ``sum_b G_b phi_b(w)`` (``G_b ~ -M R_b``,
free ``6 x q`` matrices), and exactly in the output-error refinement.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.frf import rigid_receptance
from rigidid.core.geometry import skew
from rigidid.core.linalg import numerical_rank
from rigidid.errors import IdentificationError, InputError

__all__ = ["RigidFrfFit", "mass_matrix_from_parameters", "rigid_frf_fit"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

_SYM = [(i, j) for i in range(6) for j in range(i, 6)]


@dataclass(frozen=True)
class RigidFrfFit:
    """The rigid-body model fitted to the rigid coordinates of accelerance FRFs.

    Attributes
    ----------
    parameters : ndarray, shape (10,)
        ``(m, m c_x, m c_y, m c_z, Jxx, Jyy, Jzz, Jxy, Jxz, Jyz)`` about the origin of
        the coordinates (inertia with the sign of :func:`mass_matrix_from_parameters`).
    mass_matrix, stiffness, damping : ndarray, shape (6, 6)
        ``M``, ``K`` and ``C`` about that origin (``K`` and ``C`` only as far as the
        data determine them: the minimum-norm part otherwise).
    residual : float
        Output misfit of the model (upper residual fitted) to the rigid
        coordinates, RMS over the lines, relative to the RMS of the coordinates.
    refined : bool
        Whether the output-error fit moved from the equation-error start.
    covariance : ndarray, shape (10, 10), or None
        Covariance of `parameters` (sandwich of the output-error fit, clustered per line and reference);
        None without the output-error fit.
    misfit_rows : ndarray, shape (12 q, n), or None
        The output-error fit's weighted misfit (real then imaginary parts, per rigid coordinate
        at the sensors and reference) along the lines, for
        :func:`rigidid.core.frfstats.misfit_units`.
    """

    parameters: Array
    mass_matrix: Array
    stiffness: Array
    damping: Array
    residual: float
    refined: bool
    covariance: Array | None = None
    misfit_rows: Array | None = None


def mass_matrix_from_parameters(theta: ArrayLike) -> Array:
    """The 6 x 6 rigid-body mass matrix about the origin from its ten parameters.

    Parameters
    ----------
    theta : array_like, shape (10,)
        ``(m, m c_x, m c_y, m c_z, Jxx, Jyy, Jzz, Jxy, Jxz, Jyz)``: mass, first
        moments, inertia about the origin (off-diagonals as stored in the tensor).

    Returns
    -------
    ndarray, shape (6, 6)
        ``[[m I, -[m c]x], [[m c]x, J_o]]`` (translations first).
    """
    t = np.asarray(theta, dtype=float)
    out = np.zeros((6, 6))
    out[:3, :3] = t[0] * np.eye(3)
    out[:3, 3:] = -skew(t[1:4])
    out[3:, :3] = skew(t[1:4])
    out[3:, 3:] = np.array([[t[4], t[7], t[8]], [t[7], t[5], t[9]], [t[8], t[9], t[6]]])
    return out


def _sym(v: Array) -> Array:
    out = np.zeros((6, 6))
    for k, (i, j) in enumerate(_SYM):
        out[i, j] = out[j, i] = v[k]
    return out


def _model(u: Array, theta: Array, kv: Array, cv: Array, tft: Array) -> CArray:
    """``X(u) = -u^2 (K - u^2 M + i u C)^-1 T_f^T``, shape (n, 6, q)."""
    x = rigid_receptance(1j * u, mass_matrix_from_parameters(theta), _sym(kv), _sym(cv), tft)
    result: CArray = -(u**2)[:, None, None] * x
    return result


def rigid_frf_fit(
    omega: ArrayLike,
    coordinates: ArrayLike,
    forces: ArrayLike,
    *,
    damping: bool = True,
    residual_basis: ArrayLike | None = None,
    refine: bool = True,
    sensor_gram: ArrayLike | None = None,
) -> RigidFrfFit:
    """Fit ``M``, ``K`` and ``C`` of a rigid body to its accelerance in rigid coordinates.

    Parameters
    ----------
    omega : array_like, shape (n,)
        Angular frequencies of the lines (any unit of 1/time; ``K`` and ``C`` come
        out per that unit squared and per that unit).
    coordinates : array_like of complex, shape (6, q, n)
        Rigid coordinates of the accelerance, ``X = T^+ H`` (per unit force), about
        the origin of `forces`.
    forces : array_like, shape (6, q)
        ``T_f^T``: the generalised force of each unit reference force about that origin.
    damping : bool
        Fit ``C`` (else ``C = 0``).
    residual_basis : array_like, shape (n, b), optional
        Real functions of frequency of the upper residual (elastic modes above
        the lines), each with its own free real ``6 x q`` coefficient.
    refine : bool
        Fit by output error (default), started from the equation-error fit; else the
        equation-error fit alone (biased on noisy FRFs: its regressors hold the noise).
    sensor_gram : array_like, shape (6, 6), optional
        ``T^T T`` of the sensors the coordinates were projected from: the output error
        is measured at the sensors, ``|T (X - X_model)|`` (identity: in rigid coordinates).

    Returns
    -------
    RigidFrfFit

    Raises
    ------
    InputError
        If the shapes disagree.
    IdentificationError
        If the lines do not determine the ten inertial parameters, or the fit gives a
        mass that is not positive.

    Notes
    -----
    Equation error (the start): each line's equation of eq. (1) of [1],
    ``K X + i w C X - w^2 M X = -w^2 T_f^T``, divided by ``w^2 ||X(w)||``, real and
    imaginary parts stacked, columns scaled to unit norm; the inertial parameters are
    solved with ``K``, ``C`` and the residual coefficients projected out, so that what the
    data leave free in ``K`` and ``C`` does not leak into ``M``. Exact for noise-free
    FRFs, but with noisy FRFs the regressors ``X`` hold the noise (errors in variables):
    on femtools' soft-mount case at 1 % noise the mass came out 15-45 % low.

    Output error (:func:`_output_error`): the misfit of the model's accelerance
    ``X_m = -w^2 (K - w^2 M + i w C)^-1 T_f^T`` (plus the upper residual, projected
    out) to the data, at the sensors, each reference and line weighted by the inverse of
    the data's norm there (the noise of an FRF grows with its level), minimised by the
    core's Levenberg-Marquardt (:func:`rigidid.core.optimize.levenberg_marquardt`): the
    noise is in the residual only, so the estimate is consistent. The covariance of the
    ten inertial parameters (``covariance``) is the sandwich of the fit clustered per line
    and reference (:meth:`_Problem.covariance`).
    """
    w = np.asarray(omega, dtype=float).reshape(-1)
    x = np.asarray(coordinates, dtype=complex)
    tft = np.asarray(forces, dtype=float)
    n = w.size
    if x.ndim != 3 or x.shape[0] != 6 or x.shape[2] != n or tft.shape != x.shape[:2]:
        raise InputError(f"coordinates must have shape (6, q, {n}) and forces (6, q), got {x.shape} and {tft.shape}")
    basis = np.zeros((n, 0)) if residual_basis is None else np.asarray(residual_basis, dtype=float).reshape(n, -1)
    w0 = float(np.sqrt(w.min() * w.max()))
    u = w / w0  # K and C are fitted per w0^2 and w0
    xs = np.moveaxis(x, 2, 0)  # (n, 6, q)
    theta, kv, cv = _equation_error(u, xs, tft, basis, damping)
    gram = np.eye(6) if sensor_gram is None else np.asarray(sensor_gram, dtype=float)
    chol = np.linalg.cholesky(gram / np.trace(gram) * 6.0).T  # R, R^T R = T^T T (scaled)
    weights = 1.0 / np.maximum(np.linalg.norm(np.einsum("ij,njq->niq", chol, xs), axis=1), np.finfo(float).tiny)
    problem = _Problem(u, xs, tft, basis, damping, chol, weights)
    refined = False
    covariance = None
    if refine:
        theta, kv, cv, refined = _output_error(problem, theta, kv, cv)
        if refined:
            problem, theta, kv, cv = _model_weighted(problem, theta, kv, cv)
        covariance = problem.covariance(theta, kv, cv)
    if not theta[0] > 0.0:
        raise IdentificationError(f"the rigid-body fit gives a mass of {theta[0]:.4g}, not positive")
    rows = problem.residual_rows(theta, kv, cv)
    x_flat = xs.reshape(n, -1)
    r_out = x_flat - _model(u, theta, kv, cv, tft).reshape(n, -1)
    r2 = np.concatenate([r_out.real, r_out.imag])
    if basis.shape[1]:
        g_un = np.concatenate([basis, np.zeros_like(basis)])
        r2 = r2 - g_un @ np.linalg.lstsq(g_un, r2, rcond=None)[0]
    return RigidFrfFit(
        parameters=theta,
        mass_matrix=mass_matrix_from_parameters(theta),
        stiffness=_sym(kv) * w0**2,
        damping=_sym(cv) * w0,
        residual=float(np.linalg.norm(r2) / np.linalg.norm(x_flat)),
        refined=refined,
        covariance=covariance,
        misfit_rows=rows,
    )


def _equation_error(u: Array, xs: CArray, tft: Array, basis: Array, damping: bool) -> tuple[Array, Array, Array]:
    """The equation-error fit (the start of the output-error one): ``theta``, ``K`` and ``C`` per ``w0``."""
    n, _, q = xs.shape
    scale = 1.0 / (u**2 * np.linalg.norm(xs.reshape(n, -1), axis=1))
    # columns: each unknown's contribution to every line's 6 x q equation, scaled per line
    cols_m = [-(u**2)[:, None, None] * (mass_matrix_from_parameters(e) @ xs) for e in np.eye(10)]
    cols_k = [_sym(e) @ xs for e in np.eye(21)]
    cols_c = [1j * u[:, None, None] * c for c in cols_k] if damping else []
    cols_g = []
    for jb in range(basis.shape[1]):
        for i in range(6 * q):
            g = np.zeros((n, 6 * q), dtype=complex)
            g[:, i] = u**2 * basis[:, jb]
            cols_g.append(g.reshape(n, 6, q))

    def stack(cols: list[CArray]) -> Array:
        if not cols:
            return np.zeros((2 * n * 6 * q, 0))
        a = np.stack([(c * scale[:, None, None]).reshape(-1) for c in cols], axis=1)
        return np.concatenate([a.real, a.imag])

    a_m = stack(cols_m)
    a_o = stack(cols_k + cols_c + cols_g)
    rhs = (-(u**2)[:, None, None] * np.broadcast_to(tft, (n, 6, q)) * scale[:, None, None]).reshape(-1)
    b = np.concatenate([rhs, np.zeros_like(rhs)])
    a_p, b_p, uo, no = _project_out(a_o, a_m, b)
    nm = np.linalg.norm(a_m, axis=0)
    sol, _, rank_m, sv = np.linalg.lstsq(a_p / nm, b_p, rcond=None)
    if rank_m < 10 or sv[-1] < 1e-6 * sv[0]:
        raise IdentificationError(
            f"the {q} reference(s) over these lines do not determine the mass, CG and inertia with the mounts "
            "fitted (at least 2 references at different points and in different directions, lines off the supports)"
        )
    theta = sol / nm
    rest = np.zeros(0)
    if a_o.shape[1]:  # the nuisance unknowns, minimum norm within the numerical rank
        rest = (uo[2].T @ ((uo[0].T @ (b - a_m @ theta)) / uo[1])) / no
    kv = rest[:21]
    cv = rest[21:42] if damping else np.zeros(21)
    return theta, kv, cv


def _project_out(a_o: Array, a_m: Array, b: Array) -> tuple[Array, Array, tuple[Array, Array, Array], Array]:
    """Project the nuisance columns `a_o` (scaled to unit norm) out of `a_m` and `b`.

    Their numerical rank is the one rank tolerance (:func:`rigidid.core.linalg.numerical_rank`):
    the directions of ``K`` and ``C`` the references do not see are dropped, harmless to ``M``.
    Returns the projected ``a_m``, ``b``, the kept SVD ``(U, s, V^T)`` and the column norms.
    """
    no = np.linalg.norm(a_o, axis=0)
    no[no == 0.0] = 1.0
    if not a_o.shape[1]:
        return a_m, b, (np.zeros((b.size, 0)), np.zeros(0), np.zeros((0, 0))), no
    uo, so, vt = np.linalg.svd(a_o / no, full_matrices=False)
    k = int(numerical_rank(so, a_o.shape[0]))
    uo, so, vt = uo[:, :k], so[:k], vt[:k]
    return a_m - uo @ (uo.T @ a_m), b - uo @ (uo.T @ b), (uo, so, vt), no


class _Problem:
    """The output-error misfit of the rigid-body model and its Jacobian (the upper residual projected out).

    The misfit of line ``l``, reference ``j``: ``w_lj R (X_lj - X_m,lj)``, ``R^T R = T^T T`` (at the
    sensors), ``w_lj`` the inverse of the data's norm there; real and imaginary parts stacked. The
    upper residual's real coefficients are projected out per reference (variable projection).
    """

    def __init__(
        self, u: Array, xs: CArray, tft: Array, basis: Array, damping: bool, chol: Array, weights: Array
    ) -> None:
        self.u, self.xs, self.tft, self.damping, self.chol, self.weights = u, xs, tft, damping, chol, weights
        self.basis = basis
        n, q = u.size, tft.shape[1]
        self.n_projected = basis.shape[1] * 6 * q
        # per reference: an orthonormal basis of the weighted residual functions (real parts only)
        self.q_basis = [np.linalg.qr(basis * weights[:, j, None])[0] for j in range(q)] if basis.shape[1] else []
        self.n_params = 52 if damping else 31
        self.n_residuals = 2 * n * 6 * q
        # dA/dp = (its matrix) x (its factor per line): -u^2 M_e, K_e, i u C_e
        self.mats = np.stack([mass_matrix_from_parameters(e) for e in np.eye(10)] + [_sym(e) for e in np.eye(21)])
        self.which = np.r_[np.arange(31), np.arange(10, 31)] if damping else np.arange(31)
        damped = [np.broadcast_to(1j * u, (21, n))] if damping else []
        factors = [np.broadcast_to(-(u**2), (10, n)), np.ones((21, n)), *damped]
        self.factors: CArray = np.vstack(factors).astype(complex)

    def pack(self, theta: Array, kv: Array, cv: Array) -> Array:
        return np.concatenate([theta, kv, cv] if self.damping else [theta, kv])

    def unpack(self, pv: Array) -> tuple[Array, Array, Array]:
        return pv[:10], pv[10:31], (pv[31:52] if self.damping else np.zeros(21))

    def _weighted(self, e: CArray) -> Array:
        """``(n, 6, q, ...)`` complex misfits -> weighted, projected real rows ``(2, 6, q, n, ...)``."""
        wts = self.weights[:, None, :, None] if e.ndim == 4 else self.weights[:, None, :]
        r = np.moveaxis(np.tensordot(self.chol, e, axes=(1, 1)), 0, 1) * wts
        out = np.stack([r.real, r.imag])  # (2, n, 6, q, ...)
        for j, qb in enumerate(self.q_basis):
            part = out[0, :, :, j].reshape(qb.shape[0], -1)
            out[0, :, :, j] = (part - qb @ (qb.T @ part)).reshape(out[0, :, :, j].shape)
        result: Array = np.moveaxis(out, 1, 3)
        return result

    def residual(self, pv: Array) -> Array:
        theta, kv, cv = self.unpack(pv)
        return self._weighted(self.xs - _model(self.u, theta, kv, cv, self.tft)).reshape(-1)

    def jacobian(self, pv: Array) -> tuple[Array, Array]:
        """The residual and its Jacobian ``dr/dp`` (``d X_m = -A^-1 dA X_m``)."""
        theta, kv, cv = self.unpack(pv)
        n, q = self.u.size, self.tft.shape[1]
        a = _sym(kv)[None] - (self.u**2)[:, None, None] * mass_matrix_from_parameters(theta)[None]
        a = a + 1j * self.u[:, None, None] * _sym(cv)[None]
        xm = -(self.u**2)[:, None, None] * np.linalg.solve(a, np.broadcast_to(self.tft.astype(complex), (n, 6, q)))
        ainv = np.linalg.solve(a, np.broadcast_to(np.eye(6, dtype=complex), (n, 6, 6)))
        base = (self.mats.reshape(-1, 6) @ np.moveaxis(xm, 1, 0).reshape(6, -1)).reshape(-1, 6, n, q)
        dx = np.moveaxis(base, (2, 1, 3, 0), (0, 1, 2, 3))[..., self.which] * self.factors.T[:, None, None, :]
        cols: CArray = (ainv @ dx.reshape(n, 6, -1)).reshape(n, 6, q, -1)  # (n, 6, q, P)
        jm = self._weighted(cols).reshape(-1, self.which.size)
        return self._weighted(self.xs - xm).reshape(-1), jm

    def fitted_norm(self, theta: Array, kv: Array, cv: Array) -> Array:
        """The norm at the sensors of the fitted accelerance (model plus upper residual) per line and reference,
        ``|R X_fit|``, shape (n, q): the data less the unweighted misfit."""
        rows = self._weighted(self.xs - _model(self.u, theta, kv, cv, self.tft)) / self.weights.T[None, None]
        data = np.einsum("ij,njq->iqn", self.chol, self.xs)
        fit = np.stack([data.real, data.imag]) - rows
        result: Array = np.sqrt(np.sum(fit**2, axis=(0, 1))).T
        return result

    def residual_rows(self, theta: Array, kv: Array, cv: Array) -> Array:
        """The weighted misfit as rows along frequency, ``(2 6 q, n)`` (for the misfit in noise units)."""
        return self.residual(self.pack(theta, kv, cv)).reshape(-1, self.u.size)

    def covariance(self, theta: Array, kv: Array, cv: Array) -> Array:
        """Covariance of the ten inertial parameters: the sandwich ``B S^T S B`` clustered per line and reference.

        ``B = (J^T J)^+`` (scaled columns, numerical rank), ``S`` the scores ``J_c^T r_c`` of each line and
        reference (its twelve misfits: six coordinates at the sensors, real and imaginary parts, correlated
        through the sensors): right whatever the noise's level per value, where the weights (the data's norm
        per line and reference) only approximate it. Each cluster's misfit is first divided by the fit's
        leverage there, ``r_c -> (I - H_cc)^(-1/2) r_c`` (Bell and McCaffrey's CR2, :func:`_leverage_adjusted`).
        """
        r, jm = self.jacobian(self.pack(theta, kv, cv))
        n, q = self.u.size, self.tft.shape[1]
        cn = np.linalg.norm(jm, axis=0)
        cn[cn == 0.0] = 1.0
        u, s, vt = np.linalg.svd(jm / cn, full_matrices=False)
        k = int(numerical_rank(s, jm.shape[0]))
        bread = vt[:k].T / s[:k] ** 2 @ vt[:k]  # (J^T J)^+ of the scaled columns
        hb = np.stack([np.sum(qb**2, axis=1) for qb in self.q_basis]) if self.q_basis else np.zeros((q, n))
        adjusted = _leverage_adjusted(u[:, :k].reshape(12, q, n, k), hb, r.reshape(12, q, n))
        scores = np.einsum("cqnp,qnc->qnp", (jm / cn).reshape(12, q, n, -1), adjusted).reshape(q * n, -1)
        g = (bread @ (scores.T @ scores) @ bread)[:10, :10]
        cov: Array = g / cn[:10, None] / cn[None, :10]
        return cov


def _leverage_adjusted(u_k: Array, basis_leverage: Array, r: Array) -> Array:
    """Each line and reference's misfit ``r_c`` (12 values) times ``(I - H_cc)^(-1/2)`` (CR2).

    Parameters
    ----------
    u_k : ndarray, shape (12, q, n, k)
        The left singular vectors of the weighted Jacobian (its column space), per misfit row, reference
        and line; ``H = U U^T`` is the fit's hat matrix.
    basis_leverage : ndarray, shape (q, n)
        The upper residual's own leverage per reference and line (its functions, fitted per real row and
        projected out of the Jacobian: on the six real rows of the cluster, none on the imaginary).
    r : ndarray, shape (12, q, n)
        The misfit.

    Returns
    -------
    ndarray, shape (q, n, 12)

    Notes
    -----
    A least-squares misfit is the noise times ``I - H``: ``E[r_c r_c^T] = s^2 (I - H)_cc``, short of the
    noise by the cluster's leverage ``H_cc``, whose trace averages ``k / G`` over ``G`` clusters; a factor
    ``N / (N - k)`` over all ``N`` misfits (the correction before) restores it only where every cluster's
    scores see the average leverage. With 52 parameters over the 126 clusters of femtools' acceptance case
    (21 lines, 6 references; benchmarks/frf_coverage.py, near) the standard errors came out 6-18 % wider
    than before; on mounted bodies (about 630 clusters) 1-2 %. ``(I - H_cc)^(-1/2)`` makes the sandwich
    unbiased under equal noise (Bell and McCaffrey 2002; Pustejovsky and Tipton 2018) and, the misfits of
    eq. (1) of [1] being correlated within a cluster only through the sensors, keeps its robustness to
    unequal noise.
    """
    uc = np.moveaxis(u_k, 0, 2)  # (q, n, 12, k)
    h = uc @ np.swapaxes(uc, -1, -2)
    h[..., range(6), range(6)] += basis_leverage[..., None]
    lam, vec = np.linalg.eigh(h)
    shrink = 1.0 / np.sqrt(np.clip(1.0 - lam, 1e-3, None))
    rc = np.moveaxis(r, 0, 2)  # (q, n, 12)
    adjusted: Array = np.einsum("qnij,qnj->qni", vec, np.einsum("qnkj,qnk->qnj", vec, rc) * shrink)
    return adjusted


OUTPUT_ERROR_EVALUATIONS = 200
"""Budget of the output-error fit's Levenberg-Marquardt (5-15 evaluations on femtools' cases; on mounted bodies of
benchmarks/frf_coverage.py 60 stopped one fit short, its mass 1.3 % off, 3 of its standard errors)."""

_DECREMENT = 1e-4
"""Converged once the Gauss-Newton step is below a hundredth of a standard error (in decrement units)."""


def _output_error(problem: _Problem, theta: Array, kv: Array, cv: Array) -> tuple[Array, Array, Array, bool]:
    """The output-error fit by Levenberg-Marquardt, from a second start past a spurious mode.

    The first start is the equation-error fit. The output-error cost has local minima: on mounted bodies
    measured above their support modes (benchmarks/frf_coverage.py, mounted) one draw in six ended
    where the fitted ``K`` and ``C`` put a spurious mode in or above the band to fit the noise (a damping
    eigenvalue -400 to -800 times the true ones), its mass and inertia 3-11 of their standard errors off
    while the true basin had a lower cost. Where the fit converged to a minimum with such a mode
    (:func:`_spurious`; an unconverged fit is not a local minimum), it is run again from the same inertia
    with ``K = C = 0`` (the free body: the mass line); from there every one of those draws reached the
    true basin. The minimum without a spurious mode is kept whenever that second start reaches one, whatever
    the two costs: a mode above the band's lowest lines is outside the model (the supports' modes lie below
    the mass line's band), so its minimum is not a rival estimate but the noise fitted. Keeping the lower
    cost instead left mounted draw 483 of benchmarks/frf_coverage.py (with the upper residual) in the
    spurious basin, its cost lower than the true basin's by 1.6e-5 of itself, CG y and J_xx 7.8 and 8.2
    of their standard errors off with no warning (from the true basin: 0.14 and 0.35). Where both starts end
    with a spurious mode, the lower cost is kept. Returns ``theta``, ``K`` and ``C`` (per ``w0``) and whether
    it moved from the equation-error start (kept where the model cannot be evaluated or no step lowers the
    misfit).
    """
    p0 = problem.pack(theta, kv, cv)
    c0 = _cost(problem, p0)
    if not np.isfinite(c0):
        return theta, kv, cv, False
    x, c, converged = _minimise(problem, p0)
    if converged and _spurious(problem.u, *problem.unpack(x)[:2]):
        x2, c2, _ = _minimise(problem, problem.pack(theta, np.zeros_like(kv), np.zeros_like(cv)))
        if np.isfinite(c2) and (c2 < c or not _spurious(problem.u, *problem.unpack(x2)[:2])):
            x, c = x2, c2
    if not c < c0:
        return theta, kv, cv, False
    th, kk, cc = problem.unpack(x)
    return th, kk, cc, True


MODEL_WEIGHT_PASSES = 1
"""Refits of the output-error fit with its weights from the fitted model (see :func:`_model_weighted`): one.
With each line twice at 1 -/+ 10 % (tests/core/test_rigidfrf.py) the first took the mass from 2 % to 2.6e-4
off (the fit's stop), a second did not move it."""


MODEL_WEIGHT_EVALUATIONS = 30
"""Cost evaluations the reweighted fit of :func:`_model_weighted` may take. It starts at the minimum of a cost
whose weights differ by the estimate's error (of order ``s / sqrt(lines)``), a few Gauss-Newton steps away;
where ``K`` and ``C`` are not identified (free-free bodies, the exact fit forced) neither fit converges, and the
full :data:`OUTPUT_ERROR_EVALUATIONS` again doubled the fit's cost (3.6 s on 3,200 lines) to move along the
directions the data do not determine."""


def _model_weighted(problem: _Problem, theta: Array, kv: Array, cv: Array) -> tuple[_Problem, Array, Array, Array]:
    """The output-error fit refitted with weights from the fitted model, not from the noisy data.

    Weights ``1 / |R X_data|`` (the start: the noise of an FRF grows with its level) correlate with the
    noise they weight: a line whose noise raised ``|X|`` weighs less than one whose noise lowered it, so the
    fit leans to the lower values, a fitted accelerance too low and a mass too high. To first order the
    estimating equation ``J^T W (X - X_m(p)) = 0`` has mean ``E[J^T W e] = J^T E[(dW/dX) e e^T]``, of the
    order of the noise's variance over each line's level: a bias of order ``s^2 / |X|^2`` per line that the
    lines add up (it does not average out), while the standard error falls as ``1 / sqrt(lines)``: its ratio to
    the standard error grows with the noise and the lines. Measured on 40 mounted bodies of
    benchmarks/frf_coverage.py (noise 0.5 % relative plus a 0.5 % floor), paired on the same draws, the mean
    z of the mass moved by -0.054 (+-0.004) and of ``J_zz`` by -0.066 (+-0.003); on femtools' case 15
    (near, 126 clusters) by -0.007. With ``W`` from the fitted model ``|R X_fit|`` (independent
    of the noise to first order, :meth:`_Problem.fitted_norm`) the estimating equation has mean zero at
    the truth; the fit is repeated :data:`MODEL_WEIGHT_PASSES` times from where it stopped (the weights then
    move with the estimate's error, of order ``s / sqrt(lines)``, smooth over the lines and not the noise of
    any one line; a second pass moves them by its square). A pass
    that cannot lower its reweighted cost keeps its start.
    """
    for _ in range(MODEL_WEIGHT_PASSES):
        norm = problem.fitted_norm(theta, kv, cv)
        weights = 1.0 / np.maximum(norm, np.finfo(float).tiny)
        nxt = _Problem(problem.u, problem.xs, problem.tft, problem.basis, problem.damping, problem.chol, weights)
        p0 = nxt.pack(theta, kv, cv)
        if not np.isfinite(_cost(nxt, p0)):
            break
        x, c, _ = _minimise(nxt, p0, MODEL_WEIGHT_EVALUATIONS)
        problem = nxt
        if c < _cost(nxt, p0):
            theta, kv, cv = nxt.unpack(x)
    return problem, theta, kv, cv


SPURIOUS_MODE = 1.1
"""A fitted natural frequency above this many times the lowest line's is a spurious mode (see :func:`_spurious`)."""


def _spurious(u: Array, theta: Array, kv: Array) -> bool:
    """Whether the fitted body on its mounts has a mode above the band's lowest lines.

    The undamped natural frequencies (eigenvalues of ``M^-1 K``, per ``w0``) of a body on mounts lie below the
    band of its mass line (the supports may reach its lowest lines: femtools' case 15 has its highest at
    1.01 times the lowest line); one above :data:`SPURIOUS_MODE` times the lowest line is a resonance the FRFs
    do not show (the spurious minima seen had them at 1.5-6.4 times).
    """
    lam = np.linalg.eigvals(np.linalg.solve(mass_matrix_from_parameters(theta), _sym(kv))).real
    return bool(np.any(lam > (SPURIOUS_MODE * u.min()) ** 2))


def _cost(problem: _Problem, pv: Array) -> float:
    """``|r|^2`` at `pv` (``inf`` where the model cannot be evaluated)."""
    try:
        r = problem.residual(pv)
    except np.linalg.LinAlgError:
        return np.inf
    c = float(r @ r)
    return c if np.isfinite(c) else np.inf


def _minimise(problem: _Problem, p0: Array, evaluations: int = OUTPUT_ERROR_EVALUATIONS) -> tuple[Array, float, bool]:
    """The output-error cost minimised from `p0` (:func:`rigidid.core.optimize.levenberg_marquardt`, at most
    `evaluations` of the cost): where, the cost there and whether a convergence test fired."""
    from rigidid.core.optimize import levenberg_marquardt

    def normal(x: Array, index: Any) -> tuple[Array, Array, Array]:
        r, jm = problem.jacobian(x[0])
        return np.array([r @ r]), (jm.T @ r)[None], (jm.T @ jm)[None]

    with np.errstate(all="ignore"):
        best = levenberg_marquardt(
            normal, lambda x, index: np.array([_cost(problem, x[0])]), p0[None],
            max_evaluations=evaluations, residuals=problem.n_residuals,
            decrement=_DECREMENT,
        )  # fmt: skip
    c = float(best.cost[0])
    return best.x[0], (c if np.isfinite(c) else np.inf), bool(best.converged[0])
