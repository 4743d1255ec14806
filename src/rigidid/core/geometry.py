"""Rigid-body kinematics: sensor transformation and change of reference point.

Coordinates of rigid-body motion are ordered ``(x, y, z, rx, ry, rz)``: the
translation of a reference point followed by the small rotation vector.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.linalg import numerical_rank
from rigidid.errors import InputError

__all__ = [
    "LayoutFrame",
    "frame_arrays",
    "layout_condition",
    "layout_frame",
    "local_sensor_matrix",
    "normalise_directions",
    "sensor_matrix",
    "sensor_outline",
    "skew",
    "transfer_matrix",
]

Array = NDArray[np.float64]


def skew(v: ArrayLike) -> Array:
    """Return the cross-product matrix ``S(v)`` with ``S(v) @ w == cross(v, w)``.

    Parameters
    ----------
    v : array_like, shape (3,)
        Any 3-vector.

    Returns
    -------
    ndarray, shape (3, 3)
        The skew-symmetric matrix of `v`. ``H_dg`` of eq. (13) of [1] is
        ``skew(g - d)``.
    """
    x, y, z = np.asarray(v, dtype=float)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def transfer_matrix(offset: ArrayLike) -> Array:
    """Motion of a point from the motion of a reference point, eqs. (11)-(14) of [1].

    Parameters
    ----------
    offset : array_like, shape (3,)
        Position of the point minus position of the reference point (length).

    Returns
    -------
    ndarray, shape (6, 6)
        ``G`` with ``x_point = G @ x_ref`` for rigid motion, i.e.
        ``[[I, -S(offset)], [0, I]]``. With ``offset = d - g`` this is ``G_dg``
        of eq. (12); its inverse is ``transfer_matrix(-offset)`` (eq. (14)).

    Examples
    --------
    A rotation about z moves a point at ``(1, 0, 0)`` along y:

    >>> (transfer_matrix([1.0, 0.0, 0.0]) @ [0, 0, 0, 0, 0, 1.0])[:3].tolist()
    [0.0, 1.0, 0.0]
    """
    g = np.eye(6)
    g[:3, 3:] = -skew(offset)
    return g


def normalise_directions(directions: ArrayLike) -> Array:
    """Scale each measuring direction to unit length.

    Parameters
    ----------
    directions : array_like, shape (p, 3)
        Measuring axes, any length.

    Returns
    -------
    ndarray, shape (p, 3)
        Unit vectors.

    Raises
    ------
    InputError
        If a direction is zero or not finite.
    """
    d = np.asarray(directions, dtype=float).reshape(-1, 3)
    norms = np.linalg.norm(d, axis=1)
    bad = np.flatnonzero(~np.isfinite(norms) | (norms <= 0.0))
    if bad.size:
        raise InputError("direction is a zero or non-finite vector", location=f"sensor {bad[0] + 1}")
    result: Array = d / norms[:, None]
    return result


def sensor_matrix(positions: ArrayLike, directions: ArrayLike, reference: ArrayLike = (0.0, 0.0, 0.0)) -> Array:
    """Sensor transformation ``T_mo``: eq. (3) of [1] for any measuring direction.

    Parameters
    ----------
    positions : array_like, shape (..., p, 3)
        Sensor locations (length); leading axes stack several layouts.
    directions : array_like, shape (..., p, 3)
        Unit measuring axes of the sensors.
    reference : array_like, shape (3,)
        The reference point of the rigid-body coordinates (length).

    Returns
    -------
    ndarray, shape (..., p, 6)
        Row ``i`` is ``[n_i, (r_i - reference) x n_i]``, so that the reading of
        sensor ``i`` is ``T[i] @ x`` for rigid motion ``x`` of the reference
        point. For ``n_i = +x`` the row is ``[1, 0, 0, 0, w_i, -v_i]``, eq. (3).

    Notes
    -----
    Directions are used as given; normalise them first
    (:func:`normalise_directions`) unless they are already unit vectors.

    Examples
    --------
    A sensor on the x axis at ``(0, 1, 0)`` reads ``x - rz``:

    >>> sensor_matrix([[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]]).tolist()
    [[1.0, 0.0, 0.0, 0.0, 0.0, -1.0]]
    """
    pos = np.asarray(positions, dtype=float)
    n = np.asarray(directions, dtype=float)
    if pos.ndim < 2:
        pos, n = pos.reshape(-1, 3), n.reshape(-1, 3)
    r = pos - np.asarray(reference, dtype=float)
    result: Array = np.concatenate([n, np.cross(r, n)], axis=-1)
    return result


class LayoutFrame:
    """A length scale and origin that make a sensor layout dimensionless.

    Attributes
    ----------
    centre : ndarray, shape (3,)
        Centroid of the sensor positions (length).
    scale : float
        RMS distance of the sensors from `centre` (length); 1 if they coincide.
    """

    __slots__ = ("centre", "scale")

    def __init__(self, centre: Array, scale: float):
        self.centre = centre
        self.scale = scale

    def to_local(self, points: ArrayLike) -> Array:
        """Map points (length) to the dimensionless frame."""
        result: Array = (np.asarray(points, dtype=float) - self.centre) / self.scale
        return result


def frame_arrays(positions: ArrayLike) -> tuple[Array, Array]:
    """Centroid and RMS radius of one or several sensor layouts.

    Parameters
    ----------
    positions : array_like, shape (..., p, 3)
        Sensor locations (length); leading axes stack layouts.

    Returns
    -------
    centre : ndarray, shape (..., 3)
        Centroid of the positions (length).
    scale : ndarray, shape (...)
        RMS distance of the sensors from the centroid (length); 1 where they
        all coincide.
    """
    r = np.asarray(positions, dtype=float)
    centre = r.mean(axis=-2)
    scale = np.sqrt(np.mean(np.sum((r - centre[..., None, :]) ** 2, axis=-1), axis=-1))
    return centre, np.where(scale > 0.0, scale, 1.0)


def layout_frame(positions: ArrayLike) -> LayoutFrame:
    """Centroid and RMS radius of a sensor layout.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor locations (length).

    Returns
    -------
    LayoutFrame
        Used to make the identification independent of origin and units.

    Examples
    --------
    >>> frame = layout_frame([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    >>> frame.centre.tolist(), frame.scale
    ([0.0, 0.0, 0.0], 1.0)
    """
    centre, scale = frame_arrays(np.asarray(positions, dtype=float).reshape(-1, 3))
    return LayoutFrame(centre, float(scale))


def local_sensor_matrix(positions: ArrayLike, directions: ArrayLike) -> Array:
    """The sensor transformation ``T`` in the layout's dimensionless frame (:func:`layout_frame`).

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor locations (length).
    directions : array_like, shape (p, 3)
        Unit measuring axes.

    Returns
    -------
    ndarray, shape (p, 6)
        :func:`sensor_matrix` of the positions about the sensor centroid divided
        by the RMS radius: independent of origin and units.
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    return sensor_matrix(layout_frame(pos).to_local(pos), directions)


def layout_condition(positions: ArrayLike, directions: ArrayLike) -> tuple[float, int]:
    """Condition number and rank of the dimensionless sensor transformation.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor locations (length).
    directions : array_like, shape (p, 3)
        Unit measuring axes.

    Returns
    -------
    cond : float
        2-norm condition number of ``T_mo`` built about the sensor centroid with
        positions divided by the RMS radius (independent of origin and units);
        ``inf`` when the rank is below 6.
    rank : int
        Numerical rank of that matrix (at most 6). The paper's step (3)
        requires rank 6.
    """
    t = local_sensor_matrix(positions, directions)
    s = np.linalg.svd(t, compute_uv=False)
    rank = int(numerical_rank(s, t.shape[0]))
    cond = float(s[0] / s[-1]) if rank == 6 and s.size == 6 else float("inf")
    return cond, rank


def sensor_outline(positions: ArrayLike) -> list[int]:
    """A closed outline through distinct points, for drawing a sensor layout as a frame.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Points (length unit); repeated points count once.

    Returns
    -------
    list of int
        Indices into `positions`, ordered by angle around the centroid in the
        points' best-fitting plane, the first index repeated at the end (no
        repetition for fewer than three distinct points).
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    distinct: list[int] = []
    for i, p in enumerate(pos):
        if not any(np.allclose(p, pos[j], rtol=0.0, atol=1e-12 * (1.0 + np.abs(p).max())) for j in distinct):
            distinct.append(i)
    if len(distinct) < 3:
        return distinct
    pts = pos[distinct]
    centred = pts - pts.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    u, v = centred @ vt[0], centred @ vt[1]
    order = np.argsort(np.arctan2(v, u), kind="stable")
    ring = [distinct[int(k)] for k in order]
    return [*ring, ring[0]]
