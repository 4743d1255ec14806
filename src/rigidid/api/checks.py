"""Every answer checks itself: default standard errors, the misfit's verdict and plausibility checks.

The workflow half of issue 22 (the numbers are in :mod:`rigidid.core.linearised` and
:mod:`rigidid.core.checks`): :func:`rigidid.api.identify` calls these on the
structured route's answer; :func:`rigidid.api.with_mounts` adds the rates' and the torque
roll axis' standard errors.
"""

from __future__ import annotations

import warnings
from collections.abc import Hashable, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from rigidid.core.estimator import Estimates
    from rigidid.core.identify import Identification
    from rigidid.core.linearised import StandardErrors
    from rigidid.core.mounts import MountRates
    from rigidid.core.noise import NoiseLevels
    from rigidid.results import IdentifyResult

__all__ = [
    "about_the_answer",
    "checked",
    "damping_meaning",
    "noise_levels",
    "paper_standard_errors",
    "pass_on",
    "plausibility",
    "rate_errors",
    "rates_verdict",
    "roll_axis_error",
    "standard_errors_of",
    "verdict",
]

Array = NDArray[np.float64]


def noise_levels(
    noise: NoiseLevels | Mapping[str, float] | None, positions: Array, directions: Array, shapes: NDArray[np.complex128]
) -> NoiseLevels:
    """The levels of a run: ``DEFAULT_NOISE`` with the shape noise measured, then the overrides."""
    from rigidid.core.noise import NoiseLevels, estimate_noise

    if isinstance(noise, NoiseLevels):
        return noise
    return replace(estimate_noise(positions, directions, shapes), **dict(noise or {}))


def standard_errors_of(
    ident: Identification,
    positions: Array,
    directions: Array,
    poles: NDArray[np.complex128],
    shapes: NDArray[np.complex128],
    levels: NoiseLevels,
) -> StandardErrors | None:
    """Linearised standard errors of a structured identification (None when they cannot be formed)."""
    from rigidid.core.linearised import standard_errors

    diag = ident.diagnostics
    try:
        errors = standard_errors(
            positions, directions, poles, shapes, inertia_per_mass=ident.inertia_per_mass, mass=ident.mass,
            noise=levels, weights=diag.residual_weights, misfit=diag.misfit, misfit_dof=diag.misfit_dof,
            center_of_gravity=ident.center_of_gravity,
        )  # fmt: skip
    except (np.linalg.LinAlgError, ValueError):
        return None
    return errors


def paper_standard_errors(
    ident: Identification,
    positions: Array,
    directions: Array,
    poles: NDArray[np.complex128],
    shapes: NDArray[np.complex128],
    levels: NoiseLevels,
) -> StandardErrors | None:
    """Linearised standard errors of the paper's sequential route (eqs. (36)-(40) of [1]).

    The route is identified again with the data moved along each noise direction
    (:func:`rigidid.core.linearised.noise_directions`; forward differences, as the
    structured route's). A moved test that the route refuses counts as no response
    (:attr:`StandardErrors.failed`). None when the noise is zero.

    References
    ----------
    .. [1] "Determination of rigid body characteristics from time domain modal test
       data", Journal of Sound and Vibration, 1994.
    """
    from rigidid.core.estimator import Estimates
    from rigidid.core.identify import identify
    from rigidid.core.linearised import Linearised, assembled, noise_directions
    from rigidid.errors import RigididError

    moved = noise_directions(positions, directions, poles, shapes, levels)
    k = moved.sigma.size
    if k == 0:
        return None
    cg, inertia = np.full((k, 3), np.nan), np.full((k, 3, 3), np.nan)
    stiff, damp = np.full((k, 6, 6), np.nan), np.full((k, 6, 6), np.nan)
    status = np.full(k, 5, dtype=np.int8)
    for i in range(k):
        try:
            one = identify(
                moved.positions[i], moved.directions[i], moved.poles[i], moved.shapes[i], method="paper", warn=False
            )
        except (RigididError, np.linalg.LinAlgError):
            continue
        cg[i], inertia[i] = one.center_of_gravity, one.inertia_per_mass
        stiff[i], damp[i], status[i] = one.stiffness_per_mass, one.damping_per_mass, 0
    base = Estimates(
        ident.center_of_gravity[None], ident.inertia_per_mass[None], ident.stiffness_per_mass[None],
        ident.damping_per_mass[None], np.zeros(1, dtype=np.int8),
    )  # fmt: skip
    lin = Linearised(base, Estimates(cg, inertia, stiff, damp, status), moved.sigma, levels)
    return assembled(
        lin, inertia_per_mass=ident.inertia_per_mass, mass=ident.mass, misfit=None, misfit_dof=0, weighted=False
    )


