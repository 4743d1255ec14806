"""The pre-trigger's noise in the band the refit sees: each channel's level and each record's variance.

The refit (:mod:`rigidid.core.timedomain.refine`) fits decays decimated by its factor ``q``
(:func:`~rigidid.core.timedomain.preprocess.decimate`), so the noise it weights by and tests against
(:mod:`rigidid.core.timedomain.acceptance`) is the noise in that band. Taking it from the raw
pre-trigger's variance times the decimation filter's noise gain ``sum h^2`` holds for white noise only:
behind an anti-alias filter the raw samples hold less power near their Nyquist frequency than white noise
of the same level in the band, and the refit's residual then reads about 1.2 times that level
(an 8th-order Butterworth at 0.4 fs, ``benchmarks/chain_matrix.py``'s ``aa`` cell).

Here the pre-trigger is decimated as the decays are, after its mean and the mains hum found
(:mod:`rigidid.core.timedomain.hum`, least squares on the raw samples) are taken out, and its variance is
measured there. The decimated samples of white noise are slightly correlated (the filter's taps,
:func:`~rigidid.core.timedomain.intervals.noise_correlation`): a record's variance has
``(m - 1 - r) / (1 + 2 sum rho_k^2)`` degrees of freedom, ``m`` the decimated samples and ``r`` the lines
taken out. The readers keep at most :data:`PRE_HELD` rows of each pre-trigger (its first) for this.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.linalg import numerical_rank
from rigidid.core.timedomain.hum import hum_columns
from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH, decimate

__all__ = ["PRE_HELD", "BandNoise", "band_noise"]

Array = NDArray[np.float64]

PRE_HELD = 1 << 15
"""Rows of each record's pre-trigger held for its noise in the fit's band (the first ones)."""

_SILENT = 1e-20
"""A band variance below this fraction of the raw pre-trigger's (the hum and the mean in) is rounding."""

_MIN_DOF = 8.0
"""Least degrees of freedom of every record's band variance (the acceptance test's own floor)."""


@dataclass(frozen=True)
class BandNoise:
    """The pre-trigger's noise in the fit's band (:func:`band_noise`).

    Attributes
    ----------
    sigma : ndarray, shape (p,)
        Each channel's noise level at the fit's rate, pooled over the records.
    variance : ndarray, shape (records, p)
        Each record's variance per channel at the fit's rate.
    dof : tuple of float
        Each record's white-equivalent degrees of freedom of `variance` (module notes).
    """

    sigma: Array
    variance: Array
    dof: tuple[float, ...]


def band_noise(held: Sequence[Array], dt: float, factor: int, frequencies: Sequence[float] = ()) -> BandNoise | None:
    """The noise of pre-trigger rows in the band of decays decimated by `factor` (module notes).

    Parameters
    ----------
    held : sequence of ndarray, shape (n_i, p)
        Per record, rows of its pre-trigger from its first (raw rate).
    dt : float
        The raw sample interval (s).
    factor : int
        The fit's decimation factor (1: none).
    frequencies : sequence of float
        The hum found (Hz): a cosine and a sine of each taken out with the mean.

    Returns
    -------
    BandNoise or None
        None when a record's pre-trigger is too short to give :data:`_MIN_DOF` degrees of freedom in the
        band, or a channel holds nothing but the lines (:data:`_SILENT`).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> noise = band_noise([rng.standard_normal((4000, 2)) for _ in range(3)], 1e-3, 4)
    >>> from rigidid.core.timedomain.preprocess import fir_taps
    >>> bool(np.allclose(noise.sigma, np.sqrt(np.sum(fir_taps(4) ** 2)), rtol=0.1))
    True
    """
    from rigidid.core.timedomain.intervals import noise_correlation

    rho = noise_correlation(factor)
    inflation = 1.0 + 2.0 * float(np.sum(rho[1:] ** 2))
    squares, counts, raw = [], [], 0.0
    for x in held:
        n = x.shape[0]
        m = n if factor <= 1 else n // factor - 2 * FIR_HALF_LENGTH - 1  # the decimated samples
        if m < _MIN_DOF * inflation + 2 * len(frequencies) + 1:
            return None
        basis = np.column_stack([np.ones(n), hum_columns(np.arange(n, dtype=float) * dt, 1.0, frequencies, 1)[:, 0, :]])
        coef, _, _, s = np.linalg.lstsq(basis, x, rcond=None)
        r = x - basis @ coef
        raw = raw + ((x - x.mean(axis=0)) ** 2).sum(axis=0) / (n * len(held))
        z = decimate(r, factor) if factor > 1 else r
        z = z - z.mean(axis=0)
        squares.append((z**2).sum(axis=0))
        counts.append(z.shape[0] - int(numerical_rank(s, n)))
    total = np.sum(squares, axis=0) / sum(counts)
    if not np.all(total > _SILENT * raw):  # nothing but the lines (and rounding): noise-free records
        return None
    variance = np.array([m2 / c for m2, c in zip(squares, counts, strict=True)])
    return BandNoise(np.sqrt(total), variance, tuple(c / inflation for c in counts))
