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

from rigidid.core.geometry import skew
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
        Whether the output-error refinement improved the equation-error estimate.
    """

    parameters: Array
    mass_matrix: Array
    stiffness: Array
    damping: Array
    residual: float
    refined: bool


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
    m = mass_matrix_from_parameters(theta)
    a = _sym(kv)[None] - (u**2)[:, None, None] * m[None] + 1j * u[:, None, None] * _sym(cv)[None]
    x: CArray = np.linalg.solve(a, np.broadcast_to(tft.astype(complex), (u.size, *tft.shape)))
    return -(u**2)[:, None, None] * x


def rigid_frf_fit(
    omega: ArrayLike,
    coordinates: ArrayLike,
    forces: ArrayLike,
    *,
    damping: bool = True,
    residual_basis: ArrayLike | None = None,
    refine: bool = False,
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
        the lines), each with its own free ``6 x q`` coefficient.
    refine : bool
        Refine the equation-error estimate by output error (trust-region least
        squares on ``M``, ``K``, ``C`` with the residual coefficients projected out,
        misfit relative per line); kept only if it lowers that misfit. Slow on
        thousands of lines (seconds to a minute).

    Returns
    -------
    RigidFrfFit

    Raises
    ------
    InputError
        If the shapes disagree.
    IdentificationError
        If the lines do not determine the ten inertial parameters.

    Notes
    -----
    Equation error: each line's equation is divided by ``w^2 ||X(w)||`` (so that
    lines near a resonance, where ``X`` and its noise are large, do not dominate),
    real and imaginary parts stacked, columns scaled to unit norm. The inertial
    parameters are solved first with ``K``, ``C`` and the residual coefficients
    projected out, so that what the data leave free in ``K`` and ``C`` (with
    ``q < 6`` references only ``K X`` is seen) does not leak into ``M``. Exact for
    noise-free rigid-body FRFs whatever the band (eq. (1) of [1] holds line by
    line); the elastic residual is exact after the output-error refinement.
    """
    w = np.asarray(omega, dtype=float).reshape(-1)
    x = np.asarray(coordinates, dtype=complex)
    tft = np.asarray(forces, dtype=float)
    n = w.size
    if x.ndim != 3 or x.shape[0] != 6 or x.shape[2] != n or tft.shape != x.shape[:2]:
        raise InputError(f"coordinates must have shape (6, q, {n}) and forces (6, q), got {x.shape} and {tft.shape}")
    q = x.shape[1]
    basis = np.zeros((n, 0)) if residual_basis is None else np.asarray(residual_basis, dtype=float).reshape(n, -1)
    w0 = float(np.sqrt(w.min() * w.max()))
    u = w / w0  # K and C are fitted per w0^2 and w0
    xs = np.moveaxis(x, 2, 0)  # (n, 6, q)
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
    # project the nuisance unknowns out (their null directions are harmless)
    if a_o.shape[1]:
        no = np.linalg.norm(a_o, axis=0)
        no[no == 0.0] = 1.0
        uo, so, _ = np.linalg.svd(a_o / no, full_matrices=False)
        uo = uo[:, so > so[0] * 1e-10]
        a_p = a_m - uo @ (uo.T @ a_m)
        b_p = b - uo @ (uo.T @ b)
    else:
        a_p, b_p = a_m, b
    nm = np.linalg.norm(a_m, axis=0)
    sol, _, rank_m, sv = np.linalg.lstsq(a_p / nm, b_p, rcond=None)
    if rank_m < 10 or sv[-1] < 1e-6 * sv[0]:
        raise IdentificationError(
            f"the {q} reference(s) over these lines do not determine the mass, CG and inertia with the mounts "
            "fitted (at least 2 references at different points and in different directions, lines off the supports)"
        )
    theta = sol / nm
    if not theta[0] > 0.0:
        raise IdentificationError(f"the rigid-body fit gives a mass of {theta[0]:.4g}, not positive")
    rest = np.linalg.lstsq(a_o, b - a_m @ theta, rcond=1e-10)[0] if a_o.shape[1] else np.zeros(0)
    kv = rest[:21]
    cv = rest[21:42] if damping else np.zeros(21)

    x_flat = xs.reshape(n, -1)
    refined = False
    if refine:
        theta, kv, cv, refined = _refine_output_error(u, x_flat, basis, tft, (theta, kv, cv), damping)
    r_out = x_flat - _model(u, theta, kv, cv, tft).reshape(n, -1)
    r2 = np.concatenate([r_out.real, r_out.imag])
    if basis.shape[1]:
        g_un = np.concatenate([basis, np.zeros_like(basis)])
        r2 = r2 - g_un @ np.linalg.lstsq(g_un, r2, rcond=None)[0]
    misfit = float(np.linalg.norm(r2) / np.linalg.norm(x_flat))
    return RigidFrfFit(
        parameters=theta,
        mass_matrix=mass_matrix_from_parameters(theta),
        stiffness=_sym(kv) * w0**2,
        damping=_sym(cv) * w0,
        residual=misfit,
        refined=refined,
    )


