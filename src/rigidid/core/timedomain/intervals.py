"""Calibrated covariance of the output-error refinement on the records (issue 11, item 4).

The refinement (:func:`rigidid.core.timedomain.refine.refine_body`) is a
weighted least-squares fit whose weights are one noise level per channel. Its
textbook Cramér-Rao bound ``s^2 (J^T J)^-1`` holds only when those weights are
the true noise levels of every residual and the residuals are white. Neither
is guaranteed: the noise level of a channel can differ between impacts (gain
settings, the hammer, ambient noise; in the simulator it is relative to each
record's RMS) while the weights pool the impacts, and the anti-alias filter of
the decimation correlates neighbouring decimated samples. Then the estimate's
covariance is the *sandwich* ``B^-1 M B^-1`` with ``B = J^T J`` and ``M =
J^T Sigma J``, ``Sigma`` the covariance of the weighted residuals, which is
estimated here from the fit's own residual, per impact and channel, with the
filter's known correlation between samples.

A fit stopped by its evaluation budget before the minimum is a second source
of error the bound ignores: the remaining Gauss-Newton step ``B^-1 J^T r``
tells how far the estimate still is from the minimum; its outer product is
added to the covariance (a mean-square-error matrix), so such a fit gets wider
intervals instead of over-confident ones.

Why the sandwich is the refit's covariance, not only a bound (issue 23): with the
linear parameters projected out, the estimate's error is, to first order, one
Gauss-Newton step from the truth, ``-(J^T J)^-1 J^T e`` (``J^T P_perp = J^T``:
Kaufman's Jacobian is exact in the gradient), whose covariance is ``B^-1 J^T Sigma J
B^-1`` exactly; ``Sigma`` is ``v_ic P`` per impact and channel when the noise is
stationary within a decay and white before the decimation filter. Measured on the
chain benchmark's test (``benchmarks/refit_noise_calibration.py``): the refit's
error equals that step to 0.003-0.01 of its standard error (the estimate is linear
in the noise at 1 %), ``v_ic`` is unbiased (0.95-1.05 of the true level per impact
and channel), and over 394 noise draws the estimate's spread is 1.01-1.08 of the mean
reported std per figure (sampling error 3.6 %). With the channels' delays fitted the
delays' columns stay in ``J`` and the body's std is the joint covariance's marginal.

A residual above the pre-trigger's noise (a misfit, or noise coloured in the fit's band)
needs no further widening: ``v_ic`` is the residual's own level, ``R_ic`` times the
pre-trigger's, so the sandwich already is the Birge-scaled covariance, per impact and
channel (:func:`rigidid.api.records.refit_verdict`). On the chain benchmark's ``aa`` cell
(an unstated 8th-order anti-alias filter at 0.4 fs: its noise 1.25 times denser in the fit's
band than the white level the pre-trigger states, residual over pre-trigger 1.25-1.29 on every
impact and channel) the sandwich alone matches the Monte Carlo spread; scaled again by the
square root of the misfit ratio, the intervals were 1.13 times too wide
(``benchmarks/refit_width.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.linalg import pseudo_inverse
from rigidid.core.timedomain.preprocess import fir_taps

__all__ = ["VARIANCE_FROM", "ParameterCovariance", "noise_correlation", "parameter_covariance"]

Array = NDArray[np.float64]

VARIANCE_FROM = "sandwich"
"""How the record intervals' variance is estimated: the robust (sandwich) covariance of
:func:`parameter_covariance` (the fit's residual per impact and channel, the decimation
filter's correlation, plus the remaining Gauss-Newton step)."""

_CORRELATION_FLOOR = 1e-4  # lags whose normalised correlation is below this are dropped


@dataclass(frozen=True)
class ParameterCovariance:
    """Covariance of the fitted parameters, robust and textbook.

    Attributes
    ----------
    matrix : ndarray, shape (n, n)
        The calibrated covariance: sandwich plus the outer product of the
        remaining Gauss-Newton step (parameter units squared).
    bound : ndarray, shape (n, n)
        The textbook bound ``s^2 (J^T J)^+`` with ``s^2`` the residual's mean
        square over the degrees of freedom.
    step : ndarray, shape (n,)
        The remaining Gauss-Newton step ``-(J^T J)^+ J^T r`` (zero at the
        minimum).
    decrement : float
        ``step^T J^T J step / s^2``: the fall of ``2 cost / s^2`` the step
        promises; about the number of parameters' worth of noise or less at a
        converged fit, large when the fit stopped early.
    """

    matrix: Array
    bound: Array
    step: Array
    decrement: float


def noise_correlation(factor: int) -> Array:
    """Correlation between decimated samples of white noise, lag 0, 1, 2, ...

    Parameters
    ----------
    factor : int
        Decimation factor of :func:`rigidid.core.timedomain.preprocess.decimate`
        (``<= 1``: no decimation).

    Returns
    -------
    ndarray, shape (L + 1,)
        ``rho[m]``: correlation of two decimated samples ``m`` apart, ``rho[0] = 1``;
        lags up to the last whose magnitude reaches 1e-4 (``[1.0]`` without
        decimation).

    Notes
    -----
    White noise filtered by the taps ``h`` and kept every ``q``-th sample has
    autocovariance ``sigma^2 sum_k h_k h_{k + m q}`` at lag ``m``. The windowed
    sinc's is small (about 0.04 at lag 1, alternating) but spans the filter's
    length, 20 lags.

    Examples
    --------
    >>> rho = noise_correlation(4)
    >>> float(rho[0]), bool(abs(rho[1]) < 0.05)
    (1.0, True)
    """
    if factor <= 1:
        return np.ones(1)
    h = fir_taps(int(factor))
    full = np.correlate(h, h, mode="full")[h.size - 1 :]
    rho = full[:: int(factor)] / full[0]
    big = np.flatnonzero(np.abs(rho) >= _CORRELATION_FLOOR)
    result: Array = rho[: int(big[-1]) + 1]
    return result


_SHIFTED_COPIES = 4_000_000  # values below which _correlate_rows sums shifted copies (no scipy import)


def _correlate_rows(block: Array, rho: Array) -> Array:
    """``P X`` along axis 0 with ``P`` the symmetric Toeplitz matrix of `rho`, truncated at the ends.

    One pass of ``scipy.ndimage.correlate1d`` with zeros beyond the ends (a fifth of the time
    of a sum of shifted copies, lag by lag, on the refit's Jacobian per channel); below
    :data:`_SHIFTED_COPIES` values (the rigid combinations' Jacobian), the sum of shifted copies,
    which costs less than importing ``scipy.ndimage`` (about 0.15 s).
    """
    if rho.size == 1:
        return block * float(rho[0])
    if block.size <= _SHIFTED_COPIES:
        shifted: Array = block * float(rho[0])
        for lag in range(1, min(rho.size, block.shape[0])):
            shifted[lag:] += float(rho[lag]) * block[:-lag]
            shifted[:-lag] += float(rho[lag]) * block[lag:]
        return shifted
    from scipy.ndimage import correlate1d

    out: Array = correlate1d(block, np.concatenate([rho[:0:-1], rho]), axis=0, mode="constant", cval=0.0)
    return out


def parameter_covariance(
    jacobian: Array,
    residual: Array,
    lengths: Sequence[int],
    channels: int,
    factor: int,
    n_linear: int,
    *,
    combinations: Array | None = None,
) -> ParameterCovariance:
    """Robust (sandwich) covariance of a weighted least-squares fit to decimated records.

    Parameters
    ----------
    jacobian : ndarray, shape (N, n)
        Jacobian of the weighted residual at the estimate (the variable-projection
        one: linear parameters already projected out). Rows ordered impact by
        impact, within an impact sample by sample, within a sample channel by
        channel (``N = channels * sum(lengths)``).
    residual : ndarray, shape (N,)
        Weighted residual at the estimate, same order.
    lengths : sequence of int
        Decimated samples fitted per impact.
    channels : int
        Channels per sample.
    factor : int
        Decimation factor the samples were taken with (``<= 1``: none).
    n_linear : int
        Linear parameters solved inside the residual (amplitudes, offsets), for
        the degrees of freedom.
    combinations : ndarray, shape (channels, m), optional
        An orthonormal basis ``Q`` whose span holds every sample's Jacobian rows
        (the refit's rigid combinations of the weighted channels): `jacobian` then
        holds ``Q^T J_n`` per sample (``m * sum(lengths)`` rows) and `residual` is still
        per channel. The same covariance at ``m / channels`` of the cost (Notes).

    Returns
    -------
    ParameterCovariance

    Raises
    ------
    ValueError
        If the rows do not match `lengths` and `channels`.

    Notes
    -----
    ``B = J^T J``, ``B^+`` its pseudo-inverse (cut at the one rank tolerance,
    :func:`rigidid.core.linalg.pseudo_inverse`). The meat is ``M = sum_i sum_c v_ic J_ic^T P J_ic``
    over impacts ``i`` and channels ``c``, ``J_ic`` the rows of one impact and
    channel in time order, ``v_ic`` the mean square of their residual times
    ``N / (N - n - n_linear)``, ``P`` the Toeplitz matrix of
    :func:`noise_correlation`. The covariance is ``B^+ M B^+ + d d^T``, ``d``
    the remaining Gauss-Newton step. Assumes the noise independent between
    channels and stationary within an impact's decay (its level may differ
    between impacts and channels). Cost: about ``N n (n + 2 L)`` operations,
    ``L`` the correlation's lags (20).

    With `combinations` ``Q`` and ``J_n = Q A_n`` (``A_n`` the rows given):
    ``sum_c v_ic J_nc^T J_mc = A_n^T S_i A_m`` with ``S_i = Q^T diag(v_i) Q``
    (m x m); writing ``S_i = L_i L_i^T`` (its eigen-decomposition), the meat is
    the same sum over the m columns of ``L_i^T A_n``, ``J^T J = A^T A`` and
    ``J^T r = sum_n A_n^T Q^T r_n``: exact, no row of ``J`` formed.
    """
    j = np.asarray(jacobian, dtype=float)
    r = np.asarray(residual, dtype=float)
    n_rows, n_par = r.size, j.shape[1]
    width = channels if combinations is None else int(np.shape(combinations)[1])
    if r.shape != (n_rows,) or n_rows != channels * int(sum(lengths)) or j.shape[0] != width * int(sum(lengths)):
        raise ValueError("jacobian and residual rows must be channels * sum(lengths)")
    info = j.T @ j
    binv, rank = pseudo_inverse(info, symmetric=True)
    dof = max(n_rows - rank - n_linear, 1)
    s2 = float(r @ r) / dof
    rho = noise_correlation(factor)
    meat, gradient = np.zeros((n_par, n_par)), np.zeros(n_par)
    first = 0
    for n in lengths:
        blk = j[first * width : (first + int(n)) * width].reshape(int(n), width, n_par)
        res = r[first * channels : (first + int(n)) * channels].reshape(int(n), channels)
        first += int(n)
        v = np.mean(res**2, axis=0) * (n_rows / dof)
        if combinations is not None:
            q = np.asarray(combinations, dtype=float)
            e, u = np.linalg.eigh(q.T @ (v[:, None] * q))
            blk_w = np.matmul(np.sqrt(np.maximum(e, 0.0))[:, None] * u.T, blk)
            res = res @ q
        else:
            blk_w = blk * np.sqrt(v)[None, :, None]
        gradient += blk.reshape(-1, n_par).T @ res.reshape(-1)
        meat += blk_w.reshape(-1, n_par).T @ _correlate_rows(blk_w, rho).reshape(-1, n_par)
    meat = 0.5 * (meat + meat.T)
    step = -binv @ gradient
    cov = binv @ meat @ binv + np.outer(step, step)
    decrement = float(step @ info @ step) / s2 if s2 > 0 else 0.0
    return ParameterCovariance(matrix=cov, bound=s2 * binv, step=step, decrement=decrement)
