"""Units an engineer reads: stiffness and damping in force units.

rigidid computes in the layout's own units: lengths in ``units.length``, masses
in ``units.mass``, time in seconds. A support stiffness then comes out in
``mass/s^2`` (translations), which is a force per length only in coherent unit
systems (kg with m). For everything else this module gives the factor that
turns the result into a force unit per length, and the unit strings to print.

The whole 6x6 stiffness (or damping) matrix at the CG converts with ONE factor:
its translation block is ``mass/s^2 = (mass length/s^2)/length``, its coupling
blocks ``mass length/s^2`` (force per radian, or moment per length) and its
rotation block ``mass length^2/s^2`` (moment per radian); in every block the
only change is ``mass length/s^2 -> force``. So::

    K [force, length] = factor * K [mass, length, s],
    factor = (kg per mass unit) * (m per length unit) / (N per force unit)

e.g. lb, in and lbf: ``0.45359237 * 0.0254 / 4.4482216152605 = 1/386.0886``.

Pure Python: no numpy, rich or typer here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = [
    "FORCE_UNITS",
    "G0",
    "KG_PER_MASS",
    "LBF",
    "M_PER_LENGTH",
    "N_PER_FORCE",
    "ForceUnits",
    "default_force_unit",
    "force_factor",
    "force_units",
    "rate_units",
]

G0 = 9.80665
"""Standard gravity (m/s^2), exact by definition."""

LB = 0.45359237
"""One avoirdupois pound in kg, exact by definition."""

LBF = LB * G0
"""One pound-force in N (4.4482216152605)."""

M_PER_LENGTH: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048}
"""Metres per length unit of ``layout.json``."""

KG_PER_MASS: dict[str, float] = {
    "kg": 1.0,
    "g": 0.001,
    "t": 1000.0,
    "lb": LB,
    "slug": LBF / 0.3048,  # 1 lbf s^2/ft = 14.5939029372 kg
}
"""Kilograms per mass unit of ``layout.json``."""

N_PER_FORCE: dict[str, float] = {"N": 1.0, "kN": 1000.0, "lbf": LBF}
"""Newtons per force unit."""

FORCE_UNITS: tuple[str, ...] = tuple(N_PER_FORCE)
"""The force units ``--force-unit`` accepts."""

_IMPERIAL_MASS = ("lb", "slug")


def default_force_unit(mass: str) -> str:
    """``lbf`` for pound and slug masses, ``N`` for kg, g and t."""
    return "lbf" if mass in _IMPERIAL_MASS else "N"


def force_factor(length: str, mass: str, force: str) -> float:
    """Factor from ``mass length / s^2`` to `force`: multiply a stiffness or damping matrix by it.

    Parameters
    ----------
    length : str
        Length unit of the layout (``m``, ``cm``, ``mm``, ``in``, ``ft``).
    mass : str
        Mass unit of the layout (``kg``, ``g``, ``t``, ``lb``, ``slug``).
    force : str
        ``N``, ``kN`` or ``lbf``.

    Returns
    -------
    float
        ``kg_per_mass * m_per_length / N_per_force``.

    Raises
    ------
    ValueError
        An unknown unit name.
    """
    for name, table in (("length", M_PER_LENGTH), ("mass", KG_PER_MASS), ("force", N_PER_FORCE)):
        value = {"length": length, "mass": mass, "force": force}[name]
        if value not in table:
            raise ValueError(f"unknown {name} unit {value!r}; choose one of {', '.join(table)}")
    return KG_PER_MASS[mass] * M_PER_LENGTH[length] / N_PER_FORCE[force]


@dataclass(frozen=True)
class ForceUnits:
    """Unit strings of a 6x6 stiffness or damping matrix in force units.

    Attributes
    ----------
    force : str
        ``N``, ``kN`` or ``lbf``.
    length : str
        The layout's length unit.
    factor : float
        See :func:`force_factor`.
    stiffness : dict of str
        ``translation`` (force/length), ``coupling`` (force/rad in the rows of
        translations, equal to moment/length in the rows of rotations) and
        ``rotation`` (force length/rad).
    damping : dict of str
        The same with an extra ``s``.
    """

    force: str
    length: str
    factor: float
    stiffness: dict[str, str]
    damping: dict[str, str]


def force_units(length: str, mass: str, force: str | None = None) -> ForceUnits:
    """The factor and unit strings for stiffness and damping in force units.

    Parameters
    ----------
    length, mass : str
        Units of the layout.
    force : str, optional
        ``N``, ``kN`` or ``lbf``; default :func:`default_force_unit` of `mass`.

    Returns
    -------
    ForceUnits
    """
    f = default_force_unit(mass) if force is None else force
    factor = force_factor(length, mass, f)
    stiffness = {"translation": f"{f}/{length}", "coupling": f"{f}/rad", "rotation": f"{f} {length}/rad"}
    damping = {
        "translation": f"{f} s/{length}",
        "coupling": f"{f} s/rad",
        "rotation": f"{f} {length} s/rad",
    }
    return ForceUnits(f, length, factor, stiffness, damping)


def check_same_units(given: Any, layout: Any, *, source: str | None, location: str = "units") -> None:
    """Refuse a file whose length and mass units differ from the layout's: the one unit check.

    Parameters
    ----------
    given, layout
        The units of the file and of the layout: a mapping with ``"length"`` and ``"mass"`` or an object with
        those attributes (the files' pydantic ``units`` blocks).
    source : str or None
        The file to name in the error.
    location : str
        Its field (or dataset) that holds the units.

    Raises
    ------
    InputError
        When the units differ.
    """
    from rigidid.errors import InputError

    def pair(units: Any) -> tuple[str, str]:
        if isinstance(units, Mapping):
            return str(units["length"]), str(units["mass"])
        return str(units.length), str(units.mass)

    (gl, gm), (ll, lm) = pair(given), pair(layout)
    if (gl, gm) != (ll, lm):
        raise InputError(
            f"units ({gl}, {gm}) differ from the layout's units ({ll}, {lm})", source=source, location=location
        )


def rate_units(length: str, mass: str, force: str | None = None, *, per_mass: bool = False) -> tuple[float, str, str]:
    """Factor and units of mount rates: from ``mass/s^2`` and ``mass/s`` to ``N/mm`` and ``N s/mm``.

    Parameters
    ----------
    length, mass : str
        Units of the layout.
    force : str, optional
        ``N``, ``kN`` or ``lbf`` (default :func:`default_force_unit`).
    per_mass : bool
        Rates per unit mass (no mass known): factor 1, units ``1/s^2`` and ``1/s``.

    Returns
    -------
    float, str, str
        The factor and the stiffness and damping units.
    """
    if per_mass:
        return 1.0, "1/s^2 (per mass)", "1/s (per mass)"
    fu = force_units(length, mass, force)
    return fu.factor, f"{fu.force}/{length}", f"{fu.force} s/{length}"
