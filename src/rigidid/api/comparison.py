"""Comparing a result JSON with a reference (``rigidid compare``): reading the two files."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rigidid.compare import DEFAULT_RTOL, Comparison, compare_results
from rigidid.errors import InputError

__all__ = ["compare"]


def _read_result(path: Path) -> dict[str, Any]:
    """A result JSON of ``rigidid identify``, checked to be one."""
    from rigidid.limits import MAX_JSON_BYTES

    src = str(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(MAX_JSON_BYTES + 1)
    except OSError as exc:
        raise InputError(exc.strerror or str(exc), source=src) from None
    if len(raw) > MAX_JSON_BYTES:
        raise InputError(f"larger than {MAX_JSON_BYTES} bytes", source=src)
    try:
        data = json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError:
        raise InputError("not UTF-8 text: not a result JSON", source=src) from None
    except json.JSONDecodeError as exc:
        raise InputError(f"invalid JSON: {exc.msg}", source=src, location=f"line {exc.lineno}") from None
    except RecursionError:
        raise InputError("nested too deeply to be a result JSON", source=src) from None
    if not isinstance(data, dict) or "center_of_gravity" not in data or not isinstance(data.get("units"), dict):
        raise InputError(
            "not a result JSON of `rigidid identify` (no center_of_gravity and units); "
            "write one with `rigidid identify ... --json FILE`",
            source=src,
        )
    return data


def compare(
    result: str | os.PathLike[str],
    reference: str | os.PathLike[str],
    *,
    rtol: float | Mapping[str, float] = DEFAULT_RTOL,
    sigma: float = 0.0,
) -> Comparison:
    """What ``rigidid compare RESULT REFERENCE`` does: two result JSON files compared figure by figure.

    Parameters
    ----------
    result, reference : path-like
        Result JSONs (``rigidid identify --json``, any route).
    rtol, sigma
        As for :func:`rigidid.compare.compare_results`.

    Returns
    -------
    Comparison

    Raises
    ------
    InputError
        A file that cannot be read, is not a result JSON, or is in other units than the other.

    Examples
    --------
    >>> from rigidid.api import compare
    >>> comparison = compare("result.json", "reference.json", rtol=1e-3, sigma=3)  # doctest: +SKIP
    >>> [figure.name for figure in comparison.regressions]  # doctest: +SKIP
    """
    a, b = _read_result(Path(result)), _read_result(Path(reference))
    return compare_results(a, b, rtol=rtol, sigma=sigma, names=(str(result), str(reference)))
