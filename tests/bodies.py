"""Random bodies and layouts for tests: physically valid, seeded, varied."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from rigidid.core.simulate import Body, Mount

Array = NDArray[np.float64]


def random_body(
    rng: np.random.Generator,
    *,
    n_mounts: int = 4,
    damping: float = 0.02,
    proportional: bool = False,
    scale: float = 1.0,
) -> Body:
    """A random, physically valid body on mounts (test helper).

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness.
    n_mounts : int
        Number of mounts, at least 3, placed around and below the CG.
    damping : float
        Typical modal damping ratio the mount damping aims at.
    proportional : bool
        If false, each mount has its own damping-to-stiffness ratio and a full
        3x3 damping matrix (non-proportional damping, complex modes).
    scale : float
        Length scale of the body (length units).

    Returns
    -------
    Body
    """
    mass = float(rng.uniform(5.0, 500.0))
    cg = rng.uniform(-1.0, 1.0, 3) * scale
    axes = np.sort(rng.uniform(0.3, 1.0, 3)) * scale
    a2 = axes**2
    moments = mass / 5.0 * np.array([a2[1] + a2[2], a2[0] + a2[2], a2[0] + a2[1]])
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    inertia = q @ np.diag(moments) @ q.T
    mounts: list[Mount] = []
    k0 = mass * (2.0 * np.pi * rng.uniform(5.0, 15.0)) ** 2 / n_mounts
    for i in range(n_mounts):
        angle = 2.0 * np.pi * (i + rng.uniform(-0.2, 0.2)) / n_mounts
        pos = cg + scale * np.array([np.cos(angle), np.sin(angle), -rng.uniform(0.2, 0.8)])
        kd = k0 * rng.uniform(0.3, 1.5, 3)
        r, _ = np.linalg.qr(rng.standard_normal((3, 3)))
        kmat = r @ np.diag(kd) @ r.T
        if proportional:
            cmat = 2.0 * damping / (2.0 * np.pi * 10.0) * kmat
        else:
            r2, _ = np.linalg.qr(rng.standard_normal((3, 3)))
            cd = 2.0 * damping * np.sqrt(kd * mass / n_mounts) * rng.uniform(0.2, 2.0, 3)
            cmat = r2 @ np.diag(cd) @ r2.T
        mounts.append(Mount(pos, kmat, cmat))
    return Body(mass, cg, inertia, tuple(mounts))


def random_layout(
    rng: np.random.Generator,
    n_sensors: int,
    *,
    scale: float = 1.0,
    centre: Sequence[float] = (0.0, 0.0, 0.0),
    skewed: bool = True,
) -> tuple[Array, Array]:
    """Random sensor positions and unit directions of full rank.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness.
    n_sensors : int
        Number of sensors, at least 6.
    scale : float
        Half-width of the box the sensors lie in (length).
    centre : sequence of 3 floats
        Centre of that box.
    skewed : bool
        Random unit directions if true, else cycling through the +/- axes.

    Returns
    -------
    positions, directions : ndarray, shape (n_sensors, 3)
    """
    pos = np.asarray(centre, dtype=float) + scale * rng.uniform(-1.0, 1.0, (n_sensors, 3))
    if skewed:
        d = rng.standard_normal((n_sensors, 3))
    else:
        d = np.eye(3)[np.arange(n_sensors) % 3] * rng.choice([-1.0, 1.0], (n_sensors, 1))
    return pos, d / np.linalg.norm(d, axis=1)[:, None]


def flat_layout_on_symmetric_mounts() -> tuple[Body, Array, Array]:
    """A body on mounts symmetric about its CG (inertia unobservable) seen by an almost flat layout.

    Identification warns that the layout is ill-conditioned (condition about 4e7), then fails
    because the inertia is not observable: a warning followed by an error.
    """
    corners = [[x, y, z] for x in (0.3, -0.3) for y in (0.2, -0.2) for z in (0.2, -0.2)]
    mounts = [Mount.from_values(p, (1e5, 1e5, 2e5)) for p in corners]
    body = Body(50.0, np.zeros(3), np.diag([2.0, 3.0, 4.0]), mounts)
    positions = np.array([[x, y, z * 1e-7] for x in (0.4, -0.4) for y in (0.3, -0.3) for z in (0.2, -0.2)])
    directions = np.eye(3)[[0, 1, 2, 0, 1, 2, 0, 1]]
    return body, positions, directions


def corner_references(positions: Array) -> Array:
    """Three hammer points at corners of the sensors' bounding box (x, y, z hits: ``np.eye(3)``)."""
    lo, hi = positions.min(axis=0), positions.max(axis=0)
    return np.array([[hi[0], hi[1], hi[2]], [lo[0], hi[1], lo[2]], [hi[0], lo[1], lo[2]]])


def frf_test_on_mounts(
    rng: np.random.Generator, *, soften: float = 1.0, references: int = 3
) -> tuple[Body, Array, Array, Array, Array, Array, NDArray[np.complex128]]:
    """Issue 12's FRF test: a random body on mounts, 8 sensors, 0.25-400 Hz in 3200 lines, one elastic
    mode at 300 Hz, 1 % noise on the accelerance. `soften` scales the mounts' stiffness (damping by its
    square root: 0.01 puts the supports a tenth lower, free-free); `references` is 3 (x, y, z at three
    corners, :func:`corner_references`) or 6 (the same corners hit again along y, z, x). Returns body,
    positions, directions, reference positions and directions, frequencies and FRFs (p, q, f)."""
    import dataclasses

    from rigidid.core.frf import accelerance, random_elastic_modes

    body = random_body(rng)
    if soften != 1.0:
        mounts = tuple(Mount(m.position, m.stiffness * soften, m.damping * np.sqrt(soften)) for m in body.mounts)
        body = dataclasses.replace(body, mounts=mounts)
    pos, dirs = random_layout(rng, 8, centre=body.center_of_gravity)
    rpos, rdirs = corner_references(pos), np.eye(3)
    f = np.linspace(0.25, 400.0, 3200)
    elastic = random_elastic_modes(rng, [300.0], 8, references, mass=body.mass)
    if references == 6:
        rpos, rdirs = np.vstack([rpos, rpos]), np.vstack([rdirs, rdirs[[1, 2, 0]]])
    h = accelerance(body, pos, dirs, rpos, rdirs, f, elastic=elastic, noise=0.01, rng=rng)
    return body, pos, dirs, rpos, rdirs, f, h
