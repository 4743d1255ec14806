"""The body, layouts and impacts the impact-record benchmarks share (not a benchmark).

A 40 kg body (SI units) on four mounts whose six modes are 8.0, 10.3, 14.95,
15.27 (2.1 % above the previous), 21.6 and 26.1 Hz, damping ratios 0.31 % to
6.9 %, complex (damping not proportional to stiffness): ``samples/four-mounts``,
which ``tests/core/test_timedomain.py`` uses too.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rigidid.api import body_from_file
from rigidid.io.files import layout_arrays, load_body, load_layout

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "four-mounts"
BODY = body_from_file(load_body(SAMPLE / "body.json"))
MASS, CG, INERTIA = BODY.mass, BODY.center_of_gravity, BODY.inertia_tensor
_, _POSITIONS, _DIRECTIONS = layout_arrays(load_layout(SAMPLE / "layout.json"))
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]


SIX_OF_EIGHT = (0, 2, 3, 4, 6, 7)
"""The six corner sensors whose sensor matrix is best conditioned (ratio of singular values 0.38;
the first six corners are rank 5: they cannot tell a rigid body's six motions apart)."""


def layout(n_sensors: int) -> tuple[np.ndarray, np.ndarray]:
    """Sensor positions (m) and unit directions: the sample's 8 box corners, then seeded random points on the box.

    Six sensors: :data:`SIX_OF_EIGHT` of the corners."""
    corners, axes = _POSITIONS, _DIRECTIONS
    if n_sensors == 6:
        return corners[list(SIX_OF_EIGHT)], axes[list(SIX_OF_EIGHT)]
    rng = np.random.default_rng(5)
    extra = n_sensors - 8
    pos = np.vstack([corners, rng.uniform(-1.0, 1.0, (max(extra, 0), 3)) * [0.3, 0.2, 0.15]])[:n_sensors]
    d = np.vstack([axes, rng.standard_normal((max(extra, 0), 3))])[:n_sensors]
    return pos, d / np.linalg.norm(d, axis=1)[:, None]
