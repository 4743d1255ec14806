"""The checks every impact record passes, whatever its format: sensor ids, finite values, uniform time, decay.

Whole records (:func:`check_record`, what :func:`rigidid.io.records.read_record`
runs) and records read in blocks (:class:`TimeCheck`, :func:`check_decay`) are
checked with the same tolerances and say what is wrong in the same words,
naming the file and the row (line number, header = row 1) or column.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from rigidid.core.timedomain.stamps import token_resolution
from rigidid.errors import InputError
from rigidid.io.records.columns import column as _column
from rigidid.io.records.columns import row as _where

__all__ = [
    "DECAY_RATIO",
    "MIN_ROWS",
    "TIME_TOLERANCE",
    "TimeCheck",
    "check_decay",
    "check_record",
    "check_time",
    "layout_ids",
]

Array = NDArray[np.float64]

TIME_TOLERANCE = 0.01
"""Largest relative deviation of a time step from the mean sample interval.

The mean interval is ``(t_last - t_first) / (n - 1)``. When the time column is
written with few digits, the rounding (half a unit of the last digit of the
last row's time, twice) is allowed on top."""

DECAY_RATIO = 0.5
"""A record decays when, after its energy peak, the RMS of the last 10 % of the
samples is below this fraction of the RMS of the first 10 % (channels scaled
by their peak value, then summed)."""

MIN_ROWS = 16
"""Fewest data rows a record may have."""


def check_time(time: Array, line_of: Callable[[int], int], time_tokens: Callable[[], list[str]], src: str) -> float:
    n = time.shape[0]
    dt: float = float(time[-1] - time[0]) / (n - 1)
    if not dt > 0.0:
        raise InputError("time does not increase from the first to the last row", source=src, location=_column("time"))
    steps = np.diff(time)
    typical = float(np.median(steps))
    deviation = np.abs(steps - typical)
    tolerance = TIME_TOLERANCE * typical
    bad = np.flatnonzero(deviation > tolerance)
    if bad.size:
        # allow the rounding of the digits written (two roundings of half a unit each)
        resolution = min((token_resolution(token) for token in time_tokens()), default=0.0)
        if resolution > 0.5 * typical:
            raise InputError(
                f"time is written with too few digits (to {resolution:g} s) for the sample interval {typical:.6g} s",
                source=src,
                location=_column("time"),
            )
        allowed = max(tolerance, resolution) * (1.0 + 1e-6)
        bad = np.flatnonzero((deviation > allowed) & (np.abs(steps - dt) > allowed))
    if bad.size:
        k = int(bad[0])
        raise InputError(
            f"time step {steps[k]:.6g} s differs from the sample interval {typical:.6g} s by more than "
            f"{100 * TIME_TOLERANCE:g} % (time must be uniformly sampled and increasing)",
            source=src,
            location=_where(line_of(k + 1)),
        )
    return dt


def check_decay(data: Array, line_of: Callable[[int], int], src: str, energy: Array | None = None) -> Array:
    """Raise unless the record decays after its energy peak; return its ``channel_energy``."""
    from rigidid.core.timedomain.preprocess import channel_energy  # lazily: the core's time domain is not light

    if energy is None:
        energy = channel_energy(data)
    peak = int(np.argmax(energy))
    after = energy[peak:]
    k = after.shape[0] // 10
    if k < 2:
        raise InputError(
            f"the largest sample is at the end of the record ({after.shape[0]} samples follow it): no free decay",
            source=src,
            location=_where(line_of(peak)),
        )
    head = math.sqrt(float(np.mean(after[:k])))
    tail = math.sqrt(float(np.mean(after[-k:])))
    if not tail < DECAY_RATIO * head:
        first, last = line_of(data.shape[0] - k), line_of(data.shape[0] - 1)
        raise InputError(
            f"the signal does not decay: after the peak (row {line_of(peak)}) the RMS of the last 10 % of the "
            f"samples is {100 * tail / head:.0f} % of that of the first 10 % (must be below {100 * DECAY_RATIO:g} %)",
            source=src,
            location=f"rows {first}-{last}",
        )
    return energy


def layout_ids(sensor_ids: Sequence[str], src: str) -> list[str]:
    """The layout's sensor ids as strings, the column names a record must have; refused when one repeats."""
    wanted = [str(s) for s in sensor_ids]
    if len(set(wanted)) != len(wanted):
        raise InputError("the layout has a sensor id twice", source=src)
    return wanted


def check_record(
    data: Array,
    time: Array,
    line_of: Callable[[int], int],
    time_tokens: Callable[[], list[str]],
    src: str,
    wanted: list[str],
) -> tuple[Array, float]:
    """The checks every record passes whatever its format: finite, uniform time, no dead channel, decay."""
    if not np.isfinite(time).all() or not np.isfinite(data).all():
        finite = np.isfinite(data)
        bad_rows = np.flatnonzero(~np.isfinite(time) | ~finite.all(axis=1))
        k = int(bad_rows[0])
        name = "time" if not np.isfinite(time[k]) else wanted[int(np.argmin(finite[k]))]
        raise InputError("a value is NaN or infinite", source=src, location=f"{_where(line_of(k))}, {_column(name)}")
    dt = check_time(time, line_of, time_tokens, src)
    peaks = np.zeros(data.shape[1])
    step = max(1, (1 << 16) // max(1, data.shape[1]))
    for start in range(0, data.shape[0], step):
        np.maximum(peaks, np.max(np.abs(data[start : start + step]), axis=0), out=peaks)
    for i, name in enumerate(wanted):
        if not peaks[i] > 0.0:
            raise InputError(f"sensor {name!r} reads zero in every row", source=src, location=_column(name))
    check_decay(data, line_of, src)
    return data, dt


class TimeCheck:
    """The uniform-time check of :func:`check_time`, block by block.

    Time is checked against the median step of the first block (:func:`check_time`
    takes the median of all steps: the two differ only on records whose step
    changes), with the same allowance for the digits written and the same
    messages.

    Parameters
    ----------
    line_of : callable
        ``line_of(rows)(k)``: the file's line of data row `k` once `rows` rows are read.
    time_tokens : callable
        The time column's values as written (for the digits' rounding).
    src : str
        The file, for messages.
    """

    def __init__(
        self, line_of: Callable[[int], Callable[[int], int]], time_tokens: Callable[[], list[str]], src: str
    ) -> None:
        self.line_of, self.time_tokens, self.src = line_of, time_tokens, src
        self.first = math.nan
        self.last = math.nan
        self.rows = 0
        self.typical = math.nan
        self.allowed: float | None = None

    def add(self, t: Array) -> None:
        if t.shape[0] == 0:
            return
        if self.rows == 0:
            self.first = float(t[0])
            steps = np.diff(t)
        else:
            steps = np.diff(np.concatenate([[self.last], t]))
        if math.isnan(self.typical) and steps.size:
            self.typical = float(np.median(steps))
            if not self.typical > 0.0:
                raise InputError(
                    "time does not increase from the first to the last row", source=self.src, location=_column("time")
                )
        if steps.size:
            deviation = np.abs(steps - self.typical)
            tolerance = TIME_TOLERANCE * self.typical
            bad = np.flatnonzero(deviation > (tolerance if self.allowed is None else self.allowed))
            if bad.size and self.allowed is None:
                resolution = min((token_resolution(token) for token in self.time_tokens()), default=0.0)
                if resolution > 0.5 * self.typical:
                    raise InputError(
                        f"time is written with too few digits (to {resolution:g} s) for the sample interval "
                        f"{self.typical:.6g} s",
                        source=self.src,
                        location=_column("time"),
                    )
                self.allowed = max(tolerance, resolution) * (1.0 + 1e-6)
                bad = np.flatnonzero(deviation > self.allowed)
            if bad.size:
                k = int(bad[0])
                row = self.rows + k - (1 if self.rows else 0) + 1  # data row (from 0) of the step's end
                raise InputError(
                    f"time step {steps[k]:.6g} s differs from the sample interval {self.typical:.6g} s by more than "
                    f"{100 * TIME_TOLERANCE:g} % (time must be uniformly sampled and increasing)",
                    source=self.src,
                    location=_where(self.line_of(self.rows + t.shape[0])(row)),
                )
        self.last = float(t[-1])
        self.rows += t.shape[0]

    def dt(self) -> float:
        dt = (self.last - self.first) / (self.rows - 1)
        if not dt > 0.0:
            raise InputError(
                "time does not increase from the first to the last row", source=self.src, location=_column("time")
            )
        return dt
