"""The mass-line band of a free-free test whose FRFs show no resonance: the plateau.

A body hung on soft cords and measured above its suspension modes has an
accelerance that tends to the constant ``T M^-1 T_f^T`` (the mass line, eq. (1)
of the mass-line notes): no rigid-body peak lies in the band, so the automatic
band of :func:`rigidid.core.massline.auto_band` (3x the highest rigid-body
peak to half the first elastic one) has nothing to start from. This module
finds that band from the FRFs alone.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from rigidid.core.frfmodes import peak_split, summed_power

__all__ = ["MIN_PLATEAU_LINES", "PLATEAU_SLOPE", "plateau_band", "top_slope"]

MIN_PLATEAU_LINES = 10
"""Fewest lines a plateau band holds."""

PLATEAU_SLOPE = 0.5
"""Largest log-log slope of the summed FRF magnitude over the band still called a plateau (a
stiffness line below the rigid-body modes has slope 2, a mass line 0)."""


def plateau_band(frequencies: ArrayLike, frf: ArrayLike) -> tuple[float, float] | None:
    """The band where the FRFs are flat below their first peak (free-free, above the suspension modes), or None.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz, ascending, positive.
    frf : array_like of complex, shape (p, q, f)
        Accelerance.

    Returns
    -------
    (float, float) or None
        From the first line to the last one (without a peak in the summed
        magnitude ``sum |H|^2``, a peak standing a factor 2 above both
        neighbouring valleys) or to half the first peak (an elastic mode:
        the band is kept clear of it), when the magnitude's log-log slope
        there (least squares) is within :data:`PLATEAU_SLOPE` of zero and the
        band holds :data:`MIN_PLATEAU_LINES` lines; None otherwise (below
        the first peak the FRFs still rise or fall: a rigid-body peak on
        mounts, or a band across the suspension modes).

    Notes
    -----
    The peak test is the one of the automatic band
    (:func:`rigidid.core.frfmodes.peak_split`: prominence ``log 2`` of
    ``log sum |H|^2``), so a file it refuses for "no resonance peak" is the
    file this function looks at.
    """
    f = np.asarray(frequencies, dtype=float).reshape(-1)
    h = np.asarray(frf)
    s = summed_power(h)
    if f.size < 3 or s.shape != f.shape:
        return None
    peaks, _ = peak_split(f, h)
    hi = float(f[-1]) if peaks.size == 0 else 0.5 * float(peaks[0])  # kept clear of the first (elastic) peak
    sel = f <= hi
    if np.count_nonzero(sel) < MIN_PLATEAU_LINES:
        return None
    x = np.log(f[sel])
    design = np.column_stack([np.ones_like(x), x])
    slope = np.linalg.lstsq(design, 0.5 * np.log(s[sel]), rcond=None)[0][1]  # of |H|, not |H|^2
    if abs(slope) > PLATEAU_SLOPE:
        return None
    return float(f[0]), float(f[sel][-1])


def top_slope(frequencies: ArrayLike, frf: ArrayLike, band: tuple[float, float], fraction: float = 0.2) -> float:
    """Log-log slope of the summed FRF magnitude over the top `fraction` of `band`.

    Above the rigid-body modes the accelerance tends to the flat mass line
    (slope 0; a mode below the band makes it fall towards it); an elastic mode
    just above the band makes it rise (slope ``2 r^2 / (1 - r^2)`` at ``r = f /
    f_elastic``: 1 at ``r = 0.58``, 7.5 at ``r = 0.89``). The FRF routes model
    the modes above the band by a residual that such a near mode escapes.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz, ascending.
    frf : array_like of complex, shape (p, q, f)
        Accelerance.
    band : (float, float)
        The band a route used (Hz).
    fraction : float
        Part of the band, from its top, that the slope is fitted over.

    Returns
    -------
    float
        The slope of ``log |H|`` (root of the summed ``|H|^2``) over ``log f``;
        0 when fewer than 5 lines lie there.
    """
    f = np.asarray(frequencies, dtype=float).reshape(-1)
    s = summed_power(frf)
    lo, hi = float(band[0]), float(band[1])
    sel = (f >= hi - fraction * (hi - lo)) & (f <= hi)
    if np.count_nonzero(sel) < 5:
        return 0.0
    x = np.log(f[sel])
    design = np.column_stack([np.ones_like(x), x])
    return float(np.linalg.lstsq(design, 0.5 * np.log(s[sel]), rcond=None)[0][1])