def rate_errors(
    errors: StandardErrors,
    positions: Array,
    axes: Array | None,
    groups: Sequence[Hashable | None] | None,
    rates_value: tuple[Array, Array | None],
) -> tuple[Array, Array | None]:
    """Standard errors of the per-mount stiffness and damping rates (absolute with a mass, else per mass)."""
    from rigidid.core.mounts import mount_rates

    n = positions.shape[0]

    def figure(est: Estimates) -> Array:
        out = np.full((est.status.shape[0], 2, n, 3), np.nan)
        for b in np.flatnonzero(est.ok):
            r = mount_rates(
                est.stiffness_per_mass[b], est.center_of_gravity[b], positions, axes, est.damping_per_mass[b],
                groups=groups,
            )  # fmt: skip
            out[b, 0] = r.stiffness
            out[b, 1] = np.nan if r.damping is None else r.damping
        return out

    stiff, damp = rates_value
    scale = 1.0 if errors.mass is None else errors.mass
    value = np.stack([stiff / scale, (damp if damp is not None else np.zeros_like(stiff)) / scale])
    sd = errors.std(figure, value)
    return sd[0], (None if damp is None else sd[1])


def roll_axis_error(errors: StandardErrors, torque_axis: Sequence[float], direction: Array) -> float:
    """Angular standard error (degrees) of the torque roll axis ``J^-1 t``."""
    t = np.asarray(torque_axis, dtype=float)
    t = t / np.linalg.norm(t)

    def figure(est: Estimates) -> Array:
        out = np.zeros((est.status.shape[0], 3))
        ok = est.ok
        w = np.linalg.solve(est.inertia_per_mass[ok], np.broadcast_to(t, (int(ok.sum()), 3))[..., None])[..., 0]
        w /= np.linalg.norm(w, axis=1, keepdims=True)
        w *= np.sign(w @ direction)[:, None]
        out[ok] = np.cross(direction, w)
        return out

    return float(np.rad2deg(np.sqrt(np.sum(errors.std(figure) ** 2))))


UNEXPLAINED_MISFIT = 1e4
"""Misfit per degree of freedom (the misfit 100 times the noise) above which the rigid-body
model is taken not to explain the data at all: an error, not an answer."""

MISFIT_WARN = 9.0 * 21
"""Chi-square misfit on 21 degrees of freedom above which a warning names the likely cause: the
model misses the data by three times the noise levels (far beyond the 0.999 quantile, 46.8).
Between the two the levels are merely optimistic (modes estimated from records often carry
more than the default 0.1 % and 5 %): the standard errors are scaled up by the misfit, and the
table and JSON say so, without a warning."""


def _pct(x: float) -> str:
    return f"{100.0 * x:.2g} %"


