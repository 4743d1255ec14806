"""Limits that keep rigidid finite and bounded, checked at the boundary before any work.

Every limit is refused with an :class:`~rigidid.errors.InputError` naming the
option (or parameter) and the limit, so that nothing overflows, allocates
without bound, or runs for minutes before failing.
"""

from __future__ import annotations

import math

from rigidid.errors import InputError

__all__ = [
    "MAX_ARRAY_BYTES",
    "MAX_CSV_BYTES",
    "MAX_JSON_BYTES",
    "MAX_MAGNITUDE",
    "MAX_MODEL_ORDER",
    "MAX_MODES",
    "MAX_SEGMENTS",
    "MAX_UFF_BYTES",
    "check_count",
    "check_number",
    "check_record_size",
]

MAX_JSON_BYTES = 16 * 2**20
"""Largest layout.json / body.json read (bytes)."""
MAX_CSV_BYTES = 64 * 2**20
"""Largest modes.csv read (bytes)."""
MAX_UFF_BYTES = 1024 * 2**20
"""Largest universal file read (bytes)."""
MAX_ARRAY_BYTES = 1024 * 2**20
"""Largest array of simulated records (bytes, all records together)."""
MAX_MAGNITUDE = 1e100
"""Largest magnitude of a number given as an option: squares and products of it stay finite."""
MAX_MODES = 30
"""Most modes estimated from records."""
MAX_MODEL_ORDER = 1000
"""Highest model order of the stabilisation sweep."""
MAX_SEGMENTS = 1000
"""Most interleaved segments for data-driven intervals."""


def check_number(value: float | None, name: str, *, positive: bool = False, nonnegative: bool = False) -> None:
    """Refuse NaN, infinity, magnitudes above :data:`MAX_MAGNITUDE`, and (optionally) signs."""
    if value is None:
        return
    if not math.isfinite(value):
        raise InputError(f"must be a finite number, got {value}", source=name)
    if abs(value) > MAX_MAGNITUDE:
        raise InputError(f"must be at most {MAX_MAGNITUDE:g} in magnitude, got {value:g}", source=name)
    if positive and not value > 0:
        raise InputError(f"must be positive, got {value:g}", source=name)
    if nonnegative and not value >= 0:
        raise InputError(f"must be zero or positive, got {value:g}", source=name)


def check_count(value: int | None, name: str, *, low: int, high: int) -> None:
    """Refuse an integer outside ``[low, high]``."""
    if value is None:
        return
    if not low <= value <= high:
        raise InputError(f"must be from {low} to {high}, got {value}", source=name)


def check_record_size(
    sample_rate: float,
    seconds: float,
    channels: int,
    records: int,
    *,
    name: str = "sample_rate",
    advice: str = "lower the sample rate or the duration",
) -> None:
    """Refuse simulated records whose samples would exceed :data:`MAX_ARRAY_BYTES`.

    Parameters
    ----------
    sample_rate : float
        Samples per second.
    seconds : float
        Record length (s), pre-trigger included.
    channels, records : int
        Sensors per record and number of records.
    name : str
        What to blame (an option or parameter name).
    advice : str
        What to change, in the message's closing brackets.
    """
    samples = sample_rate * seconds
    need = samples * max(channels, 1) * max(records, 1) * 8.0 * 2  # the records and one working copy
    if not math.isfinite(need) or need > MAX_ARRAY_BYTES:
        raise InputError(
            f"{samples:.3g} samples x {channels} sensors x {records} records would need {need / 2**30:.3g} GiB; "
            f"the limit is {MAX_ARRAY_BYTES / 2**30:g} GiB ({advice})",
            source=name,
        )
