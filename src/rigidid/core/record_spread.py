"""A data-driven uncertainty: re-identify on interleaved segments of the impact records.

Each record is split into ``K`` interleaved segments (samples ``j, j + K, j + 2K...``
for ``j = 0..K-1``). Every segment holds the whole free decay at ``1/K`` of the
sample rate, and its measurement noise is independent of the other segments'
(for noise that is white at the original rate). Identifying the body from each
segment gives ``K`` independent estimates; their spread, scaled to the full
data, is an interval that needs no assumed noise level.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.identify import Identification, identify
from rigidid.core.uncertainty import IntervalEstimate
from rigidid.errors import IdentificationError, InputError

__all__ = ["RecordSpread", "record_spread"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class RecordSpread:
    """Spread of the identification over interleaved segments of the records.

    Attributes
    ----------
    segments : int
        ``K``, the number of interleaved segments.
    used : int
        Segments whose modes and body could be identified.
    center_of_gravity, inertia, principal_moments, stiffness_diagonal : IntervalEstimateEstimate
        Estimate from all the data; ``std`` = standard deviation of the segment
        estimates divided by ``sqrt(K)``; ``low, high`` = estimate -/+
        Student's ``t(used - 1)`` 97.5 % quantile times ``std``. Inertia,
        moments and stiffness are per mass when `per_mass`.
    per_mass : bool
        True when no mass was given.
    """

    segments: int
    used: int
    center_of_gravity: IntervalEstimate
    inertia: IntervalEstimate
    principal_moments: IntervalEstimate
    stiffness_diagonal: IntervalEstimate
    per_mass: bool


def _quantities(result: Identification) -> dict[str, Array]:
    scale = 1.0 if result.mass is None else result.mass
    return {
        "center_of_gravity": np.asarray(result.center_of_gravity, dtype=float),
        "inertia": scale * np.asarray(result.inertia_per_mass, dtype=float),
        "principal_moments": scale * result.principal_moments_per_mass,
        "stiffness_diagonal": scale * np.diag(result.stiffness_per_mass),
    }


def record_spread(
    records: Sequence[ArrayLike],
    dt: float,
    positions: ArrayLike,
    directions: ArrayLike,
    full: Identification,
    *,
    segments: int = 4,
    mass: float | None = None,
    n_modes: int = 6,
    estimate_options: dict[str, Any] | None = None,
) -> RecordSpread:
    """Identify the body on each interleaved segment of the records and summarise the spread.

    Parameters
    ----------
    records : sequence of array_like, shape (n_k, p)
        The impact records (samples x sensors, layout order).
    dt : float
        Their sample interval (s).
    positions, directions : array_like, shape (p, 3)
        The layout.
    full : Identification
        The identification from all the data (the estimate the interval is about).
    segments : int
        ``K`` >= 2. The sample rate divided by ``K`` must stay above twice the
        highest mode (the segments are not low-pass filtered).
    mass : float, optional
        Mass of the body.
    n_modes : int
        Modes to estimate per segment (the six rigid-body modes are chosen as
        for the full data when there are more).
    estimate_options : dict, optional
        Passed to :func:`rigidid.core.timedomain.estimate_modes` (``method``,
        ``band``, ``max_order``).

    Returns
    -------
    RecordSpread

    Raises
    ------
    InputError
        For ``segments`` < 2.
    IdentificationError
        When fewer than two segments can be identified.

    Notes
    -----
    The scaling by ``1/sqrt(K)`` assumes the error of an estimate is dominated
    by measurement noise, so that its variance is inversely proportional to
    the amount of data. Errors common to all segments (sensor positions and
    directions, the modelling itself) do not show in this spread; combine it
    with the Monte Carlo intervals of :func:`~rigidid.core.uncertainty.propagate`
    for those. With few segments the interval is wide by construction
    (Student's t with ``K - 1`` degrees of freedom).
    """
    from scipy.special import stdtrit

    from rigidid.core.geometry import local_sensor_matrix, normalise_directions
    from rigidid.core.selection import select_rigid_modes
    from rigidid.core.timedomain import estimate_modes

    if segments < 2:
        raise InputError(f"need at least 2 segments, got {segments}", source="segments")
    pos = np.asarray(positions, dtype=float)
    dirs = normalise_directions(directions)
    t = local_sensor_matrix(pos, dirs)
    arrays = [np.asarray(r, dtype=float) for r in records]
    samples: dict[str, list[Array]] = {key: [] for key in _quantities(full)}
    for j in range(segments):
        try:
            est = estimate_modes(
                [a[j::segments] for a in arrays], dt * segments, n_modes=n_modes, **(estimate_options or {})
            )
            keep = select_rigid_modes(t, est.shapes) if est.shapes.shape[1] > 6 else np.arange(6)
            result = identify(
                pos, dirs, est.poles[keep], est.shapes[:, keep], mass=mass,
                method=full.method, warn=False,  # type: ignore[arg-type]
            )  # fmt: skip
        except IdentificationError:
            continue
        for key, value in _quantities(result).items():
            samples[key].append(value)
    used = len(samples["center_of_gravity"])
    if used < 2:
        raise IdentificationError(
            f"only {used} of {segments} record segments could be identified; use fewer segments (`segments`) "
            "or records sampled faster"
        )
    factor = float(stdtrit(used - 1, 0.975))
    intervals = {}
    for key, estimate in _quantities(full).items():
        std = np.std(np.stack(samples[key]), axis=0, ddof=1) / math.sqrt(segments)
        intervals[key] = IntervalEstimate(estimate, std, estimate - factor * std, estimate + factor * std)
    return RecordSpread(segments=segments, used=used, per_mass=full.mass is None, **intervals)
