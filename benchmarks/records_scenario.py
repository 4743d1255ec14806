"""The body, layouts and impacts the impact-record benchmarks share (not a benchmark).

A 40 kg body (SI units) on four mounts whose six modes are 8.0, 10.3, 14.95,
15.27 (2.1 % above the previous), 21.6 and 26.1 Hz, damping ratios 0.31 % to
6.9 %, complex (damping not proportional to stiffness). The same body as
``tests/core/test_timedomain.py``.
"""

from __future__ import annotations

import numpy as np

from rigidid.core.simulate import Body, Mount

MASS = 40.0
CG = np.array([0.05, -0.03, 0.12])
INERTIA = np.array([[1.6, 0.08, -0.05], [0.08, 2.1, 0.04], [-0.05, 0.04, 2.9]])
BODY = Body(
    MASS,
    CG,
    INERTIA,
    (
        Mount.from_values([0.35, 0.25, -0.1], [29000.0, 5000.0, 73100.0], [2.0, 2.0, 2.0]),
        Mount.from_values(
            [-0.3, 0.22, -0.12], [5800.0, 30000.0, 101300.0], [[2.0, 0.0, 0.0], [0.0, 2.7, -0.5], [0.0, -0.5, 2.4]]
        ),
        Mount.from_values(
            [-0.32, -0.24, -0.1],
            [6900.0, 23100.0, 67300.0],
            [[56.9, -44.4, -87.5], [-44.4, 37.8, 70.7], [-87.5, 70.7, 141.4]],
        ),
        Mount.from_values(
            [0.33, -0.2, -0.08],
            [250700.0, 109900.0, 127100.0],
            [[14.9, -17.1, -20.1], [-17.1, 24.6, 26.6], [-20.1, 26.6, 33.3]],
        ),
    ),
)
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]


def layout(n_sensors: int) -> tuple[np.ndarray, np.ndarray]:
    """Sensor positions (m) and unit directions: the 8 box corners, then seeded random points on the box."""
    quadrants = ((0.3, 0.2), (-0.3, 0.2), (-0.3, -0.2), (0.3, -0.2))
    corners = np.array([[x, y, z] for z in (0.15, -0.15) for x, y in quadrants])
    axes = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.6, 0.8, 0]], float)
    rng = np.random.default_rng(5)
    extra = n_sensors - 8
    pos = np.vstack([corners, rng.uniform(-1.0, 1.0, (max(extra, 0), 3)) * [0.3, 0.2, 0.15]])[:n_sensors]
    d = np.vstack([axes, rng.standard_normal((max(extra, 0), 3))])[:n_sensors]
    return pos, d / np.linalg.norm(d, axis=1)[:, None]
