"""An FRF simulator written afresh for the FRF benchmarks: a rigid body on point mounts.

It shares no code with rigidid's estimators (numpy only): ``M``, ``K`` and ``C`` assembled
here, accelerance ``H(w) = -w^2 T (K - w^2 M + i w C)^-1 T_f^T`` solved line by line, elastic
modes added as modal sums, noise complex and relative to each value, optional H1 bias.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

Array = np.ndarray


def cross(v: Array) -> Array:
    """The matrix of ``v x`` (3 x 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rows(points: Array, dirs: Array) -> Array:
    """Rigid motion (translation of the origin, rotation) seen along ``dirs`` at ``points``: (n, 6)."""
    return np.hstack([dirs, np.cross(points, dirs)])


@dataclass
class Rig:
    """A body on mounts with its sensors and references (all about the global origin)."""

    mass: float
    cg: Array
    inertia: Array  # about the CG
    mount_points: Array  # (k, 3)
    mount_k: Array  # (k, 3) stiffness along x, y, z at each mount
    damping_ratio: float  # mount damping ratio at 10 Hz equivalent (C = 2 zeta K / w_ref)
    sensors: Array
    sensor_dirs: Array
    refs: Array
    ref_dirs: Array
    elastic: list[tuple[float, float, Array, Array]] = field(default_factory=list)  # (Hz, zeta, phi_s, phi_r)

    def matrices(self) -> tuple[Array, Array, Array]:
        m = np.zeros((6, 6))
        m[:3, :3] = self.mass * np.eye(3)
        c = cross(self.cg)
        m[:3, 3:] = -self.mass * c
        m[3:, :3] = self.mass * c
        m[3:, 3:] = self.inertia - self.mass * c @ c
        k = np.zeros((6, 6))
        for pt, kk in zip(self.mount_points, self.mount_k, strict=True):
            b = np.hstack([np.eye(3), -cross(pt)])  # displacement of the point from (u, theta)
            k += b.T @ np.diag(kk) @ b
        return m, k, k.copy()

    def rigid_hz(self) -> Array:
        m, k, _ = self.matrices()
        ev = np.linalg.eigvals(np.linalg.solve(m, k)).real
        return np.sort(np.sqrt(np.maximum(ev, 0.0))) / (2 * np.pi)

    def frf(
        self,
        f: Array,
        noise: float = 0.0,
        rng: np.random.Generator | None = None,
        h1_bias: float = 0.0,
        additive: float = 0.0,
    ) -> Array:
        """Accelerance (p, q, f) with complex noise of ``noise`` times each value plus ``additive``
        times each FRF's RMS over the lines (a noise floor: what dominates at anti-resonances)."""
        m, k, kc = self.matrices()
        w_ref = 2 * np.pi * max(float(np.median(self.rigid_hz())), 1e-3)
        c = 2.0 * self.damping_ratio / w_ref * kc
        t = rows(self.sensors, self.sensor_dirs)
        tf = rows(self.refs, self.ref_dirs)
        w = 2 * np.pi * np.asarray(f, dtype=float)
        a = k[None] - (w**2)[:, None, None] * m[None] + 1j * w[:, None, None] * c[None]
        x = np.linalg.solve(a, np.broadcast_to(tf.T.astype(complex), (w.size, 6, tf.shape[0])))
        h = -(w**2)[:, None, None] * np.einsum("pi,niq->npq", t, x)
        for fe, ze, ps, pr in self.elastic:
            we = 2 * np.pi * fe
            h += (-(w**2) / (we**2 - w**2 + 2j * ze * we * w))[:, None, None] * np.outer(ps, pr)[None]
        h = np.moveaxis(h, 0, 2)
        if h1_bias:
            # H1 underestimates near resonances (leakage/low coherence): scale by 1 - bias * peakiness
            s = np.sum(np.abs(h) ** 2, axis=(0, 1))
            h = h * (1.0 - h1_bias * s / s.max())[None, None, :]
        if noise or additive:
            g = rng if rng is not None else np.random.default_rng(0)
            e = (g.standard_normal(h.shape) + 1j * g.standard_normal(h.shape)) / np.sqrt(2.0)
            rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=2, keepdims=True))
            h = h + (noise * np.abs(h) + additive * rms) * e
        return h


def make_rig(
    rng: np.random.Generator,
    *,
    mount_hz: float = 8.0,
    zeta: float = 0.02,
    n_sensors: int = 8,
    n_refs: int = 3,
    free: bool = False,
    mass_scale: float = 1.0,
    size_scale: float = 1.0,
) -> Rig:
    """A random box-like body (5-100 kg, about 1 m; times `mass_scale` and `size_scale`) on four mounts below it."""
    mass = float(rng.uniform(5.0, 100.0)) * mass_scale
    cg = rng.uniform(-0.2, 0.2, 3) * size_scale
    half = np.array([0.6, 0.4, 0.25]) * rng.uniform(0.8, 1.2, 3) * size_scale
    mom = mass / 3.0 * np.array([half[1] ** 2 + half[2] ** 2, half[0] ** 2 + half[2] ** 2, half[0] ** 2 + half[1] ** 2])
    r, _ = np.linalg.qr(rng.standard_normal((3, 3)) * 0.2 + np.eye(3))
    inertia = r @ np.diag(mom) @ r.T
    corners = np.array([[sx, sy, -1.0] for sx in (-1, 1) for sy in (-1, 1)]) * half + cg
    kz = mass * (2 * np.pi * mount_hz) ** 2 / 4.0
    kk = kz * rng.uniform(0.4, 1.0, (4, 3))
    kk[:, 2] = kz * rng.uniform(0.8, 1.2, 4)
    if free:
        kk = kk * 1e-4
    box = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half + cg
    sel = rng.permutation(8)[:n_sensors] if n_sensors <= 8 else np.arange(n_sensors) % 8
    sensors = box[sel] + rng.uniform(-0.05, 0.05, (n_sensors, 3)) * size_scale
    sd = np.eye(3)[np.arange(n_sensors) % 3]
    sd = sd + rng.uniform(-0.2, 0.2, sd.shape)
    sd /= np.linalg.norm(sd, axis=1, keepdims=True)
    lo, hi = sensors.min(axis=0), sensors.max(axis=0)
    three = np.array([[hi[0], hi[1], hi[2]], [lo[0], hi[1], lo[2]], [hi[0], lo[1], lo[2]]])
    rpts = np.vstack([three, three])[:n_refs]
    rdirs = np.vstack([np.eye(3), np.eye(3)[[1, 2, 0]]])[:n_refs]
    return Rig(mass, cg, inertia, corners, kk, zeta, sensors, sd, rpts, rdirs)


def add_elastic(rig: Rig, rng: np.random.Generator, hz: float, zeta: float = 0.01) -> None:
    """An elastic mode of ``hz`` (unit modal mass per the body mass), random shape."""
    s = 1.0 / np.sqrt(rig.mass)
    rig.elastic.append((hz, zeta, s * rng.standard_normal(len(rig.sensors)), s * rng.standard_normal(len(rig.refs))))


def truth_errors(rig: Rig, mass: float, cg: Array, inertia: Array) -> tuple[float, float, float]:
    """Mass (relative), CG (over the body's largest half-size), inertia (largest element over the trace/3)."""
    size = float(np.max(np.abs(rig.sensors - rig.cg)))
    scale = float(np.trace(rig.inertia)) / 3.0
    return (
        abs(mass - rig.mass) / rig.mass,
        float(np.linalg.norm(np.asarray(cg) - rig.cg)) / size,
        float(np.max(np.abs(np.asarray(inertia) - rig.inertia))) / scale,
    )