def verdict(
    ident: Identification,
    errors: StandardErrors | None,
    positions: Array,
    directions: Array,
    poles: NDArray[np.complex128],
    shapes: NDArray[np.complex128],
    levels: NoiseLevels,
    assumed: bool = False,
) -> list[tuple[type[Warning], str]]:
    """The misfit's verdict on a structured answer: warnings (category, text), or an error when nothing fits.

    With `assumed` levels (six sensors and no shape noise stated: nothing measured the
    noise), a misfit above them only widens the standard errors (their ``inflation``);
    no warning.

    Raises
    ------
    IdentificationError
        When the misfit per degree of freedom exceeds :data:`UNEXPLAINED_MISFIT`.
    """
    from rigidid.core.linearised import misfit_parts
    from rigidid.errors import IdentificationError, ModelMisfitWarning

    diag = ident.diagnostics
    if diag.misfit is None or diag.misfit_dof <= 0 or errors is None:
        return []
    misfit, dof = diag.misfit, diag.misfit_dof
    levels_text = (
        f"frequency {_pct(levels.frequency)}, damping ratio {_pct(levels.damping)}, shape {_pct(levels.shape)}"
    )
    if misfit <= MISFIT_WARN or (assumed and misfit <= UNEXPLAINED_MISFIT * dof):
        return []
    parts = misfit_parts(positions, directions, poles, shapes, levels, ident.center_of_gravity, ident.inertia_per_mass)
    cause = ""
    if parts is not None:
        stiff, damp = parts
        cause = (
            "; the damping equations carry most of it: damping ratios less accurate than assumed "
            "(--damping-noise) or damping that is not viscous, so the damping matrix is the least certain figure"
            if damp > stiff
            else "; the stiffness equations carry most of it: a frequency less accurate than assumed "
            "(--frequency-noise), a sensor's position or direction, an elastic mode or a support that is not a "
            "linear spring"
        )
    ratio = float(np.sqrt(misfit / dof))
    if misfit > UNEXPLAINED_MISFIT * dof:
        raise IdentificationError(
            f"the rigid-body model cannot explain these modes: they miss it by {ratio:.3g} times the noise levels "
            f"({levels_text}; chi-square misfit {misfit:.3g} on {dof} degrees of freedom){cause}"
        )
    if misfit <= MISFIT_WARN or assumed:
        return []
    used = "" if errors.weighted else " and the noise weighting was not used"
    return [
        (
            ModelMisfitWarning,
            f"the rigid-body model explains these modes only to {ratio:.2g} times the noise levels ({levels_text}; "
            f"chi-square misfit {misfit:.3g} on {dof} degrees of freedom): the standard errors are scaled up by "
            f"{errors.inflation:.2g}{used}{cause}",
        )
    ]


def damping_meaning(ident: Identification, errors: StandardErrors | None) -> list[tuple[type[Warning], str]]:
    """What a damping matrix that is not positive semi-definite means, judged by its standard error."""
    from rigidid.errors import PhysicalPlausibilityWarning

    c = 0.5 * (ident.damping_per_mass + ident.damping_per_mass.T)
    # dimension-free: the eigenvalue of C scaled by its diagonal (translations and rotations alike)
    d = 1.0 / np.sqrt(np.maximum(np.abs(np.diag(c)), 1e-300))
    low = float(np.linalg.eigvalsh(c * np.outer(d, d))[0])
    if errors is None or low >= 0.0:
        return []

    def figure(est: Estimates) -> Array:
        cs = 0.5 * (est.damping_per_mass + np.swapaxes(est.damping_per_mass, 1, 2))
        out = np.full(cs.shape[0], np.nan)
        ok = np.all(np.isfinite(cs), axis=(1, 2))
        out[ok] = np.linalg.eigvalsh(cs[ok] * np.outer(d, d))[:, 0]
        return out

    sd = float(errors.inflation * errors.linearised.std(figure))
    z = -low / sd if sd > 0.0 else np.inf
    if z <= 2.0:
        text = (
            f"the damping matrix's negative eigenvalue is within {z:.2g} standard errors of zero: these modes "
            "determine the damping poorly (it is the least certain figure), not a negative damping; the CG, "
            "inertia and stiffness are not affected"
        )
    else:
        text = (
            f"the damping matrix's negative eigenvalue is {z:.2g} standard errors below zero: a damping ratio or a "
            "mode shape's phase is wrong, or the damping is not viscous; the CG, inertia and stiffness are not "
            "affected"
        )
    return [(PhysicalPlausibilityWarning, text)]


def plausibility(ident: Identification, positions: Array, units: Mapping[str, str]) -> list[tuple[type[Warning], str]]:
    """Warnings that the answer cannot be the body the sensors sit on (:func:`rigidid.core.checks.implausible_body`)."""
    from rigidid.core.checks import implausible_body
    from rigidid.errors import PhysicalPlausibilityWarning, UnitsWarning
    from rigidid.units import KG_PER_MASS, M_PER_LENGTH

    mass_kg = None if ident.mass is None else ident.mass * KG_PER_MASS[units["mass"]]
    found = implausible_body(
        positions, ident.center_of_gravity, ident.inertia_per_mass, mass_kg=mass_kg,
        metre=M_PER_LENGTH[units["length"]],
    )  # fmt: skip
    return [(UnitsWarning if f.kind == "density" else PhysicalPlausibilityWarning, f.text) for f in found]


