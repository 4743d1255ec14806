"""Sample intervals of several records compared at the resolution of their time stamps.

A record's sample interval is measured from its time column as
``(t_last - t_first) / (n - 1)``. Written with a finite number of decimals,
each of the two stamps is rounded by up to half a unit of its last digit, so
the interval is known to ``resolution / (n - 1)`` only: two records of one
acquisition (same clock) written with 7 decimals differ by up to ``1e-7 /
(n - 1)`` s wherever their time columns start. Comparing intervals tighter
than that refuses records exported by ordinary acquisition software.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["RELATIVE_FLOOR", "common_interval", "different_intervals", "interval_uncertainty", "token_resolution"]

RELATIVE_FLOOR = 1e-9
"""Relative difference of two intervals always taken as equal (the rounding of
binary time stamps and of the interval's own arithmetic)."""


def token_resolution(token: str) -> float:
    """Unit of the last digit of a number as written (``"0.125"`` -> 0.001, ``"1.5e-3"`` -> 1e-4; 0: unreadable).

    Parameters
    ----------
    token : str
        A time stamp as written (decimal point ``.``).

    Returns
    -------
    float
        The resolution (s).
    """
    text = token.strip().lower()
    exponent = 0
    if "e" in text:
        text, _, exp = text.partition("e")
        try:
            exponent = int(exp)
        except ValueError:
            return 0.0
    decimals = len(text.partition(".")[2]) if "." in text else 0
    return float(10.0 ** (exponent - decimals))


def interval_uncertainty(resolution: float, rows: int, last_time: float = 0.0) -> float:
    """Largest error of ``(t_last - t_first) / (rows - 1)`` from time stamps rounded to `resolution`.

    Parameters
    ----------
    resolution : float
        Unit of the last digit written in the time column (s); 0 for binary
        time (then the float64 spacing at `last_time` is taken).
    rows : int
        Samples in the record (at least 2).
    last_time : float
        Largest time stamp's magnitude (s), for the binary spacing.

    Returns
    -------
    float
        Bound on the interval's error (s): two roundings of half a unit.
    """
    unit = max(float(resolution), float(np.spacing(abs(float(last_time)))))
    return unit / max(1, rows - 1)


def common_interval(dts: Sequence[float], uncertainties: Sequence[float] | None = None) -> tuple[float, bool]:
    """The one sample interval of several records, or the word that they differ.

    Parameters
    ----------
    dts : sequence of float
        Each record's measured interval (s).
    uncertainties : sequence of float, optional
        Each interval's error bound (:func:`interval_uncertainty`); None: all
        exact (only :data:`RELATIVE_FLOOR` allowed).

    Returns
    -------
    dt : float
        The interval of the record known most precisely (the first of equals).
    same : bool
        False when two intervals differ by more than their bounds together
        plus :data:`RELATIVE_FLOOR` of the largest.
    """
    values = np.asarray(dts, dtype=float)
    bounds = np.zeros_like(values) if uncertainties is None else np.asarray(uncertainties, dtype=float)
    best = int(np.argmin(bounds))
    # every pair's ranges [dt - u, dt + u] overlap (in 1-D: the highest lower end below the lowest upper end)
    gap = float(np.max(values - bounds) - np.min(values + bounds))
    same = bool(gap <= RELATIVE_FLOOR * float(np.max(values)))
    return float(values[best]), same


def different_intervals(dts: Sequence[float], uncertainties: Sequence[float]) -> str:
    """The one-line message for records whose intervals differ beyond their time stamps' resolution.

    Parameters
    ----------
    dts, uncertainties : sequence of float
        As :func:`common_interval` (s).

    Returns
    -------
    str
        Both extremes with the digits that tell them apart, and what the stamps resolve.
    """
    lo, hi = min(dts), max(dts)
    rel = (hi - lo) / hi if hi > 0 else 0.0
    digits = 6 if rel <= 0 else max(6, int(np.ceil(-np.log10(rel))) + 2)
    return (
        f"records have different sample intervals ({lo:.{digits}g} to {hi:.{digits}g} s, {rel:.2g} apart; "
        f"their time stamps resolve the interval to {max(uncertainties):.2g} s)"
    )
