"""Matching the columns (or channels) of a record to the layout's sensor ids: one rule for every format."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rigidid.errors import InputError
from rigidid.io.dialect import column_key

__all__ = ["NON_SENSOR_PREFIXES", "RESERVED_FIELDS", "channel_names", "column", "match_columns", "row"]

RESERVED_FIELDS = frozenset({"time", "dt", "sample_rate", "data", "channels"})
"""Names of a binary record's arrays that are not channels (``.npz``, ``.mat``, ``.h5``)."""

NON_SENSOR_PREFIXES = ("force", "hammer", "trigger", "excitation", "tacho", "impact", "load_cell")
"""Column names (matched without case and unit suffix) that are not sensors and are left out."""


def _not_sensor_hint(name: str, skip_non_sensors: bool) -> str:
    """How to have a force or trigger channel left out, or a mistyped sensor id found."""
    key = column_key(name)
    if skip_non_sensors and any(p in key for p in NON_SENSOR_PREFIXES):
        return (
            "; a force or trigger channel is left out when its name starts with "
            f"{', '.join(NON_SENSOR_PREFIXES)}: rename it (e.g. 'hammer') or delete the column"
        )
    if skip_non_sensors:
        return (
            "; a sensor id of the layout, mistyped? (columns named like force, hammer, trigger... "
            "are left out; any other must be a sensor)"
        )
    return ""


def row(line: int) -> str:
    """Where a row is, for a message: ``"row 5"``."""
    return f"row {line}"


def column(name: str) -> str:
    """Where a column is, for a message: ``"column 'A+x'"``."""
    return f"column {name!r}"


def match_columns(
    names: Sequence[str], wanted: Sequence[str], src: str, where: str, *, skip_non_sensors: bool = False
) -> tuple[list[int], list[str]]:
    """Index in `names` of each of `wanted`, and the non-sensor names left out.

    Parameters
    ----------
    names : sequence of str
        The record's column (channel) names.
    wanted : sequence of str
        The layout's sensor ids, in layout order.
    src, where : str
        File and location for the messages.
    skip_non_sensors : bool
        Leave out columns named like a force, hammer, trigger... channel
        (:data:`NON_SENSOR_PREFIXES`) instead of refusing them.

    Raises
    ------
    InputError
        An unnamed or repeated column, a column that is no sensor, a sensor without a column.
    """
    seen: dict[str, int] = {}
    skipped: list[str] = []
    for k, name in enumerate(names):
        if not name:
            raise InputError("a column has no name", source=src, location=where)
        if name in seen or name in skipped:
            raise InputError(f"column {name!r} appears twice", source=src, location=f"{where}, {column(name)}")
        if name in wanted:
            seen[name] = k
        elif skip_non_sensors and column_key(name).startswith(NON_SENSOR_PREFIXES):
            skipped.append(name)
        else:
            raise InputError(
                f"column {name!r} is not a sensor of the layout" + _not_sensor_hint(name, skip_non_sensors),
                source=src,
                location=f"{where}, {column(name)}",
            )
    missing = [s for s in wanted if s not in seen]
    if missing:
        raise InputError(
            f"sensor {missing[0]!r} of the layout has no column"
            + (f" ({len(missing)} sensors missing)" if len(missing) > 1 else ""),
            source=src,
            location=where,
        )
    return [seen[s] for s in wanted], skipped


def column_order(names: Sequence[str] | None, count: int, wanted: Sequence[str], src: str, where: str) -> list[int]:
    """Index of each of `wanted` among a record's `count` sensor columns.

    Unnamed columns (`names` None) must be the layout's sensors in layout order,
    as many as it has; named ones are matched by :func:`match_columns`.

    Raises
    ------
    InputError
        Another number of unnamed columns, or what :func:`match_columns` refuses.
    """
    if names is None:
        if count != len(wanted):
            raise InputError(
                f"{count} sensor columns after time, the layout has {len(wanted)} sensors", source=src, location=where
            )
        return list(range(count))
    return match_columns(names, wanted, src, where)[0]


def channel_names(value: Any) -> list[str]:
    """Channel names as a file stores them: an array of strings or bytes, a MATLAB cell array or char matrix."""
    arr = np.asarray(value, dtype=object) if not isinstance(value, np.ndarray) else value
    if arr.dtype.kind in "SU" and arr.ndim == 2:  # MATLAB char matrix: one name per row
        return ["".join(str(c) for c in row).strip() for row in arr]
    out = []
    for item in np.ravel(arr):
        if isinstance(item, np.ndarray):  # MATLAB cell array element
            item = item.item() if item.size == 1 else "".join(str(c) for c in np.ravel(item))
        if isinstance(item, bytes):
            item = item.decode("utf-8", errors="replace")
        out.append(str(item).strip())
    return out
