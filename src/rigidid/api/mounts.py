"""Mounts on an identified body: per-mount rates and the torque roll axis from K and C, and the mount model
(CG, inertia and mount rates fitted together) for ``--method mounts``."""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rigidid.api import checks
from rigidid.core.identify import Identification
from rigidid.core.identify import identify as identify_core
from rigidid.io import files
from rigidid.models import LayoutFile, MountsFile
from rigidid.results import IdentifyResult, MountModelFit, Mounts, PathLike
from rigidid.units import check_same_units

if TYPE_CHECKING:
    from rigidid.core.linearised import StandardErrors
    from rigidid.core.noise import NoiseLevels

    pass


def with_mounts(
    result: IdentifyResult, mounts: PathLike | MountsFile | None = None, *, torque_axis: Sequence[float] | None = None
) -> IdentifyResult:
    """Add per-mount rates (from ``mounts.json`` or a ``body.json``) and the torque roll axis.

    Parameters
    ----------
    result : IdentifyResult
        An identification with a mass (rates in force units) or without (per mass).
    mounts : path-like or MountsFile, optional
        Mount positions and optional principal axes, in the layout's units.
    torque_axis : sequence of 3 floats, optional
        Direction of a torque (for an engine, the crankshaft) for the torque roll axis.

    Returns
    -------
    IdentifyResult
        `result` with :attr:`IdentifyResult.mounts` and/or
        :attr:`IdentifyResult.torque_roll_axis` set.

    Raises
    ------
    InputError
        A bad file, units that differ from the layout's, or a zero torque axis.
    """
    from rigidid.core.mounts import mount_rates, torque_roll_axis

    ident = result.identification
    out = result
    if mounts is not None:
        positions, axes, spec = read_mount_spec(mounts, result.units)
        scale = 1.0 if ident.mass is None else ident.mass
        groups = tuple(m.group for m in spec.mounts)
        rates = mount_rates(
            scale * ident.stiffness_per_mass, ident.center_of_gravity, positions, axes, scale * ident.damping_per_mass,
            groups=groups,
        )  # fmt: skip
        nominal = None
        if all(m.stiffness is not None for m in spec.mounts):
            nominal = np.array([
                np.diag(rates.axes[k].T @ np.asarray(m.stiffness, dtype=float) @ rates.axes[k])
                for k, m in enumerate(spec.mounts)
            ])  # fmt: skip
        ids = tuple(m.id or str(k + 1) for k, m in enumerate(spec.mounts))
        k_std, c_std = None, None
        if result.standard_errors is not None:
            k_std, c_std = checks.rate_errors(
                result.standard_errors, positions, rates.axes, groups, (rates.stiffness, rates.damping)
            )
            k_std = np.where(rates.stiffness > 0.0, k_std, np.nan) if rates.unique else np.full_like(k_std, np.nan)
        found = checks.rates_verdict(result.standard_errors, ident, positions, rates)
        for category, text in found:
            warnings.warn(text, category, stacklevel=2)
        if found:
            diag = out.identification.diagnostics
            texts = tuple(t for _, t in found if t not in diag.warnings)
            out = replace(out, identification=replace(out.identification, diagnostics=replace(
                diag, warnings=(*diag.warnings, *texts))))  # fmt: skip
        out = replace(out, mounts=Mounts(ids, positions, rates, nominal, groups, k_std, c_std))
    if torque_axis is not None:
        tra = torque_roll_axis(ident.inertia_per_mass, torque_axis)
        tra_std = None
        if result.standard_errors is not None:
            tra_std = checks.roll_axis_error(result.standard_errors, torque_axis, tra.direction)
        out = replace(out, torque_roll_axis=tra, torque_roll_axis_std_deg=tra_std)
    return out


def read_mount_spec(
    mounts: PathLike | MountsFile, units: Mapping[str, str]
) -> tuple[NDArray[np.float64], NDArray[np.float64], MountsFile]:
    """Positions and axes (columns) of the mounts, checked against the layout's units."""
    spec = mounts if isinstance(mounts, MountsFile) else files.load_mounts(mounts)
    source = None if isinstance(mounts, MountsFile) else str(mounts)
    check_same_units(spec.units, units, source=source)
    positions = np.array([m.position for m in spec.mounts], dtype=float)
    axes = np.stack([np.eye(3) if m.axes is None else np.asarray(m.axes, dtype=float).T for m in spec.mounts])
    return positions, axes, spec


def mount_model(
    positions: NDArray[np.float64],
    directions: NDArray[np.float64],
    poles: NDArray[np.complex128],
    shapes: NDArray[np.complex128],
    mass: float | None,
    mounts: PathLike | MountsFile,
    layout: LayoutFile,
    noise: NoiseLevels | Mapping[str, float] | None = None,
) -> tuple[Identification, MountModelFit, StandardErrors | None]:
    """The mount model, started from the free route when six modes allow it, the comparison with it, and
    its standard errors.

    The output residuals are weighted by `noise` (default: ``estimate_noise``, the shape noise from the
    rigid-body fit, with any overrides of a mapping), as the Monte Carlo intervals are. The standard
    errors are linearised at the fit from the Jacobian of those residuals
    (:attr:`rigidid.core.mounts.MountModel.linearised`), scaled up by the misfit when it exceeds the noise.
    """
    from rigidid.core.geometry import layout_frame
    from rigidid.core.mounts import eigen_residual, identify_mount_model
    from rigidid.core.noise import NoiseLevels, estimate_noise
    from rigidid.errors import IdentificationError

    where, axes, spec = read_mount_spec(mounts, {"length": layout.units.length, "mass": layout.units.mass})
    groups = [m.group for m in spec.mounts]
    if isinstance(noise, NoiseLevels):
        levels = noise
    else:
        levels = replace(estimate_noise(positions, directions, shapes), **dict(noise or {}))
    free = None
    if poles.size == 6:
        try:
            free = identify_core(positions, directions, poles, shapes, mass=mass, warn=False)
        except IdentificationError:
            free = None
    start = None if free is None else (free.center_of_gravity, free.inertia_per_mass)
    try:
        ident, model = identify_mount_model(
            positions, directions, poles, shapes, where, axes, mass=mass, start=start, groups=groups, noise=levels
        )
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise IdentificationError(
            f"the mount model cannot be fitted to these modes ({exc}): check that mounts.json lists every support "
            "at its position, in the layout's axes and units"
        ) from exc
    length = layout_frame(positions).scale
    residual = eigen_residual(
        poles, ident.mode_shapes_cg, ident.inertia_per_mass, ident.stiffness_per_mass, ident.damping_per_mass, length
    )
    free_residual = None
    if free is not None:
        free_residual = eigen_residual(
            poles, free.mode_shapes_cg, free.inertia_per_mass, free.stiffness_per_mass, free.damping_per_mass, length
        )
    errors = None
    if model.linearised is not None:
        from rigidid.core.linearised import assembled

        errors = assembled(
            model.linearised, inertia_per_mass=ident.inertia_per_mass, mass=mass, misfit=model.cost,
            misfit_dof=model.misfit_dof, weighted=True,
        )  # fmt: skip
    return ident, MountModelFit(model, residual, free_residual, noise=levels), errors
