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


def _correlate_rows(block: Array, rho: Array) -> Array:
    """``P X`` along axis 0 with ``P`` the symmetric Toeplitz matrix of `rho`, truncated at the ends.

    One pass of ``scipy.ndimage.correlate1d`` with zeros beyond the ends (a fifth of the time
    of a sum of shifted copies, lag by lag, on the refit's Jacobian).
    """
    if rho.size == 1:
        return block * float(rho[0])
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
    """
    j = np.asarray(jacobian, dtype=float)
    r = np.asarray(residual, dtype=float)
    n_rows, n_par = j.shape
    if r.shape != (n_rows,) or n_rows != channels * int(sum(lengths)):
        raise ValueError("jacobian and residual rows must be channels * sum(lengths)")
    info = j.T @ j
    binv, rank = pseudo_inverse(info, symmetric=True)
    dof = max(n_rows - rank - n_linear, 1)
    s2 = float(r @ r) / dof
    rho = noise_correlation(factor)
    meat = np.zeros((n_par, n_par))
    first = 0
    for n in lengths:
        rows = slice(first, first + int(n) * channels)
        first += int(n) * channels
        blk = j[rows].reshape(int(n), channels, n_par)
        res = r[rows].reshape(int(n), channels)
        w = np.sqrt(np.mean(res**2, axis=0) * (n_rows / dof))[None, :, None]
        scaled = (blk * w).reshape(-1, n_par)
        meat += scaled.T @ (_correlate_rows(blk, rho) * w).reshape(-1, n_par)
    meat = 0.5 * (meat + meat.T)
    step = -binv @ (j.T @ r)
    cov = binv @ meat @ binv + np.outer(step, step)
    decrement = float(step @ info @ step) / s2 if s2 > 0 else 0.0
    return ParameterCovariance(matrix=cov, bound=s2 * binv, step=step, decrement=decrement)
