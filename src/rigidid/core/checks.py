"""Checks that say when the data are wrong: findings, not warnings.

Each function takes arrays and returns frozen finding dataclasses (or an empty
tuple); none prints or warns. The API turns findings into warnings or errors,
so the same checks can feed the identification's diagnostics.

- :func:`sensor_outliers`: one sensor whose readings fit rigid-body motion much
  worse than the others' (a wrong position, direction or sign in the layout).
- :func:`percent_damping`: damping ratios that look like percentages.
- :func:`nonrigid_modes`: modes whose shapes no rigid-body motion explains.
- :func:`inertia_not_positive`: an inertia tensor that is not positive definite.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.linalg import numerical_rank

__all__ = [
    "CG_OUTSIDE",
    "DENSITY_RANGE",
    "GYRATION_RATIO",
    "NONRIGID_RESIDUAL",
    "OUTLIER_FLOOR",
    "OUTLIER_SHARE",
    "PERCENT_DAMPING",
    "InertiaFinding",
    "ModeFinding",
    "PercentDampingFinding",
    "PlausibilityFinding",
    "SensorFinding",
    "implausible_body",
    "inertia_not_positive",
    "nonrigid_modes",
    "percent_damping",
    "sensor_outliers",
]

Array = NDArray[np.float64]

OUTLIER_SHARE = 0.6
"""A sensor is an outlier when leaving it out removes this share of the rigid-fit misfit (or more)."""
OUTLIER_FLOOR = 0.02
"""... and 2 % of the modes' RMS reading (below that, misfits are noise)."""
NONRIGID_RESIDUAL = 0.5
"""Rigid-fit residual above which a mode is not a rigid-body mode (rigid modes of real tests: below ~0.2)."""
PERCENT_DAMPING = 0.1
"""Damping ratios whose median is above this look like percentages (0.39 meant as 0.39 %)."""


@dataclass(frozen=True)
class SensorFinding:
    """A sensor that fits rigid-body motion much worse than the others.

    Attributes
    ----------
    index : int
        Row of the sensor in the layout.
    misfit : float
        Its leave-one-out misfit: how far its reading is from the rigid motion
        the other sensors give, relative to the modes' RMS reading (RMS over
        modes).
    typical : float
        The median misfit of all sensors.
    share : float
        The share of the rigid-fit misfit of all sensors that leaving this
        sensor out removes (1: the others then fit rigid motion exactly).
    """

    index: int
    misfit: float
    typical: float
    share: float


@dataclass(frozen=True)
class PercentDampingFinding:
    """Damping ratios that look like percentages.

    Attributes
    ----------
    damping_ratio : ndarray, shape (n,)
        The ratios given.
    """

    damping_ratio: Array


@dataclass(frozen=True)
class ModeFinding:
    """Modes that are not rigid-body modes.

    Attributes
    ----------
    labels : tuple of int
        Their labels.
    residuals : tuple of float
        Their rigid-fit residuals ``|psi - T T^+ psi| / |psi|``.
    """

    labels: tuple[int, ...]
    residuals: tuple[float, ...]


@dataclass(frozen=True)
class InertiaFinding:
    """An inertia tensor that is not positive definite.

    Attributes
    ----------
    principal_moments_per_mass : ndarray, shape (3,)
        Its eigenvalues, ascending (length^2); the first is not positive.
    """

    principal_moments_per_mass: Array


