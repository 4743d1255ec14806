"""A forward model of a rigid body on mounts, written apart from rigidid's (no rigidid import).

Used by ``verdict_regimes.py``: state-space eigenvectors of ``M q'' + C q' + K q = 0`` at
the CG (scipy.linalg.eig of the first-order form), sensors reading ``d . (x + theta x s)``,
and the noise model of ``rigidid``'s documentation (relative frequency and damping-ratio
noise, complex shape noise relative to each mode's RMS reading).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix: ``skew(a) @ b == np.cross(a, b)``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rot_z(deg: float) -> np.ndarray:
    c, s = np.cos(np.deg2rad(deg)), np.sin(np.deg2rad(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass
class Rig:
    """A body (mass, CG, inertia about the CG) on point mounts (position, 3x3 stiffness and damping)."""

    mass: float
    cg: np.ndarray
    inertia: np.ndarray
    mount_pos: np.ndarray  # (n, 3)
    mount_k: np.ndarray  # (n, 3, 3) in the test's axes
    mount_c: np.ndarray  # (n, 3, 3)

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """M, K, C at the CG (x, y, z, rx, ry, rz)."""
        m = np.zeros((6, 6))
        m[:3, :3] = self.mass * np.eye(3)
        m[3:, 3:] = self.inertia
        k = np.zeros((6, 6))
        c = np.zeros((6, 6))
        for r, km, cm in zip(self.mount_pos, self.mount_k, self.mount_c, strict=True):
            b = np.hstack([np.eye(3), -skew(r - self.cg)])  # point motion u = x + theta x r
            k += b.T @ km @ b
            c += b.T @ cm @ b
        return m, k, c

    def modes(self, sensors: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Six poles (Im > 0, ascending) and sensor shapes (p, 6)."""
        m, k, c = self.matrices()
        a = np.block([[np.zeros((6, 6)), np.eye(6)], [-np.linalg.solve(m, k), -np.linalg.solve(m, c)]])
        lam, vec = scipy.linalg.eig(a)
        up = np.flatnonzero(lam.imag > 0)
        up = up[np.argsort(np.abs(lam[up]))]
        phi = vec[:6, up]
        rows = np.array([np.concatenate([d, np.cross(s - self.cg, d)]) for s, d in zip(sensors, dirs, strict=True)])
        return lam[up], rows @ phi


def add_noise(
    lam: np.ndarray, psi: np.ndarray, rng: np.random.Generator, f_rel: float, z_rel: float, s_rel: float
) -> tuple[np.ndarray, np.ndarray]:
    """Noisy poles and shapes: the noise model the intervals assume."""
    w = np.abs(lam)
    z = -lam.real / w
    w2 = w * (1.0 + f_rel * rng.standard_normal(6))
    z2 = np.clip(z * (1.0 + z_rel * rng.standard_normal(6)), 0.0, 0.999)
    lam2 = w2 * (-z2 + 1j * np.sqrt(1.0 - z2 * z2))
    rms = np.sqrt(np.mean(np.abs(psi) ** 2, axis=0))
    e = (rng.standard_normal(psi.shape) + 1j * rng.standard_normal(psi.shape)) / np.sqrt(2.0)
    return lam2, psi + s_rel * rms * e


def engine(observe: float = 1.0, turn: float = 35.0, mounts: int = 3, missing: bool = False) -> Rig:
    """An engine-like body (180 kg) on three or four rubber mounts, one turned `turn` degrees about z.

    `observe` scales the mounts' height offset from the CG (small: rotations and translations
    barely couple, the inertia is weakly observable). `missing`: an extra support (a stiff hose)
    that the mounts file will not list.
    """
    cg = np.array([0.02, -0.01, 0.05])
    inertia = np.array([[6.0, 0.3, -0.4], [0.3, 9.0, 0.2], [-0.4, 0.2, 7.5]])
    base = [[0.25, 0.18, -0.15], [-0.25, 0.2, -0.12], [0.0, -0.22, -0.14], [-0.22, -0.2, -0.13]][:mounts]
    pos = np.array(base, dtype=float)
    pos[:, 2] = cg[2] + observe * (pos[:, 2] - cg[2])
    kd = np.diag([1.2e5, 0.9e5, 3.0e5])
    turns = [turn, 0.0, -10.0, 5.0][:mounts]
    ks = np.array([rot_z(t) @ kd @ rot_z(t).T for t in turns])
    cs = 6e-4 * ks + np.array([rot_z(t) @ np.diag([20.0, 35.0, 60.0]) @ rot_z(t).T for t in turns])
    if missing:
        pos = np.vstack([pos, [[0.0, 0.35, 0.2]]])
        ks = np.concatenate([ks, 0.25 * kd[None]])
        cs = np.concatenate([cs, 6e-4 * 0.25 * kd[None]])
    return Rig(180.0, cg, inertia, pos, ks, cs)


def layout(count: int, rng: np.random.Generator | None = None) -> tuple[np.ndarray, np.ndarray]:
    """`count` sensors (6, 12 or 32) on a 0.6 x 0.5 x 0.4 m box: positions and unit directions."""
    corners = np.array([[x, y, z] for x in (0.3, -0.3) for y in (0.25, -0.25) for z in (0.2, -0.2)])
    if count == 6:
        return corners[[0, 3, 5, 6, 1, 2]], np.eye(3)[[2, 0, 1, 2, 0, 1]]
    if count == 12:
        pos = np.repeat(corners[[0, 3, 5, 6]], 3, axis=0)
        return pos, np.tile(np.eye(3), (4, 1))
    gen = rng if rng is not None else np.random.default_rng(7)
    pos = np.vstack([np.repeat(corners, 3, axis=0), gen.uniform(-0.3, 0.3, (count - 24, 3)) * [1, 0.8, 0.66]])
    dirs = np.vstack([np.tile(np.eye(3), (8, 1)), np.eye(3)[gen.integers(0, 3, count - 24)]])
    return pos, dirs
