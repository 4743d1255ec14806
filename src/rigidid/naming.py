"""Sensors named by their ids in messages that number them (``sensor 3`` -> ``sensor 'A+z'``)."""

from __future__ import annotations

import re
from collections.abc import Sequence

__all__ = ["sensors_by_id"]

_NUMBERED = re.compile(r"\b(sensors?) (\d+(?:, \d+)*(?: and \d+)?)\b")


def sensors_by_id(message: str, ids: Sequence[str]) -> str:
    """Replace ``sensor 3`` and ``sensors 1, 2 and 4`` (numbered from 1 in layout order) by quoted ids.

    Parameters
    ----------
    message : str
        Text from :mod:`rigidid.core.plan`, which numbers sensors from 1.
    ids : sequence of str
        The layout's sensor ids, in layout order.

    Returns
    -------
    str
        The message with every such number that is a valid sensor number
        replaced by ``'id'``; other text unchanged.
    """

    def swap(match: re.Match[str]) -> str:
        numbers = [int(n) for n in re.findall(r"\d+", match.group(2))]
        if not all(1 <= n <= len(ids) for n in numbers):
            return match.group(0)
        names = [repr(str(ids[n - 1])) for n in numbers]
        listed = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
        return f"{match.group(1)} {listed}"

    return _NUMBERED.sub(swap, message)