def _refine_output_error(
    u: Array,
    x_flat: CArray,
    basis: Array,
    tft: Array,
    start: tuple[Array, Array, Array],
    damping: bool,
) -> tuple[Array, Array, Array, bool]:
    """The equation-error fit refined by output error (relative per line, the upper residual projected out).

    Returns the parameters (``theta``, ``K`` and ``C`` per ``w0^2`` and ``w0``, packed) and whether the
    refinement lowered the misfit (otherwise the start is returned).
    """
    n, q = x_flat.shape[0], tft.shape[1]
    theta, kv, cv = start
    wline = 1.0 / np.linalg.norm(x_flat, axis=1)  # output error: relative per line
    gw = basis * wline[:, None]
    g2 = np.concatenate([gw, np.zeros_like(gw)])  # the residual coefficients are real
    q2 = np.linalg.svd(g2, full_matrices=False)[0] if g2.shape[1] else np.zeros((2 * n, 0))

    def project(r: CArray) -> Array:
        """Stack real and imaginary parts (2n x ...) and project the upper residual out."""
        r2 = np.concatenate([r.real, r.imag])
        if not q2.shape[1]:
            return r2
        flat = r2.reshape(2 * n, -1)
        out: Array = (flat - q2 @ (q2.T @ flat)).reshape(r2.shape)
        return out

    sym_basis = [_sym(e) for e in np.eye(21)]

    def unpack(pv: Array) -> tuple[Array, Array, Array]:
        return pv[:10], pv[10:31], (pv[31:52] if damping else np.zeros(21))

    def fun(pv: Array) -> Array:
        th, kk, cc = unpack(pv)
        r = (x_flat - _model(u, th, kk, cc, tft).reshape(n, -1)) * wline[:, None]
        return project(r).reshape(-1)

    def jac(pv: Array) -> Array:
        th, kk, cc = unpack(pv)
        a = _sym(kk)[None] - (u**2)[:, None, None] * mass_matrix_from_parameters(th)[None]
        a = a + 1j * u[:, None, None] * _sym(cc)[None]
        xm = -(u**2)[:, None, None] * np.linalg.solve(a, np.broadcast_to(tft.astype(complex), (n, 6, q)))
        ainv = np.linalg.solve(a, np.broadcast_to(np.eye(6, dtype=complex), (n, 6, 6)))
        da: list[NDArray[Any]] = [-(u**2)[:, None, None] * mass_matrix_from_parameters(e)[None] for e in np.eye(10)]
        da += [np.broadcast_to(sb, (n, 6, 6)) for sb in sym_basis]
        if damping:
            da += [1j * u[:, None, None] * sb[None] for sb in sym_basis]
        cols = np.stack([(ainv @ (d @ xm)).reshape(n, -1) * wline[:, None] for d in da], axis=2)
        return project(cols).reshape(-1, len(da))

    def rms(res: Array) -> float:
        return float(np.sqrt(np.sum(res**2)) / np.sqrt(np.sum(np.abs(x_flat * wline[:, None]) ** 2)))

    p0 = np.concatenate([theta, kv, cv] if damping else [theta, kv])
    res0 = fun(p0)
    misfit = rms(res0)
    refined = False
    if np.all(np.isfinite(res0)) and misfit > 1e-12:
        from scipy.optimize import least_squares

        xs0 = np.maximum(np.abs(p0), 1e-6 * np.abs(theta).max())
        with np.errstate(all="ignore"):
            sol_ls = least_squares(fun, p0, jac=jac, x_scale=xs0, method="trf", max_nfev=30)
        if np.isfinite(sol_ls.cost) and sol_ls.x[0] > 0.0:
            new = rms(sol_ls.fun)
            if new < misfit:
                theta, kv, cv = unpack(sol_ls.x)
                misfit, refined = new, True
    return theta, kv, cv, refined
