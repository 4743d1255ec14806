"""A result JSON against a reference: per figure, the difference and whether it is a regression.

What ``rigidid compare RESULT REFERENCE`` computes (docs/FORMATS.md, "rigidid compare").
Each figure of the reference result (mass, CG, inertia, principal moments, stiffness,
damping, per-mount rates) is matched entry by entry with the result. An entry passes
when its difference is within the tolerance, ``rtol`` times the figure's scale, or
within ``sigma`` combined standard errors, ``sqrt(se_result^2 + se_reference^2)`` from
the results' own interval keys; a figure passes when all its entries do. The scales
do not depend on the origin or the axes: the CG is measured against the body's largest
radius of gyration, a matrix against its largest entry (the stiffness and damping
matrices block by block: translation, rotation, and their geometric mean for the
coupling blocks, whose units are the mean's).

Nothing here reads, prints or writes: :func:`rigidid.api.compare` reads the two files,
:mod:`rigidid.compare_render` makes the table and the JUnit XML.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError

__all__ = [
    "FIGURE_GROUPS",
    "Comparison",
    "EntryCheck",
    "FigureCheck",
    "compare_results",
    "parse_tolerances",
]

FIGURE_GROUPS = ("mass", "center_of_gravity", "inertia", "principal_moments", "stiffness", "damping", "mounts")
"""The names ``rtol`` may give a tolerance of its own (``"stiffness=0.05"``)."""

DEFAULT_RTOL = 1e-6
"""Relative tolerance when none is given: a regression test of the same data."""

_DOF = ("x", "y", "z", "rx", "ry", "rz")
_AXES = ("x", "y", "z")
_UNCERTAINTY_KEYS = ("uncertainty_records_crb", "uncertainty", "uncertainty_records")
"""Where the standard errors come from, first found first: the record route's refit bound
(the figures' own), Monte Carlo draws, record segments."""


@dataclass(frozen=True)
class EntryCheck:
    """One entry of a figure (``x`` of the CG, ``[y,rz]`` of the stiffness...).

    Attributes
    ----------
    label : str
        Which entry.
    value, reference : float or None
        The result's and the reference's value (None: absent or null).
    tolerance : float
        The absolute tolerance, ``rtol`` times the figure's scale.
    sigma : float or None
        The combined standard error, None where neither result gives one.
    unit : str
        The unit of the entry, as the reference's ``quantity_units`` or ``force_units`` spell it.
    """

    label: str
    value: float | None
    reference: float | None
    tolerance: float
    sigma: float | None
    unit: str

    @property
    def difference(self) -> float | None:
        """Result minus reference (None when either is absent)."""
        if self.value is None or self.reference is None:
            return None
        return self.value - self.reference

    @property
    def within_tolerance(self) -> bool:
        """|difference| <= tolerance; an entry missing from the result is not."""
        d = self.difference
        return d is not None and abs(d) <= self.tolerance

    def within_sigma(self, k: float) -> bool | None:
        """|difference| <= k combined standard errors (None without a standard error)."""
        d = self.difference
        if self.sigma is None or d is None or k <= 0:
            return None
        return abs(d) <= k * self.sigma

    def passed(self, k: float) -> bool:
        """Within the tolerance or within `k` combined standard errors."""
        return self.within_tolerance or bool(self.within_sigma(k))

    def excess(self, k: float) -> float:
        """|difference| over the larger allowance (tolerance, k sigma); infinite when missing."""
        d = self.difference
        if d is None:
            return math.inf
        allowed = max(self.tolerance, k * self.sigma if self.sigma is not None and k > 0 else 0.0)
        if allowed == 0.0:
            return 0.0 if d == 0.0 else math.inf
        return abs(d) / allowed


@dataclass(frozen=True)
class FigureCheck:
    """One figure: its entries, its relative tolerance and where its standard errors came from."""

    name: str
    group: str
    rtol: float
    entries: tuple[EntryCheck, ...]
    sigma_from: str | None = None
    note: str | None = None

    def passed(self, k: float) -> bool:
        """Every entry passes."""
        return all(e.passed(k) for e in self.entries)

    def worst(self, k: float) -> EntryCheck:
        """The entry farthest outside (or least inside) its allowance."""
        return max(self.entries, key=lambda e: e.excess(k))


@dataclass(frozen=True)
class Comparison:
    """A result compared with a reference (:func:`compare_results`).

    Attributes
    ----------
    figures : tuple of FigureCheck
        One per figure the reference holds.
    sigma : float
        The number of combined standard errors an entry may differ by (0: none).
    result, reference : str
        Names of the two results (file names from :func:`rigidid.api.compare`).
    skipped : tuple of str
        Figures of the result the reference does not hold (not compared).
    """

    figures: tuple[FigureCheck, ...]
    sigma: float
    result: str = "result"
    reference: str = "reference"
    skipped: tuple[str, ...] = field(default_factory=tuple)

    @property
    def regressions(self) -> tuple[FigureCheck, ...]:
        """The figures that fail."""
        return tuple(f for f in self.figures if not f.passed(self.sigma))

    @property
    def passed(self) -> bool:
        """No figure fails."""
        return not self.regressions


def parse_tolerances(text: str) -> dict[str, float]:
    """``"1e-3"`` or ``"1e-3,stiffness=0.05,damping=0.2"`` as ``{"*": 1e-3, "stiffness": 0.05, ...}``.

    Raises
    ------
    InputError
        For an unknown figure name or a tolerance that is not a non-negative number
        (source ``rtol``).
    """
    out: dict[str, float] = {}
    for part in (p.strip() for p in text.split(",")):
        name, _, value = part.rpartition("=")
        name = name.strip() or "*"
        if name != "*" and name not in FIGURE_GROUPS:
            raise InputError(f"unknown figure {name!r}; one of {', '.join(FIGURE_GROUPS)}", source="rtol")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not number >= 0 or math.isinf(number):
            raise InputError(f"{part!r} is not a relative tolerance (a number >= 0, or FIGURE=NUMBER)", source="rtol")
        out[name] = number
    return out


def compare_results(
    result: Mapping[str, Any],
    reference: Mapping[str, Any],
    *,
    rtol: float | Mapping[str, float] = DEFAULT_RTOL,
    sigma: float = 0.0,
    names: tuple[str, str] = ("result", "reference"),
) -> Comparison:
    """Compare a result JSON (as a dict) with a reference, figure by figure.

    Parameters
    ----------
    result, reference : mapping
        Result JSONs of ``rigidid identify`` (any route: modes, records, FRF), as dicts.
    rtol : float or mapping
        Relative tolerance, one for all figures or per group of :data:`FIGURE_GROUPS`
        (key ``"*"`` for the rest; default :data:`DEFAULT_RTOL`). It multiplies each
        figure's scale (module docstring).
    sigma : float
        An entry also passes when it differs by at most `sigma` combined standard
        errors of the two results (0, the default: tolerance only).
    names : tuple of str
        How the comparison names the two results.

    Returns
    -------
    Comparison

    Raises
    ------
    InputError
        Results in different units, a negative `sigma` or `rtol`, or a figure of
        the wrong shape (source ``sigma``/``rtol`` or the file's name).
    """
    tolerances = _tolerances(rtol)
    if not (sigma >= 0 and math.isfinite(sigma)):
        raise InputError(f"must be a number >= 0, not {sigma}", source="sigma")
    for part in ("length", "mass"):
        ours, theirs = result["units"].get(part), reference["units"].get(part)
        if ours != theirs:
            raise InputError(
                f"the results are in different units ({part} {ours} against {theirs}); "
                "identify both with the same layout units",
                source=names[0],
            )
    figures: list[FigureCheck] = []
    skipped: list[str] = []
    for spec in _figure_specs(result, reference):
        name, group = spec[0], spec[1]
        if _get(reference, name) is None:
            if _get(result, name) is not None:
                skipped.append(name)
            continue
        figures.append(_check_figure(result, reference, spec, tolerances.get(group, tolerances["*"]), names))
    figures.extend(_mount_figures(result, reference, tolerances.get("mounts", tolerances["*"]), names))
    return Comparison(tuple(figures), float(sigma), names[0], names[1], tuple(skipped))


def _tolerances(rtol: float | Mapping[str, float]) -> dict[str, float]:
    given = {"*": float(rtol)} if isinstance(rtol, (int, float)) else dict(rtol)
    given.setdefault("*", DEFAULT_RTOL)
    for key, value in given.items():
        if key != "*" and key not in FIGURE_GROUPS:
            raise InputError(f"unknown figure {key!r}; one of {', '.join(FIGURE_GROUPS)}", source="rtol")
        if not (value >= 0 and math.isfinite(value)):
            raise InputError(f"must be a number >= 0, not {value}", source="rtol")
    return given


def _get(data: Mapping[str, Any], dotted: str) -> Any:
    value: Any = data
    for part in dotted.split("."):
        if not isinstance(value, Mapping):
            return None
        value = value.get(part)
    return value


# (JSON key, group, labels, uncertainty key or None, scale rule)
_Spec = tuple[str, str, Sequence[str], str | None, str]


def _figure_specs(result: Mapping[str, Any], reference: Mapping[str, Any]) -> list[_Spec]:
    """The figures to compare, in the order of the tables; stiffness in force units when both have them alike."""
    pairs = [f"{a}{b}" for a in _AXES for b in _AXES]
    six = [f"[{a},{b}]" for a in _DOF for b in _DOF]
    alike = result.get("force_units") == reference.get("force_units")
    specs: list[_Spec] = [
        ("mass", "mass", ("mass",), None, "self"),
        ("mass_measured", "mass", ("mass",), None, "self"),
        ("center_of_gravity", "center_of_gravity", _AXES, "center_of_gravity", "gyration"),
        ("inertia_tensor", "inertia", pairs, "inertia_tensor", "max"),
        ("principal_moments", "principal_moments", ("1", "2", "3"), "principal_moments", "max"),
    ]
    if _get(reference, "inertia_tensor") is None:
        specs += [
            ("inertia_per_mass", "inertia", pairs, "inertia_per_mass", "max"),
            ("principal_moments_per_mass", "principal_moments", ("1", "2", "3"), "principal_moments_per_mass", "max"),
        ]
    for kind in ("stiffness", "damping"):
        if alike and _get(reference, f"{kind}_force") is not None:
            specs.append((f"{kind}_force", kind, six, f"{kind}_diagonal", "blocks"))
        elif _get(reference, f"{kind}_matrix") is not None:
            specs.append((f"{kind}_matrix", kind, six, f"{kind}_diagonal", "blocks"))
        else:
            specs.append((f"{kind}_per_mass", kind, six, f"{kind}_diagonal_per_mass", "blocks"))
    return specs


def _array(data: Mapping[str, Any], name: str, src: str, shape: tuple[int, ...]) -> NDArray[np.float64] | None:
    value = _get(data, name)
    if value is None:
        return None
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError("not numbers", source=src, location=name) from None
    if arr.size == 1 and shape == (1,):
        arr = arr.reshape(1)
    if arr.shape != shape:
        raise InputError(f"shape {arr.shape}, expected {shape}", source=src, location=name)
    return arr


def _check_figure(
    result: Mapping[str, Any], reference: Mapping[str, Any], spec: _Spec, rtol: float, names: tuple[str, str]
) -> FigureCheck:
    name, group, labels, unc_key, rule = spec
    shape = (6, 6) if rule == "blocks" else (3, 3) if len(labels) == 9 else (len(labels),)
    ref = _array(reference, name, names[1], shape)
    assert ref is not None
    ours = _array(result, name, names[0], shape)
    scale = _scale(reference, ref, rule)
    factor = _force_factor(reference, name)
    se_ours, from_ours = _std(result, unc_key, shape, factor)
    se_ref, from_ref = _std(reference, unc_key, shape, factor)
    combined = _combine(se_ours, se_ref)
    units = _units(reference, name, shape)
    entries = tuple(
        EntryCheck(
            label=labels[k],
            value=None if ours is None or not math.isfinite(ours.flat[k]) else float(ours.flat[k]),
            reference=float(ref.flat[k]),
            tolerance=float(rtol * scale.flat[k]),
            sigma=None if combined is None or not math.isfinite(combined.flat[k]) else float(combined.flat[k]),
            unit=units[k],
        )
        for k in range(ref.size)
        if math.isfinite(ref.flat[k])
    )
    note = f"absent from {names[0]}" if ours is None else None
    return FigureCheck(name, group, rtol, entries, from_ours or from_ref, note)


def _scale(reference: Mapping[str, Any], ref: NDArray[np.float64], rule: str) -> NDArray[np.float64]:
    """Each entry's scale: itself, the figure's largest entry, the radius of gyration or the block's scale."""
    if rule == "self":
        return np.abs(ref)
    if rule == "gyration":
        return np.full(ref.shape, _gyration(reference, ref))
    if rule == "blocks":
        t, r = np.max(np.abs(ref[:3, :3])), np.max(np.abs(ref[3:, 3:]))
        c = math.sqrt(t * r)
        return np.block([[np.full((3, 3), t), np.full((3, 3), c)], [np.full((3, 3), c), np.full((3, 3), r)]])
    return np.full(ref.shape, np.max(np.abs(ref)))


def _gyration(reference: Mapping[str, Any], cg: NDArray[np.float64]) -> float:
    """The body's largest radius of gyration from the reference (length): the CG's scale."""
    per_mass = _get(reference, "inertia_per_mass")
    if per_mass is None:
        tensor, mass = _get(reference, "inertia_tensor"), _get(reference, "mass") or _get(reference, "mass_measured")
        if tensor is not None and isinstance(mass, (int, float)) and mass > 0:
            per_mass = np.asarray(tensor, dtype=float) / mass
    if per_mass is not None:
        moments = np.linalg.eigvalsh(np.asarray(per_mass, dtype=float))
        if np.all(np.isfinite(moments)) and moments[-1] > 0:
            return float(math.sqrt(moments[-1]))
    return float(np.max(np.abs(cg))) or 1.0


def _force_factor(reference: Mapping[str, Any], name: str) -> float:
    """The factor from the uncertainty keys' mass units to `name`'s (force units for ``*_force``)."""
    if name.endswith("_force"):
        factor = _get(reference, "force_units.factor")
        return float(factor) if isinstance(factor, (int, float)) else 1.0
    return 1.0


def _std(
    data: Mapping[str, Any], key: str | None, shape: tuple[int, ...], factor: float
) -> tuple[NDArray[np.float64] | None, str | None]:
    """The standard errors of a figure from the first interval block holding it (diagonals on the diagonal)."""
    if key is None:
        return None, None
    for block in _UNCERTAINTY_KEYS:
        std = _get(data, f"{block}.{key}.std")
        if std is None:
            continue
        arr = np.array(std, dtype=float)  # null entries -> nan
        if key.endswith(("_diagonal", "_diagonal_per_mass")) and arr.shape == (6,):
            full = np.full((6, 6), np.nan)
            full[np.diag_indices(6)] = arr
            arr = full
        if arr.shape == shape:
            return factor * arr, block
    return None, None


def _combine(a: NDArray[np.float64] | None, b: NDArray[np.float64] | None) -> NDArray[np.float64] | None:
    if a is None and b is None:
        return None
    if a is None or b is None:
        return a if b is None else b
    both = np.sqrt(np.square(np.nan_to_num(a)) + np.square(np.nan_to_num(b)))
    return np.where(np.isnan(a) & np.isnan(b), np.nan, both)


def _units(reference: Mapping[str, Any], name: str, shape: tuple[int, ...]) -> list[str]:
    """Each entry's unit: the three blocks of a 6x6 matrix apart."""
    size = int(np.prod(shape))
    if name.endswith("_force"):
        kind = "stiffness" if name.startswith("stiffness") else "damping"
        spelt = _get(reference, f"force_units.{kind}") or {}
        t, c, r = (str(spelt.get(k, "")) for k in ("translation", "coupling", "rotation"))
        return [t if i < 3 and j < 3 else r if i >= 3 and j >= 3 else c for i in range(6) for j in range(6)]
    units = reference.get("units", {})
    length, mass = units.get("length", ""), units.get("mass", "")
    fixed = {
        "mass": mass,
        "mass_measured": mass,
        "center_of_gravity": length,
        "inertia_tensor": f"{mass} {length}^2",
        "principal_moments": f"{mass} {length}^2",
        "inertia_per_mass": f"{length}^2",
        "principal_moments_per_mass": f"{length}^2",
    }
    if name in fixed:
        return [fixed[name]] * size
    per = {"stiffness_matrix": f"{mass}/s^2", "damping_matrix": f"{mass}/s"}.get(
        name, "1/s^2" if "stiff" in name else "1/s"
    )
    unit_t = per
    unit_r = f"{per.split('/')[0]} {length}^2/{per.split('/')[1]}".strip()
    unit_c = f"{per.split('/')[0]} {length}/{per.split('/')[1]}".strip()
    return [unit_t if i < 3 and j < 3 else unit_r if i >= 3 and j >= 3 else unit_c for i in range(6) for j in range(6)]


def _mount_figures(
    result: Mapping[str, Any], reference: Mapping[str, Any], rtol: float, names: tuple[str, str]
) -> list[FigureCheck]:
    """Per-mount stiffness and damping rates, matched by mount id; scale: the mount's largest rate."""
    ref_mounts = _get(reference, "mounts.mounts")
    if not isinstance(ref_mounts, list):
        return []
    ours_list = _get(result, "mounts.mounts")
    ours_by_id = {m.get("id"): m for m in ours_list if isinstance(m, Mapping)} if isinstance(ours_list, list) else {}
    same_units = _get(result, "mounts.units") == _get(reference, "mounts.units")
    out = []
    for mount in ref_mounts:
        if not isinstance(mount, Mapping):
            raise InputError("a mount is not an object", source=names[1], location="mounts.mounts")
        ident = mount.get("id")
        ours = ours_by_id.get(ident) if same_units else None
        for kind in ("stiffness", "damping"):
            ref = _array(mount, kind, names[1], (3,))
            if ref is None or not np.any(np.isfinite(ref)):
                continue
            mine = None if ours is None else _array(ours, kind, names[0], (3,))
            scale = float(np.nanmax(np.abs(ref)))
            unit = str(_get(reference, f"mounts.units.{kind}") or "")
            entries = tuple(
                EntryCheck(
                    label=f"{ident}[{k + 1}]",
                    value=None if mine is None or not math.isfinite(mine[k]) else float(mine[k]),
                    reference=float(ref[k]),
                    tolerance=rtol * scale,
                    sigma=None,
                    unit=unit,
                )
                for k in range(3)
                if math.isfinite(ref[k])
            )
            note = None if ours is not None else f"mount {ident!r} absent from {names[0]} (or in other units)"
            out.append(FigureCheck(f"mounts.{ident}.{kind}", "mounts", rtol, entries, None, note))
    return out
