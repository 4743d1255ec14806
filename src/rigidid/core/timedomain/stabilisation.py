"""Stabilisation diagram: which poles of a sweep over model orders are physical.

A model of too high an order fits the noise with extra poles; those move from
one order to the next while the physical poles stay put. A pole is *stable*
when a pole of the previous order in the sweep has nearly the same frequency,
damping ratio and shape. Stable poles are then clustered across orders and
the clusters found at the most orders are taken as the modes.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.statespace import mac_matrix, modal_from_poles

__all__ = ["Cluster", "Criteria", "OrderPoles", "cluster_stable", "mac_matrix", "stabilise"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Criteria:
    """Tolerances of the stabilisation diagram.

    Attributes
    ----------
    frequency : float
        Largest relative change of natural frequency from the previous order.
    damping : float
        Largest relative change of damping ratio from the previous order.
    damping_floor : float
        Largest absolute change of damping ratio always accepted: the relative
        tolerance scaled to lightly damped poles, whose damping ratio scatters
        by more than `damping` of itself between orders (a 0.1 % mode would
        otherwise need agreement to 0.005 %).
    mac : float
        Smallest MAC with the matched pole of the previous order.
    max_damping : float
        Poles with a damping ratio at or above this (or at or below 0) are not
        physical and are dropped before anything else.
    """

    frequency: float = 0.005
    damping: float = 0.05
    damping_floor: float = 2e-4
    mac: float = 0.98
    max_damping: float = 0.3


@dataclass(frozen=True)
class OrderPoles:
    """The physical poles of one model order, for a stabilisation diagram.

    Attributes
    ----------
    order : int
        Model order (AR: number of lags; ERA: number of states).
    poles : ndarray of complex, shape (k,)
        Physical poles (rad/s, ``Im > 0``), ascending frequency.
    stable : ndarray of bool, shape (k,)
        Whether each pole matches one of the previous order in frequency,
        damping and shape.
    shapes : ndarray of complex, shape (r, k)
        Their shapes in the channels the model was fitted to (scaled data;
        see :class:`~rigidid.core.timedomain.ModalEstimate` for the shapes at
        the sensors).
    """

    order: int
    poles: CArray
    stable: BoolArray
    shapes: CArray

    @property
    def frequency_hz(self) -> Array:
        """Natural frequencies ``|lambda| / (2 pi)`` (Hz)."""
        return modal_from_poles(self.poles)[0]

    @property
    def damping_ratio(self) -> Array:
        """Damping ratios ``-Re(lambda) / |lambda|``."""
        return modal_from_poles(self.poles)[1]


@dataclass(frozen=True)
class Cluster:
    """Stable poles of several orders that are one mode.

    Attributes
    ----------
    pole : complex
        Representative pole (rad/s).
    shape : ndarray of complex, shape (r,)
        Its shape.
    count : int
        Number of orders at which the mode is stable.
    spread : float
        Relative scatter (standard deviation over mean) of the natural
        frequency over those orders.
    order : int
        Order the representative pole comes from.
    """

    pole: complex
    shape: CArray
    count: int
    spread: float
    order: int


_HUM_FREQUENCY = 0.005  # relative distance from a mains frequency of a hum pole
_HUM_DAMPING = 0.002  # largest damping ratio of a hum pole


def _physical(poles: CArray, band: tuple[float, float], max_damping: float) -> BoolArray:
    w = np.abs(poles)
    f = w / (2.0 * np.pi)
    z = -poles.real / np.maximum(w, 1e-300)
    result: BoolArray = (poles.imag > 0.0) & (f > band[0]) & (f < band[1]) & (z > 0.0) & (z < max_damping)
    return result & ~_mains_hum(f, z)


def _mains_hum(f: Array, z: Array) -> BoolArray:
    """Poles that are mains hum, not modes: undamped (ratio below 0.2 %) within 0.5 % of 50/60 Hz or a harmonic.

    Hum is a sinusoid of fixed amplitude; a sweep models it as a pole of zero damping at the mains'
    frequency (:mod:`rigidid.core.timedomain.hum`; the refit finds and models it, named).
    """
    from rigidid.core.timedomain.hum import MAINS_HZ

    near = np.zeros(f.shape, dtype=bool)
    for hz in MAINS_HZ:
        near |= np.abs(f / hz - 1.0) < _HUM_FREQUENCY
    out: BoolArray = near & (np.abs(z) < _HUM_DAMPING)
    return out


def stabilise(
    models: Sequence[tuple[int, CArray, CArray]],
    band: tuple[float, float],
    criteria: Criteria = Criteria(),
) -> list[OrderPoles]:
    """Keep the physical poles of each order and mark the stable ones.

    Parameters
    ----------
    models : sequence of (order, poles, shapes)
        The sweep, ascending order: poles (complex, rad/s) and shapes
        (complex, shape (r, k)) of each model.
    band : (float, float)
        Frequency band (Hz) physical poles must lie strictly inside.
    criteria : Criteria
        Tolerances.

    Returns
    -------
    list of OrderPoles
        One per model, poles ascending in frequency. The first order has no
        predecessor, so none of its poles is stable.
    """
    out: list[OrderPoles] = []
    prev: OrderPoles | None = None
    for order, poles, shapes in models:
        keep = _physical(poles, band, criteria.max_damping)
        lam, psi = poles[keep], shapes[:, keep]
        idx = np.argsort(np.abs(lam))
        lam, psi = lam[idx], psi[:, idx]
        stable = np.zeros(lam.shape[0], dtype=bool)
        if prev is not None and prev.poles.size and lam.size:
            f, z = np.abs(lam), -lam.real / np.abs(lam)
            fp, zp = np.abs(prev.poles), -prev.poles.real / np.abs(prev.poles)
            df = np.abs(f[:, None] - fp[None, :]) / fp[None, :]
            dz_abs = np.abs(z[:, None] - zp[None, :])
            dz = dz_abs / zp[None, :]
            mac = mac_matrix(psi, prev.shapes)
            damping_ok = (dz < criteria.damping) | (dz_abs < criteria.damping_floor)
            ok = (df < criteria.frequency) & damping_ok & (mac > criteria.mac)
            stable = np.any(ok, axis=1)
        current = OrderPoles(order, lam, stable, psi)
        out.append(current)
        prev = current
    return out


def cluster_stable(
    diagram: Sequence[OrderPoles],
    *,
    frequency: float = 0.005,
    mac: float = 0.9,
    min_count: int = 3,
) -> list[Cluster]:
    """Group the stable poles of a diagram into modes, most consistent first.

    Parameters
    ----------
    diagram : sequence of OrderPoles
        From :func:`stabilise`.
    frequency : float
        A stable pole joins a cluster when its frequency is within this
        relative distance of the cluster's reference pole...
    mac : float
        ... and the MAC with the reference shape exceeds this.
    min_count : int
        Clusters stable at fewer orders are dropped.

    Returns
    -------
    list of Cluster
        Sorted by decreasing `count`, then increasing `spread`.

    Notes
    -----
    Orders are visited from the highest down, so each cluster's reference is
    its pole at the highest order (where the noise is best absorbed by the
    extra poles). A cluster takes at most one pole per order, the closest. The
    representative pole is the member whose frequency and damping ratio are
    nearest the cluster's medians, taken among the upper half of its orders.
    A cluster whose reference is within `frequency` and `mac` of a cluster
    already kept (the same mode, drifted at low orders) is merged into it.
    """
    refs: list[tuple[complex, CArray]] = []
    members: list[list[tuple[int, complex, CArray]]] = []
    for entry in sorted(diagram, key=lambda d: -d.order):
        taken: dict[int, int] = {}
        for k in np.flatnonzero(entry.stable):
            lam = complex(entry.poles[k])
            psi = entry.shapes[:, k]
            best, best_df = -1, np.inf
            for index, (ref, ref_shape) in enumerate(refs):
                df = abs(abs(lam) - abs(ref)) / abs(ref)
                if df < frequency and df < best_df and mac_matrix(psi[:, None], ref_shape[:, None])[0, 0] > mac:
                    best, best_df = index, df
            if best < 0:
                refs.append((lam, psi))
                members.append([(entry.order, lam, psi)])
            elif best in taken:
                # keep the closer of two poles of the same order
                prev_k = taken[best]
                ref = refs[best][0]
                prev_lam = members[best][prev_k][1]
                if abs(abs(lam) - abs(ref)) < abs(abs(prev_lam) - abs(ref)):
                    members[best][prev_k] = (entry.order, lam, psi)
            else:
                taken[best] = len(members[best])
                members[best].append((entry.order, lam, psi))
    clusters: list[Cluster] = []
    for group in members:
        if len(group) < min_count:
            continue
        lam_all = np.array([g[1] for g in group])
        f_all = np.abs(lam_all)
        upper = group[: max(1, (len(group) + 1) // 2)]
        lam_up = np.array([g[1] for g in upper])
        f_up, z_up = np.abs(lam_up), -lam_up.real / np.abs(lam_up)
        f_med, z_med = float(np.median(f_up)), float(np.median(z_up))
        dist = ((f_up - f_med) / f_med) ** 2 + ((z_up - z_med) / max(z_med, 1e-12)) ** 2
        pick = upper[int(np.argmin(dist))]
        spread = float(np.std(f_all) / np.mean(f_all))
        clusters.append(Cluster(pick[1], pick[2], len(group), spread, pick[0]))
    clusters.sort(key=lambda c: (-c.count, c.spread))
    kept: list[Cluster] = []
    for c in clusters:
        duplicate = any(
            abs(abs(c.pole) - abs(k.pole)) / abs(k.pole) < frequency
            and mac_matrix(c.shape[:, None], k.shape[:, None])[0, 0] > mac
            for k in kept
        )
        if not duplicate:
            kept.append(c)
    return kept
