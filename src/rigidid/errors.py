"""Exceptions and warning categories of rigidid.

Every error rigidid raises on purpose is a :class:`RigididError`. The concrete
classes also derive from :class:`ValueError`, so code that already catches
``ValueError`` keeps working. The command line catches :class:`RigididError`
only at its top level and turns it into one line on standard error.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from dataclasses import dataclass

__all__ = [
    "DampingUnitWarning",
    "ElasticModeWarning",
    "FrfMisfitWarning",
    "IdentificationError",
    "IllConditionedWarning",
    "InputError",
    "NonSensorColumnWarning",
    "Notice",
    "PhysicalPlausibilityWarning",
    "RefinementWarning",
    "RigididError",
    "RigididWarning",
    "SensorFitWarning",
    "emit",
]


class RigididError(Exception):
    """Root of every error raised by rigidid."""


class InputError(RigididError, ValueError):
    """A file, argument or array that rigidid cannot use.

    Parameters
    ----------
    message : str
        What is wrong, in words a user understands.
    source : str, optional
        The file (or argument) the problem is in.
    location : str, optional
        Where in that source: ``"row 5"``, ``"sensors.3.direction"``...
    """

    def __init__(self, message: str, *, source: str | None = None, location: str | None = None):
        self.message = message
        self.source = source
        self.location = location
        super().__init__(str(self))

    def __str__(self) -> str:
        parts = [p for p in (self.source, self.location) if p]
        return ": ".join([*parts, self.message])


class IdentificationError(RigididError, ValueError):
    """The data are valid but do not determine a rigid body (singular, inconsistent...)."""


class RigididWarning(UserWarning):
    """Root category of rigidid's warnings."""


class PhysicalPlausibilityWarning(RigididWarning):
    """An identified quantity is physically impossible (e.g. inertia not positive definite)."""


class IllConditionedWarning(RigididWarning):
    """A step of the computation is badly conditioned; results may be inaccurate."""


@dataclass(frozen=True)
class Notice:
    """A warning collected while computing, emitted once the result (or the error) is known.

    Attributes
    ----------
    category : type of RigididWarning
        Its category.
    message : str
        The text.
    """

    category: type[RigididWarning]
    message: str


def emit(notices: Iterable[Notice], stacklevel: int = 3) -> None:
    """Issue collected notices as warnings (the caller's caller is named as their origin by default)."""
    for notice in notices:
        warnings.warn(notice.message, notice.category, stacklevel=stacklevel)
class SensorFitWarning(RigididWarning):
    """One sensor's readings fit rigid-body motion much worse than the others' (wrong position or direction?)."""


class DampingUnitWarning(RigididWarning):
    """Damping ratios that look like percentages (0.39 meant as 0.39 %)."""


class NonSensorColumnWarning(RigididWarning):
    """A record has columns that are not sensors (force, trigger...): they are left out."""


class ElasticModeWarning(RigididWarning):
    """A mode estimated from the records looks elastic (its shape fits rigid-body motion far worse than the others')."""


class FrfMisfitWarning(RigididWarning):
    """An FRF route's model misfits the FRFs by more than their noise explains (its answer may be off)."""


class RefinementWarning(RigididWarning):
    """The output-error refinement on the records did not reach a good fit; the structured answer is kept."""
