"""Eigensystem Realization Algorithm (ERA) on free decays, in Gram form.

The block Hankel matrix ``H0`` of the decays (``s`` block rows, one column per
sample, the records side by side) factors as ``O X``: the observability matrix
of the system times its states. ``H1``, the same matrix one sample later, is
``O A X``. ERA takes ``O`` from the leading singular vectors of ``H0`` and
``A`` from the shift between ``H0`` and ``H1``. Here only the Gram matrices
``H0 H0^T`` and ``H1 H0^T`` are formed (from lagged products, see
:func:`rigidid.core.timedomain.gram.lagged_gram`), so memory does not grow with
record length: with ``H0 H0^T = U S U^T``, the realization in the basis ``U_n``
of the ``n`` leading vectors is

    A_n = U_n^T (H1 H0^T) U_n S_n^-1,    C_n = first block row of U_n,

the same system as Juang and Pappa's balanced realization up to a similarity
``S^(1/2)``. Poles are ``log(eig(A_n)) / dt`` and shapes ``C_n`` times the
eigenvectors. One change to the textbook algorithm: the white-noise floor is
estimated from the trailing eigenvalues of ``H0 H0^T`` and removed from both
Gram matrices before ``A_n`` is formed (see :func:`era_basis`); left in, it
biases damping ratios upwards, by tens of per cent at 5 % noise.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
.. [2] J.-N. Juang, R. S. Pappa, "An eigensystem realization algorithm for
   modal parameter identification and model reduction", Journal of Guidance,
   Control, and Dynamics 8 (1985) 620-627.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["EraBasis", "era_basis", "era_modes"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


@dataclass(frozen=True)
class EraBasis:
    """The SVD of ``H0 H0^T`` and the shifted Gram, ready for any model order.

    Attributes
    ----------
    vectors : ndarray, shape (s r, k)
        ``U``, columns by decreasing singular value (the leading ``k``: all
        ``s r``, or the `max_order` of :func:`era_basis`).
    values : ndarray, shape (k,)
        ``S``: eigenvalues of ``H0 H0^T`` (squared singular values of ``H0``),
        decreasing, less the noise floor when corrected (see :func:`era_basis`).
    shifted : ndarray, shape (k, k)
        ``U^T (H1 H0^T) U`` (less the noise floor's lag-0 terms when corrected).
    channels : int
        ``r``.
    noise_floor : float
        The white-noise power per Hankel row removed (0 without correction).
    """

    vectors: Array
    values: Array
    shifted: Array
    channels: int
    noise_floor: float


def era_basis(gram: Array, channels: int, *, noise_correction: bool = True, max_order: int | None = None) -> EraBasis:
    """Decompose the Gram matrices of ERA once, for a sweep over model orders.

    Parameters
    ----------
    gram : ndarray, shape ((s + 1) r, (s + 1) r)
        :func:`~rigidid.core.timedomain.gram.lagged_gram` with ``L = s``:
        ``H0 H0^T`` is its leading ``s r`` square and ``H1 H0^T`` the block
        below it.
    channels : int
        ``r``.
    noise_correction : bool
        Remove the white-noise floor (see Notes).
    max_order : int, optional
        The largest model order :func:`era_modes` will be asked for: only
        that many leading directions are kept (default: all ``s r``).

    Returns
    -------
    EraBasis

    Notes
    -----
    White measurement noise of power ``sigma^2`` per channel adds
    ``sigma^2 N I`` to ``H0 H0^T`` and ``sigma^2 N`` identity blocks on the
    block superdiagonal of ``H1 H0^T`` (the products at lag 0). Left in, the
    first inflates ``S`` and shrinks the realized eigenvalues, so damping is
    overestimated (by about 30 % of the damping ratio at 5 % noise in our
    tests). With the correction, ``sigma^2 N`` is estimated as the median of
    the smaller half of the eigenvalues of ``H0 H0^T`` (the noise subspace
    when ``s r`` is at least twice the model order of the physical modes) and
    removed from both, the corrected ``S`` kept above 5 % of its uncorrected
    value. Coloured noise (for example after a narrow band-pass filter) is
    only partly corrected.
    """
    r = channels
    size = gram.shape[0] - r
    h00 = gram[:size, :size]
    h10 = gram[r:, :size].copy()
    values, vectors = np.linalg.eigh(0.5 * (h00 + h00.T))
    values, vectors = np.maximum(values[::-1], 0.0), vectors[:, ::-1]
    floor = 0.0
    if noise_correction and size >= 2 * r:
        floor = float(np.median(values[size // 2 :]))
        idx = np.arange(size - r)
        h10[idx, idx + r] -= floor
        values = np.maximum(values - floor, 0.05 * values)
    if max_order is not None:
        vectors, values = vectors[:, :max_order], values[:max_order]
    return EraBasis(vectors, values, vectors.T @ (h10 @ vectors), r, floor)


def era_modes(basis: EraBasis, order: int, dt: float) -> tuple[CArray, CArray]:
    """Poles and shapes of the ERA realization with `order` states.

    Parameters
    ----------
    basis : EraBasis
        From :func:`era_basis`.
    order : int
        Number of states ``n`` (at most the ``k`` directions of `basis`;
        even for ``n / 2`` modes).
    dt : float
        Sample interval (s).

    Returns
    -------
    poles : ndarray of complex, shape (k,)
        ``log(z) / dt`` (rad/s) for each eigenvalue ``z`` of ``A_n`` in the
        upper half plane.
    shapes : ndarray of complex, shape (r, k)
        ``C_n`` times the eigenvectors.
    """
    if order > basis.values.size:
        raise ValueError(f"order {order} is above the {basis.values.size} directions of the basis")
    s = basis.values[:order]
    tiny = s[0] * 1e-15 if s.size else 0.0
    a = basis.shifted[:order, :order] / np.maximum(s, tiny)[None, :]
    z, vec = np.linalg.eig(a)
    keep = z.imag > 0.0
    z, vec = z[keep], vec[:, keep]
    shapes = basis.vectors[: basis.channels, :order] @ vec
    poles: CArray = np.log(z) / dt
    return poles, shapes.astype(complex)
