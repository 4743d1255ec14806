"""Multivariate autoregressive (AR) models of free decays, the paper's DDS step.

The paper [1] obtains the modes with Data Dependent Systems, ARMA models of
increasing order fitted to the measured decays, the order raised until an
F-test says the residual sum of squares no longer improves. Here the model is
a vector AR fitted by least squares over all records at once,

    x[t] = A_1 x[t-1] + ... + A_p x[t-p] + e[t],

with the normal equations taken from the Gram matrix of the lagged records
(:func:`rigidid.core.timedomain.gram.lagged_gram`), so the whole sweep of
orders costs one pass over the data. A free decay of ``2 n`` states seen by
``r`` channels is an exact AR of order ``ceil(2 n / r)``; with measurement
noise the process is ARMA, and a higher ("over-parameterised") AR order
absorbs the noise in extra poles that the stabilisation diagram tells apart
from the physical ones.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
.. [2] S. M. Pandit, S.-M. Wu, "Time Series and System Analysis with
   Applications", Wiley, 1983 (Data Dependent Systems, the F-test on the
   residual sum of squares).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["ArFit", "ar_fits", "ar_modes", "f_test_order"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


@dataclass(frozen=True)
class ArFit:
    """One AR model fitted from a lagged Gram matrix.

    Attributes
    ----------
    order : int
        ``p``, the number of lags.
    coefficients : ndarray, shape (r, p r)
        ``[A_1, A_2, ..., A_p]``.
    rss : float
        Residual sum of squares over all channels and equations.
    """

    order: int
    coefficients: Array
    rss: float


def _block_index(blocks: list[int], r: int) -> NDArray[np.intp]:
    return (np.asarray(blocks)[:, None] * r + np.arange(r)[None, :]).ravel()


def ar_fits(gram: Array, channels: int, orders: list[int]) -> list[ArFit]:
    """Least-squares AR coefficients of several orders from one lagged Gram matrix.

    Parameters
    ----------
    gram : ndarray, shape ((L + 1) r, (L + 1) r)
        :func:`~rigidid.core.timedomain.gram.lagged_gram` with ``L >= max(orders)``:
        block ``L`` is the predicted sample, blocks ``L - 1 .. L - p`` the
        regressors of order ``p``, so that all orders are fitted to the same
        equations (as the F-test needs).
    channels : int
        ``r``.
    orders : list of int
        Orders ``p >= 1`` wanted.

    Returns
    -------
    list of ArFit
        In the order of `orders`.

    Notes
    -----
    The Gram matrix is ordered ``[x[t-1], x[t-2], ..., x[t-L], x[t]]`` and
    factored once, ``G = R^T R`` (Cholesky, after scaling to unit diagonal
    and adding ``1e-12`` to it, so an over-parameterised model of noise-free
    data does not fail). The regressors of every order are then a leading
    block of ``R``: the coefficients of order ``p`` are a triangular solve
    with ``R[:pr, :pr]`` and its residual sum of squares is the squared norm
    of ``R[pr:, target]``. This is the normal-equation solution: it loses
    accuracy when the lagged data are nearly collinear, which decimation to a
    few samples per period of the highest mode avoids.
    """
    from scipy.linalg import cholesky, solve_triangular

    r = channels
    last = gram.shape[0] // r - 1
    order_index = _block_index([*range(last - 1, -1, -1), last], r)
    g = gram[np.ix_(order_index, order_index)]
    scale = np.sqrt(np.maximum(np.diag(g), 1e-300))
    g = g / np.outer(scale, scale)
    g[np.diag_indices_from(g)] += 1e-12
    upper = cholesky(g, lower=False, check_finite=False)
    target = slice(last * r, (last + 1) * r)
    out: list[ArFit] = []
    for p in orders:
        k = p * r
        sol = solve_triangular(upper[:k, :k], upper[:k, target], lower=False, check_finite=False)
        theta = (sol * scale[target][None, :] / scale[:k, None]).T
        tail = upper[k:, target] * scale[target][None, :]
        out.append(ArFit(p, theta, float(np.sum(tail * tail))))
    return out


def ar_modes(fit: ArFit, dt: float) -> tuple[CArray, CArray]:
    """Poles and shapes of an AR model from its companion matrix.

    Parameters
    ----------
    fit : ArFit
        Coefficients ``[A_1 .. A_p]``, shape (r, p r).
    dt : float
        Sample interval (s).

    Returns
    -------
    poles : ndarray of complex, shape (k,)
        ``log(z) / dt`` (rad/s) for each eigenvalue ``z`` of the companion
        matrix in the upper half plane (one of each conjugate pair).
    shapes : ndarray of complex, shape (r, k)
        First block of each eigenvector (``z^(p-1) phi``, a multiple of the
        shape).
    """
    theta = fit.coefficients
    r = theta.shape[0]
    size = theta.shape[1]
    companion = np.zeros((size, size))
    companion[:r] = theta
    if size > r:
        companion[r:, :-r] = np.eye(size - r)
    z, vec = np.linalg.eig(companion)
    keep = z.imag > 0.0
    z, vec = z[keep], vec[:r, keep]
    poles: CArray = np.log(z) / dt
    return poles, vec.astype(complex)


def f_test_order(rss: list[float], orders: list[int], equations: int, channels: int, *, alpha: float = 0.05) -> int:
    """The AR order after which one more lag no longer improves the fit significantly.

    Parameters
    ----------
    rss : list of float
        Residual sum of squares of consecutive orders, same equations.
    orders : list of int
        The orders, ascending.
    equations : int
        Number of equations per channel (Hankel columns).
    channels : int
        ``r``.
    alpha : float
        Significance level.

    Returns
    -------
    int
        The first order ``p`` whose successor's improvement has an F statistic
        ``((RSS_p - RSS_q) / ((q - p) r^2)) / (RSS_q / (N r - q r^2))`` below
        the ``1 - alpha`` quantile of ``F((q - p) r^2, N r - q r^2)``; the last
        order if every step is significant.

    Notes
    -----
    The DDS strategy of [2] applied to the whole vector model. With long
    records nearly every step is significant (noise is not white after an AR
    fit of finite order), and the sweep runs up to its maximum order.
    """
    from scipy.special import fdtri

    r2 = channels * channels
    for idx in range(len(orders) - 1):
        p, q = orders[idx], orders[idx + 1]
        dof1 = (q - p) * r2
        dof2 = equations * channels - q * r2
        if dof2 <= 0 or rss[idx + 1] <= 0.0:
            return p
        stat = ((rss[idx] - rss[idx + 1]) / dof1) / (rss[idx + 1] / dof2)
        if stat < float(fdtri(dof1, dof2, 1.0 - alpha)):
            return p
    return orders[-1]