def sensor_outliers(
    transformation: ArrayLike,
    shapes: ArrayLike,
    *,
    share_needed: float = OUTLIER_SHARE,
    floor: float = OUTLIER_FLOOR,
) -> tuple[SensorFinding, ...]:
    """Sensors whose readings fit rigid-body motion much worse than the others'.

    Parameters
    ----------
    transformation : array_like, shape (p, 6)
        Sensor transformation ``T`` (eq. (2)-(6) of [1]; see
        :func:`rigidid.core.geometry.sensor_matrix`), any frame.
    shapes : array_like of complex, shape (p, n)
        Measured mode shapes (rigid-body modes), one column per mode.
    share_needed : float
        Leaving the sensor out must remove at least this share of the total
        misfit, and leave less than half the misfit that leaving out any other
        sensor leaves.
    floor : float
        ... and its misfit must exceed this (relative to each mode's RMS
        reading): below it, misfits are measurement noise.

    Returns
    -------
    tuple of SensorFinding
        The one sensor to blame, or empty when all sensors agree, when no
        single sensor explains the misfit, or when no sensor can be checked
        (six sensors, or each needed for rank 6). With seven sensors every
        sensor explains the misfit equally, so none is named.

    Notes
    -----
    The misfit of sensor ``i`` in mode ``k`` is its leave-one-out residual:
    ``r_ik / (1 - h_ii)``, with ``r = psi - T T^+ psi`` the least-squares
    residual and ``h_ii`` the diagonal of the hat matrix ``T T^+``; it is
    exactly the difference between the sensor's reading and the rigid motion
    fitted to the other sensors, so one bad sensor does not hide behind the
    fit it spoils. Each mode is scaled by its RMS reading; the misfits are
    combined as an RMS over the modes. Leaving sensor ``i`` out lowers the
    residual sum of squares by ``|r_i|^2 / (1 - h_ii)``; the sensor whose
    removal takes most of it is the one to blame. A sensor whose removal leaves the layout
    below rank 6 (``h_ii`` near 1) cannot be checked and is skipped.
    """
    t = np.asarray(transformation, dtype=float)
    psi = np.asarray(shapes, dtype=complex)
    p = t.shape[0]
    if p <= 6 or psi.shape[0] != p or psi.shape[1] == 0:
        return ()
    u, s, _ = np.linalg.svd(t, full_matrices=False)
    u = u[:, : int(numerical_rank(s, p))]
    leverage = np.sum(u * u, axis=1)
    coords, *_ = np.linalg.lstsq(t.astype(complex), psi, rcond=None)
    rms = np.sqrt(np.mean(np.abs(psi) ** 2, axis=0))
    residual = (psi - t @ coords) / np.where(rms > 0.0, rms, 1.0)[None, :]
    checkable = leverage < 1.0 - 1e-6
    if np.count_nonzero(checkable) < 2:
        return ()
    misfit = np.zeros(p)
    drop = np.zeros(p)
    lev = leverage[checkable, None]
    misfit[checkable] = np.sqrt(np.mean(np.abs(residual[checkable] / (1.0 - lev)) ** 2, axis=1))
    drop[checkable] = np.sum(np.abs(residual[checkable]) ** 2 / (1.0 - lev), axis=1)
    total = float(np.sum(np.abs(residual) ** 2))
    if total <= 0.0:
        return ()
    share = drop / total
    order = np.argsort(-share)
    best, second = int(order[0]), int(order[1])
    typical = float(np.median(misfit[checkable]))
    unique = 1.0 - share[second] > 2.0 * (1.0 - share[best]) + 1e-6  # with 7 sensors all shares are 1
    if share[best] >= share_needed and unique and misfit[best] > floor:
        return (SensorFinding(best, float(misfit[best]), typical, float(share[best])),)
    return ()


def percent_damping(damping_ratio: ArrayLike, *, threshold: float = PERCENT_DAMPING) -> PercentDampingFinding | None:
    """Damping ratios that look like percentages (their median above `threshold`).

    Parameters
    ----------
    damping_ratio : array_like, shape (n,)
        Fractions of critical damping of the modes used.
    threshold : float
        Rigid-body modes on mounts are damped 0.1-10 % of critical; when the
        median ratio exceeds this fraction (10 %), the numbers were probably
        meant in percent (ratios of 1 or more are refused by the reader, so
        percentages that get this far are below 1 %).

    Returns
    -------
    PercentDampingFinding or None
    """
    z = np.asarray(damping_ratio, dtype=float).ravel()
    if z.size and float(np.median(z)) > threshold:
        return PercentDampingFinding(z.copy())
    return None


def nonrigid_modes(
    labels: Sequence[int], residuals: ArrayLike, *, threshold: float = NONRIGID_RESIDUAL
) -> ModeFinding | None:
    """Modes whose shapes fit rigid-body motion too badly to be rigid-body modes.

    Parameters
    ----------
    labels : sequence of int
        Mode labels.
    residuals : array_like, shape (n,)
        Their rigid-fit residuals (:func:`rigidid.core.selection.rigid_fit_residuals`),
        0 for exact rigid-body motion and near 1 for shapes no rigid motion
        explains. Only meaningful with more than six sensors.
    threshold : float
        Residual above which a mode is reported.

    Returns
    -------
    ModeFinding or None
    """
    r = np.asarray(residuals, dtype=float).ravel()
    bad = [k for k in range(r.size) if r[k] > threshold]
    if not bad:
        return None
    return ModeFinding(tuple(int(labels[k]) for k in bad), tuple(float(r[k]) for k in bad))


def inertia_not_positive(inertia_per_mass: ArrayLike) -> InertiaFinding | None:
    """The inertia tensor's principal moments when one is not positive, else None.

    Parameters
    ----------
    inertia_per_mass : array_like, shape (3, 3)
        Inertia tensor about the CG divided by mass (length^2), symmetrised here.

    Returns
    -------
    InertiaFinding or None
    """
    j = np.asarray(inertia_per_mass, dtype=float)
    moments = np.linalg.eigvalsh(0.5 * (j + j.T))
    if moments[0] > 0.0:
        return None
    return InertiaFinding(moments)


