"""Exceptions and warning categories of rigidid.

Every error rigidid raises on purpose is a :class:`RigididError`. The concrete
classes also derive from :class:`ValueError`, so code that already catches
``ValueError`` keeps working. The command line catches :class:`RigididError`
only at its top level and turns it into one line on standard error.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

__all__ = [
    "ChainWarning",
    "ClippedChannelWarning",
    "DampingUnitWarning",
    "DoubleHitWarning",
    "ElasticModeWarning",
    "FrfMisfitWarning",
    "HumWarning",
    "IdentificationError",
    "IllConditionedWarning",
    "InputError",
    "ModelMisfitWarning",
    "NonSensorColumnWarning",
    "Notice",
    "OffsetDriftWarning",
    "PhysicalPlausibilityWarning",
    "RefinementWarning",
    "RigididError",
    "RigididWarning",
    "SensorFitWarning",
    "UnitsWarning",
    "emit",
    "named_source",
    "noted",
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


class SensorCorrectionWarning(RigididWarning):
    """A sensor's gain, axis or position, estimated from the records' redundancy, is beyond 3x its tolerance."""


class DampingUnitWarning(RigididWarning):
    """Damping ratios that look like percentages (0.39 meant as 0.39 %)."""


class NonSensorColumnWarning(RigididWarning):
    """A record has columns that are not sensors (force, trigger...): they are left out."""


class ElasticModeWarning(RigididWarning):
    """A mode estimated from the records looks elastic (its shape fits rigid-body motion far worse than the others')."""


class ClippedChannelWarning(RigididWarning):
    """A record's channel is clipped (flat tops at its peak): it is left out of the fit, named."""


class OffsetDriftWarning(RigididWarning):
    """A record's channels carry a DC offset or a drift larger than their noise: taken out, named."""


class DoubleHitWarning(RigididWarning):
    """A record holds more than one hit: the free decay is taken after the last one, named."""


class FrfMisfitWarning(RigididWarning):
    """An FRF route's model misfits the FRFs by more than their noise explains (its answer may be off)."""


class FrfPeakBiasWarning(FrfMisfitWarning):
    """The FRFs fall short of (or exceed) the modal fit at the resonance peaks beyond their noise (an H1
    estimate's leakage or coherence bias): the answer may be off beyond its interval."""


class ElasticNearBandWarning(RigididWarning):
    """The FRFs rise towards the top of the band: an elastic mode just above it biases the FRF routes."""


class FrfRoutesDisagreeWarning(RigididWarning):
    """Two FRF routes (``--method auto``) give answers further apart than their 95 % intervals allow."""


class ChainWarning(RigididWarning):
    """A channel's delay or filter shows in the records: an unmodelled skew, or an implausible estimated delay."""


class HumWarning(RigididWarning):
    """Mains hum (50 or 60 Hz or a harmonic) found in the records: modelled in the refit, named."""


class RefinementWarning(RigididWarning):
    """The output-error refinement on the records did not reach a good fit; the structured answer is kept."""


@contextmanager
def named_source(source: str | None) -> Iterator[None]:
    """Give an error raised inside that names no file the input file(s) `source` it came from."""
    try:
        yield
    except InputError as exc:
        if source and exc.source in (None, "records"):
            raise InputError(exc.message, source=source, location=exc.location) from None
        raise
    except RigididError as exc:
        if source and not str(exc).startswith(source):
            raise type(exc)(f"{source}: {exc}") from None
        raise


@contextmanager
def noted(into: list[str], *categories: type[Warning]) -> Iterator[None]:
    """Pass on every warning raised inside; the texts of those of `categories` also go into `into`."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    for w in caught:
        if issubclass(w.category, categories) and str(w.message) not in into:
            into.append(str(w.message))
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


class ModelMisfitWarning(RigididWarning):
    """The rigid-body model explains the modes only to several times the stated noise (chi-square misfit)."""


class UnitsWarning(RigididWarning):
    """The data imply an implausible body (density, size): the units or the layout are probably wrong."""