def checked(
    ident: Identification,
    errors: StandardErrors | None,
    arrays: tuple[Array, Array, NDArray[np.complex128], NDArray[np.complex128]],
    levels: NoiseLevels,
    units: Mapping[str, str],
    assumed: bool = False,
) -> Identification:
    """`ident` with the verdict, the damping's meaning and the plausibility findings warned and in its diagnostics."""

    positions, directions, poles, shapes = arrays
    found = [
        *verdict(ident, errors, positions, directions, poles, shapes, levels, assumed),
        *damping_meaning(ident, errors),
        *plausibility(ident, positions, units),
    ]
    for category, text in found:
        warnings.warn(text, category, stacklevel=3)
    if not found:
        return ident
    diag = ident.diagnostics
    return replace(ident, diagnostics=replace(diag, warnings=(*diag.warnings, *(t for _, t in found))))


def rates_verdict(
    errors: StandardErrors | None, ident: Identification, positions: Array, rates: MountRates
) -> list[tuple[type[Warning], str]]:
    """Warnings about per-mount rates: a split that is not unique, rates at zero, mounts that miss the stiffness."""
    from rigidid.core.chisquare import chi2_quantile
    from rigidid.core.mounts import split_misfit
    from rigidid.errors import PhysicalPlausibilityWarning

    if not rates.unique:
        return [(PhysicalPlausibilityWarning, f"the per-mount rates are {rates.statement}")]
    found: list[tuple[type[Warning], str]] = []
    at_zero = np.argwhere(rates.stiffness <= 0.0)
    if at_zero.size:
        names = ", ".join(f"mount {m + 1} axis {a + 1}" for m, a in at_zero)
        found.append((PhysicalPlausibilityWarning, (
            f"the stiffness rate of {names} came out zero (the fit's bound): the mounts do not split the "
            "identified stiffness as positive springs, so the rates and their standard errors are not to be trusted; "
            "check the mounts' positions and axes in mounts.json, or fix known rates"
        )))  # fmt: skip
    if errors is None:
        return found
    iu = np.triu_indices(6)
    cov = errors.inflation**2 * errors.linearised.covariance(lambda e: e.stiffness_per_mass[:, iu[0], iu[1]])
    chi2, dof = split_misfit(ident.stiffness_per_mass, cov, ident.center_of_gravity, positions, rates.axes)
    if dof > 0 and chi2 > chi2_quantile(dof, 3.09):  # 0.1 %
        found.append((PhysicalPlausibilityWarning, (
            f"the mounts in mounts.json do not explain the identified stiffness: it misses their best fit by "
            f"{np.sqrt(chi2 / dof):.2g} times its standard errors (chi-square {chi2:.3g} on {dof} degrees of "
            "freedom): a support missing from mounts.json (a hose, a cable, a torque rod) or a mount's position "
            "or axes wrong; the per-mount rates are not to be trusted"
        )))  # fmt: skip
    return found


def pass_on(held: Sequence[warnings.WarningMessage]) -> None:
    """Issue warnings that were held back, as they were."""
    for w in held:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def about_the_answer(
    result: IdentifyResult, held: Sequence[warnings.WarningMessage], *, replaced: bool
) -> IdentifyResult:
    """Warnings that describe the reported answer once a refinement may have replaced the structured one.

    When `replaced`, the held findings about the structured start (physical plausibility,
    misfit) are dropped, from the output and from the diagnostics, and the refined answer's
    own physical checks are issued instead; the other held warnings pass on unchanged.
    """
    from rigidid.core.identify import physical_checks
    from rigidid.errors import ModelMisfitWarning, PhysicalPlausibilityWarning

    about_start = (PhysicalPlausibilityWarning, ModelMisfitWarning)
    if not replaced:
        pass_on(held)
        return result
    pass_on([w for w in held if not issubclass(w.category, about_start)])
    dropped = {str(w.message) for w in held if issubclass(w.category, about_start)}
    ident = result.identification
    found = physical_checks(ident.inertia_per_mass, ident.stiffness_per_mass, ident.damping_per_mass)
    for text in found:
        warnings.warn(text, PhysicalPlausibilityWarning, stacklevel=3)
    kept = tuple(t for t in ident.diagnostics.warnings if t not in dropped)
    diag = replace(ident.diagnostics, warnings=(*kept, *(t for t in found if t not in kept)))
    return replace(result, identification=replace(ident, diagnostics=diag))
