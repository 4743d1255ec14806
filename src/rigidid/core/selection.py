"""How rigid-body-like a measured mode shape is, and which modes to use.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.linalg import solve_rows
from rigidid.errors import IdentificationError

__all__ = [
    "SUSPECT_RATIO",
    "SUSPECT_RESIDUAL",
    "elastic_suspect",
    "project_rigid",
    "project_rigid_batch",
    "rigid_fit_residuals",
    "select_rigid_modes",
    "separate_elastic",
]

#: A mode is suspected elastic when its rigid-fit residual is above this ...
SUSPECT_RESIDUAL = 0.05
#: ... and this many times the median of the other modes' residuals.
SUSPECT_RATIO = 20.0

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


def project_rigid(transformation: ArrayLike, shapes: ArrayLike) -> tuple[CArray, Array]:
    """Least-squares rigid-body coordinates of measured shapes, eq. (30) of [1] in spirit.

    Parameters
    ----------
    transformation : array_like, shape (p, 6)
        Sensor transformation ``T_mo`` of rank 6 (see
        :func:`rigidid.core.geometry.sensor_matrix`).
    shapes : array_like of complex, shape (p, n)
        Measured mode shapes, one column per mode.

    Returns
    -------
    coordinates : ndarray of complex, shape (6, n)
        ``T^+ psi``: the rigid motion that best explains each shape.
    residual : ndarray, shape (n,)
        ``|psi - T T^+ psi| / |psi|`` per mode: 0 for exact rigid-body motion,
        near 1 for a shape rigid motion cannot explain.

    Raises
    ------
    IdentificationError
        If `transformation` has rank below 6.

    Notes
    -----
    With ``p = 6`` every shape fits exactly and the residual carries no
    information; it needs ``p > 6``. Computed by :func:`project_rigid_batch`.

    Examples
    --------
    Six sensors reading a pure x translation:

    >>> from rigidid.core.geometry import sensor_matrix
    >>> pos = np.array([[1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1.0]])
    >>> dirs = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0.0]])
    >>> t = sensor_matrix(pos, dirs)
    >>> coords, residual = project_rigid(t, t @ np.array([[1.0], [0], [0], [0], [0], [0]]))
    >>> (coords.real.round(12) + 0.0).ravel().tolist(), residual.round(12).tolist()
    ([1.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0])
    """
    t = np.asarray(transformation, dtype=float)
    psi = np.asarray(shapes, dtype=complex)
    coords, residual, ok = project_rigid_batch(t[None], psi[None])
    if not ok[0]:
        raise IdentificationError("the sensor layout has rank below 6; rigid-body motion needs rank 6")
    return coords[0], residual[0]


def project_rigid_batch(transformation: Array, shapes: CArray) -> tuple[CArray, Array, NDArray[np.bool_]]:
    """:func:`project_rigid` for a stack of tests: QR of each ``T``, real and imaginary parts together.

    Parameters
    ----------
    transformation : ndarray, shape (B, p, 6)
    shapes : ndarray of complex, shape (B, p, n)

    Returns
    -------
    coordinates : ndarray of complex, shape (B, 6, n)
    residual : ndarray, shape (B, n)
    ok : ndarray of bool, shape (B,)
        False where ``T`` is singular (its coordinates are NaN).
    """
    n = shapes.shape[-1]
    rhs = np.concatenate([shapes.real, shapes.imag], axis=-1)
    if transformation.shape[1] == 6:
        sol, ok = solve_rows(transformation, rhs)
    else:
        q, r = np.linalg.qr(transformation)
        sol, ok = solve_rows(r, np.swapaxes(q, -1, -2) @ rhs)
    coords = sol[..., :n] + 1j * sol[..., n:]
    misfit = np.linalg.norm(shapes - transformation @ coords, axis=-2)
    norms = np.linalg.norm(shapes, axis=-2)
    residual = np.divide(misfit, norms, out=np.ones_like(misfit), where=norms > 0)
    return coords, residual, ok


def rigid_fit_residuals(transformation: ArrayLike, shapes: ArrayLike) -> Array:
    """Relative residual of each mode shape's least-squares fit by rigid-body motion.

    Parameters
    ----------
    transformation : array_like, shape (p, 6)
        Sensor transformation.
    shapes : array_like of complex, shape (p, n)
        Measured mode shapes.

    Returns
    -------
    ndarray, shape (n,)
        See :func:`project_rigid`.
    """
    return project_rigid(transformation, shapes)[1]


def select_rigid_modes(transformation: ArrayLike, shapes: ArrayLike, count: int = 6) -> NDArray[np.intp]:
    """Indices of the `count` modes whose shapes are closest to rigid-body motion.

    Parameters
    ----------
    transformation : array_like, shape (p, 6)
        Sensor transformation, ``p > 6``.
    shapes : array_like of complex, shape (p, n)
        Measured mode shapes, ``n >= count``.
    count : int
        How many modes to keep.

    Returns
    -------
    ndarray of int, shape (count,)
        Column indices into `shapes`, in ascending order.

    Raises
    ------
    IdentificationError
        With six sensors or fewer (every shape fits rigid motion exactly, so
        there is nothing to choose by) or fewer than `count` modes.
    """
    t = np.asarray(transformation, dtype=float)
    psi = np.asarray(shapes, dtype=complex)
    if t.shape[0] <= 6:
        raise IdentificationError(
            "choosing the rigid-body modes needs more than six sensors; name the six modes (`modes_used`)"
        )
    if psi.shape[1] < count:
        raise IdentificationError(f"need at least {count} modes, got {psi.shape[1]}")
    residual = rigid_fit_residuals(t, psi)
    return np.sort(np.argsort(residual, kind="stable")[:count])


def elastic_suspect(residuals: ArrayLike) -> int | None:
    """The one mode whose shape fits rigid-body motion far worse than the others', or None.

    Parameters
    ----------
    residuals : array_like, shape (n,)
        Rigid-fit residuals of the modes (:func:`rigid_fit_residuals`), ``n >= 2``;
        only meaningful with more than six sensors.

    Returns
    -------
    int or None
        Index of the worst mode when its residual exceeds :data:`SUSPECT_RESIDUAL`
        and :data:`SUSPECT_RATIO` times the median of the others' (an elastic mode
        taken for a rigid one, most likely); otherwise None.

    Notes
    -----
    Rigid-body modes measured with a few percent noise fit rigid motion to a
    residual of about the noise level; an elastic mode's shape is unrelated to
    rigid motion and fits to 0.1-1. The ratio test keeps a test whose every
    mode is noisy (all residuals alike) from being flagged.

    Examples
    --------
    >>> elastic_suspect([0.002, 0.003, 0.25, 0.002, 0.001, 0.004])
    2
    >>> elastic_suspect([0.06, 0.07, 0.08, 0.05, 0.06, 0.07]) is None
    True
    """
    r = np.asarray(residuals, dtype=float).ravel()
    if r.size < 2:
        return None
    k = int(np.argmax(r))
    others = float(np.median(np.delete(r, k)))
    if r[k] > SUSPECT_RESIDUAL and r[k] > SUSPECT_RATIO * others:
        return k
    return None


def separate_elastic(transformation: ArrayLike, shapes: ArrayLike) -> NDArray[np.intp] | None:
    """The six rigid-body modes among seven, when the seventh is clearly elastic; else None.

    Parameters
    ----------
    transformation : array_like, shape (p, 6)
        Sensor transformation, ``p > 6``.
    shapes : array_like of complex, shape (p, 7)
        Seven estimated mode shapes.

    Returns
    -------
    ndarray of int, shape (6,) or None
        Indices of the six modes that fit rigid-body motion best
        (:func:`select_rigid_modes`), when the one left out fits it worse than
        :data:`SUSPECT_RESIDUAL` and none of the six stands out
        (:func:`elastic_suspect`); None when the seven do not separate so.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.vstack([np.eye(6), np.ones((2, 6))])
    >>> rigid = t @ np.eye(6)
    >>> elastic = np.array([[0.0], [0.0], [0.0], [0.0], [0.0], [0.0], [1.0], [-1.0]])
    >>> separate_elastic(t, np.hstack([rigid[:, :2], elastic, rigid[:, 2:]]))
    array([0, 1, 3, 4, 5, 6])
    """
    t = np.asarray(transformation, dtype=float)
    residual = rigid_fit_residuals(t, shapes)
    keep = select_rigid_modes(t, shapes)
    left_out = np.setdiff1d(np.arange(residual.size), keep)
    if residual[left_out].min() <= SUSPECT_RESIDUAL or elastic_suspect(residual[keep]) is not None:
        return None
    return keep