DENSITY_RANGE = (1.0, 1e5)
"""Plausible bounds of a body's apparent density (kg/m^3) from its mass and the sensors'
extent: above air, below five times tungsten. The sensors' box lies inside the body, so the
implied density is an upper bound of the body's; a length unit off by 1000 moves it by 1e9."""

GYRATION_RATIO = 3.0
"""Largest radius of gyration, as a multiple of the farthest sensor's distance from the CG,
that a body the sensors sit on can have."""

CG_OUTSIDE = 2.0
"""Distance of the CG from the sensors' centroid, in multiples of the farthest sensor's, that
no body the sensors sit on reaches."""


@dataclass(frozen=True)
class PlausibilityFinding:
    """An implausible body: what was found, in words, and what to check.

    Attributes
    ----------
    kind : str
        ``"density"``, ``"gyration"`` or ``"cg_outside"``.
    value : float
        The figure judged (kg/m^3, a ratio).
    text : str
        What it means and what to check.
    """

    kind: str
    value: float
    text: str


def _box_volume(positions: Array) -> tuple[float, float]:
    """Volume of the sensors' box along their principal directions, and its thinnest-to-widest ratio."""
    centred = positions - positions.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2]
    extent = np.ptp(centred @ axes.T, axis=0)
    return float(np.prod(extent)), float(extent.min() / max(extent.max(), 1e-300))


def implausible_body(
    positions: ArrayLike,
    center_of_gravity: ArrayLike,
    inertia_per_mass: ArrayLike,
    *,
    mass_kg: float | None = None,
    metre: float = 1.0,
) -> list[PlausibilityFinding]:
    """Findings that the identified body cannot be the one the sensors sit on (units, layout).

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor locations (length).
    center_of_gravity : array_like, shape (3,)
        The CG (length).
    inertia_per_mass : array_like, shape (3, 3)
        ``J / m`` (length^2).
    mass_kg : float, optional
        The mass in kg (for the density).
    metre : float
        Metres per length unit.

    Returns
    -------
    list of PlausibilityFinding
        Empty for a plausible body. The density is judged only when the
        sensors span a box at least a tenth as thick as it is wide.

    Examples
    --------
    A 40 kg body in a 0.6 m box, its layout in metres declared as millimetres:

    >>> pos = np.array([[x, y, z] for x in (0.3, -0.3) for y in (0.2, -0.2) for z in (0.15, -0.15)])
    >>> [f.kind for f in implausible_body(pos, np.zeros(3), 0.04 * np.eye(3), mass_kg=40.0, metre=0.001)]
    ['density']
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    cg = np.asarray(center_of_gravity, dtype=float)
    j = np.asarray(inertia_per_mass, dtype=float)
    found = []
    volume, flatness = _box_volume(pos)
    if mass_kg is not None and flatness >= 0.1 and volume > 0.0:
        density = mass_kg / (volume * metre**3)
        low, high = DENSITY_RANGE
        if not low <= density <= high:
            found.append(PlausibilityFinding("density", density, (
                f"a {mass_kg:.3g} kg body around sensors spanning {volume * metre**3:.3g} m^3 would have a density of "
                f"{density:.2g} kg/m^3 (real bodies: 1e2-2e4): the layout's length unit or the mass unit is wrong"
                " (a layout in metres declared as mm, or the reverse?)"
            )))  # fmt: skip
    reach = float(np.max(np.linalg.norm(pos - cg, axis=1)))
    moments = np.linalg.eigvalsh(0.5 * (j + j.T))
    if moments[-1] > 0.0 and reach > 0.0:
        gyration = float(np.sqrt(moments[-1])) / reach
        if gyration > GYRATION_RATIO:
            found.append(PlausibilityFinding("gyration", gyration, (
                f"the largest radius of gyration is {gyration:.2g} times the farthest sensor's distance from the CG: "
                "no body the sensors sit on is that large; check the mass and the sensors' positions and units"
            )))  # fmt: skip
    centre = pos.mean(axis=0)
    spread = float(np.max(np.linalg.norm(pos - centre, axis=1)))
    outside = float(np.linalg.norm(cg - centre)) / max(spread, 1e-300)
    if outside > CG_OUTSIDE:
        found.append(PlausibilityFinding("cg_outside", outside, (
            f"the CG lies {outside:.2g} times the sensors' radius from their centroid, far outside the body they "
            "sit on: check the directions' signs and the positions in the layout"
        )))  # fmt: skip
    return found
