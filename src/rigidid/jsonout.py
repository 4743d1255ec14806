"""The JSON forms of rigidid's results: the result JSON of ``docs/FORMATS.md`` and its parts.

Every function turns a result object of :mod:`rigidid.api` or :mod:`rigidid.core`
into plain dicts, lists, floats and strings, ready for :func:`json.dumps`.
Non-finite numbers become ``None`` where a field allows it. Nothing here prints
or writes; :mod:`rigidid.render` makes the tables, :mod:`rigidid.reporting`
the HTML report.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid import __version__

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rigidid.core.frfmodes import FrfModes, ScaledBody
    from rigidid.core.layout_check import LayoutReport
    from rigidid.core.massline import MassLine
    from rigidid.core.noise import NoiseLevels
    from rigidid.core.plan import PredictedFigures, Prediction, ReferenceReport, SensorPlan
    from rigidid.core.record_spread import RecordSpread
    from rigidid.core.timedomain import ModalEstimate
    from rigidid.core.timedomain.force import ForceMass
    from rigidid.core.timedomain.refine import RecordBound, SensorCorrection
    from rigidid.core.timedomain.stabilisation import OrderPoles
    from rigidid.core.uncertainty import IntervalEstimate, Uncertainty
    from rigidid.results import IdentifyResult, MassLineResult, PlanResult

__all__ = [
    "corrections_by_sensor",
    "estimate_to_dict",
    "interval_to_dict",
    "layout_report_to_dict",
    "massline_to_dict",
    "noise_to_dict",
    "plan_to_dict",
    "predicted_figures_to_dict",
    "prediction_to_dict",
    "record_bound_to_dict",
    "record_spread_to_dict",
    "result_to_dict",
    "scaled_modes_to_dict",
    "sensor_plan_to_dict",
    "standard_errors_to_dict",
    "uncertainty_to_dict",
]


def _none_if_inf(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _plain(a: NDArray[np.float64]) -> Any:
    """Nested lists of Python floats; NaN and infinities become None (valid JSON)."""
    return _nan_none(np.asarray(a, dtype=float).tolist())


def _nan_none(x: Any) -> Any:
    if isinstance(x, list):
        return [_nan_none(v) for v in x]
    return _none_if_inf(float(x))


def _rows(a: NDArray[np.float64] | None) -> list[list[float]] | None:
    return None if a is None else [[float(v) for v in row] for row in a]


def _vec(a: NDArray[np.float64] | None) -> list[float] | None:
    return None if a is None else [float(v) for v in a]


def result_to_dict(result: IdentifyResult, force_unit: str | None = None) -> dict[str, Any]:
    """The result JSON of FORMATS.md (validated by :class:`rigidid.models.ResultFile`).

    Parameters
    ----------
    result : IdentifyResult
    force_unit : {"N", "kN", "lbf"}, optional
        Force unit of ``stiffness_force`` and ``damping_force`` (default N for
        kg, g and t, lbf for lb and slug).

    Returns
    -------
    dict
        Plain lists and floats, ready for :func:`json.dumps`.
    """
    ident = result.identification
    diag = ident.diagnostics
    modes = _modes_used_rows(result)
    candidates = None
    if result.candidate_residuals is not None:
        candidates = [{"mode": label, "rigid_fit_residual": r} for label, r in result.candidate_residuals.items()]
    energy = _energy_distribution(result)
    out: dict[str, Any] = {
        "rigidid_version": __version__,
        "method": ident.method,
        "units": {"length": result.units["length"], "mass": result.units["mass"], "time": "s"},
        "mass": ident.mass,
        "center_of_gravity": _vec(ident.center_of_gravity),
        "inertia_per_mass": _rows(ident.inertia_per_mass),
        "inertia_tensor": _rows(ident.inertia_tensor),
        "principal_moments": _vec(ident.principal_moments),
        "principal_moments_per_mass": _vec(ident.principal_moments_per_mass),
        "principal_axes": _rows(ident.principal_axes),
        "stiffness_per_mass": _rows(ident.stiffness_per_mass),
        "stiffness_matrix": _rows(ident.stiffness_matrix),
        "damping_per_mass": _rows(ident.damping_per_mass),
        "damping_matrix": _rows(ident.damping_matrix),
        "modes_used": list(result.modes_used),
        "modes_selected": result.selection,
        "energy_distribution": energy,
        "diagnostics": {
            "layout_condition": diag.layout_condition,
            "layout_rank": diag.layout_rank,
            "structure_residual": diag.structure_residual,
            "inertia_observability": diag.inertia_observability,
            "modes": modes,
            "candidate_modes": candidates,
            "warnings": list(diag.warnings),
        },
    }
    out.update(_force_keys(result, force_unit))
    if result.mounts is not None:
        out["mounts"] = mounts_to_dict(result, force_unit)
    if result.mount_model is not None:
        fit = result.mount_model
        out["mount_model"] = {
            "residual": fit.residual,
            "parameters": fit.model.parameters,
            "equations": fit.model.equations,
            "aic": fit.aic,
            "free_residual": fit.free_residual,
            "free_parameters": fit.free_parameters,
            "free_aic": fit.free_aic,
            "adequate": fit.adequate,
            **mount_test_to_dict(result),
        }
    if result.torque_roll_axis is not None:
        tra = result.torque_roll_axis
        out["torque_roll_axis"] = {
            "torque_axis": _vec(tra.torque_axis),
            "direction": _vec(tra.direction),
            "angle_to_torque_deg": tra.angle_to_torque_deg,
            "angle_to_principal_deg": _vec(tra.angle_to_principal_deg),
        }
    if result.scaled is not None:
        out.update(scaled_modes_to_dict(result.scaled, ident.mass))
    if result.force_mass is not None:
        out.update(force_mass_to_dict(result.force_mass, result.mass_given))
    if result.uncertainty is not None:
        out["uncertainty"] = uncertainty_to_dict(result.uncertainty)
    if result.standard_errors is not None:
        out["standard_errors"] = standard_errors_to_dict(result, force_unit)
    if result.record_spread is not None:
        out["uncertainty_records"] = record_spread_to_dict(result.record_spread)
    if result.record_bound is not None:
        out["uncertainty_records_crb"] = record_bound_to_dict(result.record_bound)
    return out


def _modes_used_rows(result: IdentifyResult) -> list[dict[str, Any]]:
    """``diagnostics.modes``: each mode used, measured and as the identified model gives it."""
    ident = result.identification
    diag = ident.diagnostics
    return [
        {
            "mode": label,
            "frequency_hz": float(ident.frequency_hz[k]),
            "damping_ratio": float(ident.damping_ratio[k]),
            "rigid_fit_residual": float(diag.rigid_fit_residual[k]),
            "model_frequency_hz": float(diag.model_frequency_hz[k]),
            "model_damping_ratio": float(diag.model_damping_ratio[k]),
            "model_mac": float(diag.model_mac[k]),
        }
        for k, label in enumerate(result.modes_used)
    ]


def _energy_distribution(result: IdentifyResult) -> dict[str, Any]:
    """``energy_distribution``: each mode's kinetic energy by CG axis and by principal axis."""
    from rigidid.core.energy import kinetic_energy_distribution, kinetic_energy_distribution_principal

    ident = result.identification
    return {
        "dof": ["x", "y", "z", "rx", "ry", "rz"],
        "principal_dof": ["x", "y", "z", "r1", "r2", "r3"],
        "modes": list(result.modes_used),
        "cg_axes": _rows(kinetic_energy_distribution(ident.inertia_per_mass, ident.mode_shapes_cg)),
        "principal_axes": _rows(kinetic_energy_distribution_principal(ident.inertia_per_mass, ident.mode_shapes_cg)),
    }


_Z95 = 1.959963984540054
"""The normal distribution's 97.5 % quantile: 95 % intervals are ``estimate -/+ _Z95 std``."""


def force_mass_to_dict(measured: ForceMass, mass_given: float | None) -> dict[str, Any]:
    """``mass_source``, ``mass_measured``, ``mass_given``, ``mass_difference(_relative)`` and ``force_mass``.

    The keys added when the records' force channel measured the mass (FORMATS.md, "The measured force").
    """
    m = float(measured.mass)
    return {
        "mass_source": "force",
        "mass_measured": m,
        "mass_given": None if mass_given is None else float(mass_given),
        "mass_difference": None if mass_given is None else m - float(mass_given),
        "mass_difference_relative": None if mass_given is None else m / float(mass_given) - 1.0,
        "force_mass": {
            "estimate": m,
            "std": float(measured.std),
            "ci95": [m - _Z95 * measured.std, m + _Z95 * measured.std],
            "budget": {k: float(v) for k, v in measured.budget.items()},
            "band_hz": [float(measured.band_hz[0]), float(measured.band_hz[1])],
            "lines": int(measured.lines),
            "relative_residual": float(measured.relative_residual),
            "misfit_noise_units": float(measured.misfit),
            "coherence": float(measured.coherence),
            "estimator": measured.estimator,
        },
    }


def scaled_modes_to_dict(scaled: ScaledBody, mass_given: float | None) -> dict[str, Any]:
    """``mass_measured``, ``mass_given``, ``mass_difference(_relative)`` and ``scaled_modes`` (FORMATS.md).

    The keys of the ``--method residues`` JSON, added to the result JSON when the six
    modes used are scaled by the force (``modes.csv`` ``scaling`` ``modal_a``).
    """
    out: dict[str, Any] = {
        "mass_measured": float(scaled.mass),
        "mass_given": None if mass_given is None else float(mass_given),
        "mass_difference": None if mass_given is None else float(scaled.mass - mass_given),
        "mass_difference_relative": None if mass_given is None else float(scaled.mass / mass_given - 1.0),
        "scaled_modes": {
            "mass": float(scaled.mass),
            "center_of_gravity": _vec(scaled.center_of_gravity),
            "inertia_tensor": _rows(scaled.inertia_tensor),
            "stiffness_matrix": _rows(scaled.stiffness_matrix),
            "damping_matrix": _rows(scaled.damping_matrix),
        },
    }
    return out


def _force_keys(result: IdentifyResult, force_unit: str | None) -> dict[str, Any]:
    """``force_units``, ``stiffness_force``, ``damping_force`` and ``quantity_units`` of the result JSON."""
    from rigidid.units import force_units

    ident = result.identification
    length, mass = result.units["length"], result.units["mass"]
    fu = force_units(length, mass, force_unit)
    units = {
        "mass": mass,
        "center_of_gravity": length,
        "inertia_per_mass": f"{length}^2",
        "inertia_tensor": f"{mass} {length}^2",
        "principal_moments": f"{mass} {length}^2",
        "principal_moments_per_mass": f"{length}^2",
        "principal_axes": "1",
        "stiffness_per_mass": f"1/s^2, {length}/s^2, {length}^2/s^2 (translation, coupling, rotation blocks)",
        "stiffness_matrix": f"{mass}/s^2, {mass} {length}/s^2, {mass} {length}^2/s^2 (translation, coupling, rotation)",
        "damping_per_mass": f"1/s, {length}/s, {length}^2/s (translation, coupling, rotation blocks)",
        "damping_matrix": f"{mass}/s, {mass} {length}/s, {mass} {length}^2/s (translation, coupling, rotation)",
        "energy_distribution": "1 (fractions)",
        "frequency_hz": "Hz",
        "damping_ratio": "1 (fraction of critical)",
        "rigid_fit_residual": "1",
        "layout_condition": "1",
        "inertia_observability": "1",
    }
    if ident.mass is None:
        return {"force_units": None, "stiffness_force": None, "damping_force": None, "quantity_units": units}
    units["stiffness_force"] = ", ".join(fu.stiffness.values()) + " (translation, coupling, rotation)"
    units["damping_force"] = ", ".join(fu.damping.values()) + " (translation, coupling, rotation)"
    assert ident.stiffness_matrix is not None and ident.damping_matrix is not None
    return {
        "force_units": {"force": fu.force, "factor": fu.factor, "stiffness": fu.stiffness, "damping": fu.damping},
        "stiffness_force": _rows(fu.factor * ident.stiffness_matrix),
        "damping_force": _rows(fu.factor * ident.damping_matrix),
        "quantity_units": units,
    }


def mounts_to_dict(result: IdentifyResult, force_unit: str | None = None) -> dict[str, Any]:
    """Per-mount rates in force units (per mass without a mass), with the fit's residual and uniqueness."""
    from rigidid.units import rate_units

    assert result.mounts is not None
    m = result.mounts
    rates = m.rates
    per_mass = result.identification.mass is None
    factor, k_unit, c_unit = rate_units(result.units["length"], result.units["mass"], force_unit, per_mass=per_mass)
    units = {"stiffness": k_unit, "damping": c_unit}
    damping = rates.damping if rates.damping is not None else np.full_like(rates.stiffness, np.nan)
    return {
        "units": units,
        "mounts": [
            {
                "id": m.ids[k],
                "position": _vec(m.positions[k]),
                "axes": _rows(rates.axes[k].T),
                "stiffness": _vec(factor * rates.stiffness[k]),
                "damping": _plain(factor * damping[k]),
                "nominal_stiffness": None if m.nominal is None else _vec(factor * m.nominal[k]),
                "group": None if m.groups is None else m.groups[k],
            }
            for k in range(len(m.ids))
        ],
        "stiffness_residual": rates.stiffness_residual,
        "damping_residual": _none_if_inf(rates.damping_residual),
        "unknowns": rates.unknowns,
        "rank": rates.rank,
        "unique": rates.unique,
        "statement": rates.statement,
    }


def mount_test_to_dict(result: IdentifyResult) -> dict[str, Any]:
    """The mount model's F test keys: ``f_statistic``, ``f_dof``, ``p_value``, ``significance``, ``f_test_adequate``."""
    from rigidid.core.mounts import ADEQUATE_P

    assert result.mount_model is not None
    fit = result.mount_model
    model = fit.model
    return {
        "f_statistic": model.f_statistic,
        "f_dof": None if model.f_dof is None else list(model.f_dof),
        "p_value": model.p_value,
        "significance": None if model.p_value is None else ADEQUATE_P,
        "f_test_adequate": model.adequate,
        "noise": None if fit.noise is None else noise_to_dict(fit.noise),
        "groups": (model.parameters - 9) // 6,
    }


def noise_to_dict(noise: NoiseLevels) -> dict[str, float]:
    """The noise levels: ``{"frequency", "damping", "shape", "position", "angle_deg", "mass"}``."""
    return {
        "frequency": noise.frequency,
        "damping": noise.damping,
        "shape": noise.shape,
        "position": noise.position,
        "angle_deg": noise.angle_deg,
        "mass": noise.mass,
    }


def interval_to_dict(interval: IntervalEstimate) -> dict[str, Any]:
    """``{"estimate", "std", "ci95"}`` as nested lists of floats; ``ci95`` pairs ``[low, high]``."""
    ci = np.stack([interval.low, interval.high], axis=-1)
    return {"estimate": _plain(interval.estimate), "std": _plain(interval.std), "ci95": _plain(ci)}


def uncertainty_to_dict(result: Uncertainty) -> dict[str, Any]:
    """JSON form of Monte Carlo intervals (:func:`rigidid.core.uncertainty.propagate`).

    Returns
    -------
    dict
        ``{"center_of_gravity": {"estimate": [3], "std": [3], "ci95": [[lo, hi] x 3]},
        "inertia_tensor": {... 3x3, ci95 3x3x2}, "principal_moments": {...},
        "stiffness_diagonal": {...}, "damping_diagonal": {...}, "per_mass": bool,
        "draws": int, "failed": int, "implausible": int, "seed": int | None,
        "noise": {...}}``. Without a mass the keys of the per-mass quantities
        end in ``_per_mass`` (``"inertia_per_mass"``,
        ``"principal_moments_per_mass"``, ``"stiffness_diagonal_per_mass"``,
        ``"damping_diagonal_per_mass"``), as the attributes of
        :class:`~rigidid.core.identify.Identification`.
    """
    suffix = "_per_mass" if result.per_mass else ""
    inertia_key = "inertia_per_mass" if result.per_mass else "inertia_tensor"
    return {
        "center_of_gravity": interval_to_dict(result.center_of_gravity),
        inertia_key: interval_to_dict(result.inertia),
        "principal_moments" + suffix: interval_to_dict(result.principal_moments),
        "stiffness_diagonal" + suffix: interval_to_dict(result.stiffness_diagonal),
        "damping_diagonal" + suffix: interval_to_dict(result.damping_diagonal),
        "per_mass": result.per_mass,
        "draws": result.draws,
        "failed": result.failed,
        "implausible": result.implausible,
        "seed": result.seed,
        "noise": noise_to_dict(result.noise),
    }


def standard_errors_to_dict(result: IdentifyResult, force_unit: str | None = None) -> dict[str, Any]:
    """JSON form of the default linearised standard errors (:func:`rigidid.core.linearised.standard_errors`).

    Returns
    -------
    dict
        ``method`` (``"linearised"``), ``weighted``, ``noise``, ``misfit``,
        ``misfit_dof``, ``inflation``, ``failed``, and the standard errors of
        ``center_of_gravity``, ``inertia_tensor``, ``principal_moments``,
        ``principal_axes_deg``, ``stiffness_matrix``, ``damping_matrix`` (names as
        the result's: ``_per_mass`` keys without a mass), with ``mounts``
        (``stiffness``, ``damping`` per mount, in the units of the result's
        ``mounts``) and ``torque_roll_axis_deg`` when those were computed.
    """
    from rigidid.units import force_units

    err = result.standard_errors
    assert err is not None
    per = err.per_mass
    out: dict[str, Any] = {
        "method": "linearised",
        "weighted": err.weighted,
        "noise": noise_to_dict(err.noise),
        "misfit": err.misfit,
        "misfit_dof": err.misfit_dof,
        "inflation": err.inflation,
        "failed": err.failed,
        "center_of_gravity": _vec(err.center_of_gravity),
        ("inertia_per_mass" if per else "inertia_tensor"): _rows(err.inertia),
        ("principal_moments_per_mass" if per else "principal_moments"): _vec(err.principal_moments),
        "principal_axes_deg": _vec(err.principal_axes_deg),
        ("stiffness_per_mass" if per else "stiffness_matrix"): _rows(err.stiffness),
        ("damping_per_mass" if per else "damping_matrix"): _rows(err.damping),
    }
    m = result.mounts
    if m is not None and m.stiffness_std is not None:
        factor = 1.0
        if result.identification.mass is not None:
            factor = force_units(result.units["length"], result.units["mass"], force_unit).factor
        damp = m.damping_std if m.damping_std is not None else np.full_like(m.stiffness_std, np.nan)
        out["mounts"] = [
            {"id": m.ids[k], "stiffness": _vec(factor * m.stiffness_std[k]), "damping": _plain(factor * damp[k])}
            for k in range(len(m.ids))
        ]
    if result.torque_roll_axis_std_deg is not None:
        out["torque_roll_axis_deg"] = result.torque_roll_axis_std_deg
    return out


def record_spread_to_dict(spread: RecordSpread) -> dict[str, Any]:
    """JSON form of record-segment intervals: per quantity ``{"estimate", "std", "ci95"}``, and
    ``method``, ``segments``, ``used``."""
    head = {"method": "interleaved record segments", "segments": spread.segments, "used": spread.used}
    return {**head, **_body_intervals(spread)}


def _body_intervals(source: RecordSpread | RecordBound) -> dict[str, Any]:
    """CG, inertia, principal moments and stiffness diagonal intervals; ``_per_mass`` keys without a mass."""
    suffix = "_per_mass" if source.per_mass else ""
    return {
        "center_of_gravity": interval_to_dict(source.center_of_gravity),
        ("inertia_per_mass" if source.per_mass else "inertia_tensor"): interval_to_dict(source.inertia),
        "principal_moments" + suffix: interval_to_dict(source.principal_moments),
        "stiffness_diagonal" + suffix: interval_to_dict(source.stiffness_diagonal),
    }


def corrections_by_sensor(correction: SensorCorrection, ids: Sequence[str]) -> dict[str, dict[str, Any]]:
    """JSON form of the sensors' estimated errors per sensor id (``sensor_corrections``).

    Parameters
    ----------
    correction : SensorCorrection
        :class:`rigidid.core.timedomain.refine.SensorCorrection` (rows gain, two tilts, three shifts).
    ids : sequence of str
        The fitted sensors' ids, in the correction's column order.

    Returns
    -------
    dict of str to dict
        Per id: ``gain``, ``gain_std``, ``tilt_rad`` and ``tilt_std_rad`` (two each) and ``determined``
        (gain, tilt 1, tilt 2); ``shift`` and ``shift_std`` (the position's x, y, z, layout length) and
        ``shift_determined`` (three each).
    """
    out = {}
    for i, name in enumerate(ids):
        out[name] = {
            "gain": float(correction.value[0, i]),
            "gain_std": float(correction.std[0, i]),
            "tilt_rad": [float(v) for v in correction.value[1:3, i]],
            "tilt_std_rad": [float(v) for v in correction.std[1:3, i]],
            "determined": [bool(v) for v in correction.determined[:3, i]],
            "shift": [float(v) for v in correction.value[3:, i]],
            "shift_std": [float(v) for v in correction.std[3:, i]],
            "shift_determined": [bool(v) for v in correction.determined[3:, i]],
        }
    return out


def record_bound_to_dict(bound: RecordBound) -> dict[str, Any]:
    """JSON form of the Cramér-Rao intervals of the refinement on the records: ``method``,
    ``normalised_cost``, ``noise_from``, ``residuals``, ``variance_from``, ``evaluations``,
    ``converged``, per quantity ``{"estimate", "std", "ci95"}``, with a pre-trigger the
    acceptance test's ``misfit_ratio``, ``misfit_p_value``, ``false_alarm_rate`` and ``misfit_expected``, with the
    delays estimated ``channel_delays`` (per channel id ``delay_s`` and ``std_s``), with hum found
    ``mains_hum_hz``, with the sensors' errors estimated ``sensor_corrections``, with stated tolerances the
    sensor test's ``sensor_test`` (``statistic``, ``dof``, ``p_value``, ``false_alarm_rate``,
    ``sensors_estimated``, ``correction_misfit_p_value``, ``correction_false_alarm_rate``), without a stated
    high-pass the AC coupling's test ``ac_coupling`` (``corner_hz``, ``corner_std_hz``, ``statistic``, ``dof``,
    ``p_value``, ``false_alarm_rate``, ``interior``, ``modelled``), and, when the sensors' tolerances were propagated,
    ``sensor_budget`` (per source, ``noise`` first, the std of ``center_of_gravity`` and ``inertia_tensor``) and
    ``tolerances`` (the bounds used)."""
    head = {
        "method": "Cramér-Rao bound at the output-error estimate on the records",
        "normalised_cost": bound.normalised_cost,
        "noise_from": bound.noise_from,
        "residuals": bound.residuals,
        "variance_from": bound.variance_from,
        "evaluations": bound.evaluations,
        "converged": bound.converged,
    }
    out = {**head, **_body_intervals(bound)}
    if bound.misfit is not None:
        out["misfit_ratio"] = bound.misfit.ratio
        out["misfit_p_value"] = bound.misfit.p_value
        out["false_alarm_rate"] = bound.misfit.false_alarm
        out["misfit_expected"] = bound.misfit.expected
    if bound.delays is not None:
        out["channel_delays"] = {name: {"delay_s": d, "std_s": sd} for name, (d, sd) in bound.delays.items()}
    if bound.hum_hz:
        out["mains_hum_hz"] = list(bound.hum_hz)
    if bound.sensor_correction is not None:
        out["sensor_corrections"] = corrections_by_sensor(bound.sensor_correction, bound.corrected_sensors)
    if bound.sensor_test is not None:
        test = bound.sensor_test
        out["sensor_test"] = {"statistic": test.statistic, "dof": test.dof, "p_value": test.p_value,
                              "false_alarm_rate": test.false_alarm, "sensors_estimated": test.estimated,
                              "correction_misfit_p_value": test.misfit_after,
                              "correction_false_alarm_rate": test.after_false_alarm}  # fmt: skip
    if bound.coupling is not None:
        found = bound.coupling
        out["ac_coupling"] = {"corner_hz": found.corner_hz, "corner_std_hz": _none_if_inf(found.corner_std_hz),
                              "statistic": found.statistic, "dof": found.dof, "p_value": found.p_value,
                              "false_alarm_rate": found.false_alarm, "interior": found.interior,
                              "modelled": found.modelled}  # fmt: skip
    if bound.sensor_budget is not None:
        inertia = "inertia_per_mass" if bound.per_mass else "inertia_tensor"
        out["sensor_budget"] = {
            source: {
                "center_of_gravity": parts["center_of_gravity"].tolist(),
                inertia: parts["inertia_per_mass"].tolist(),
            }
            for source, parts in bound.sensor_budget.items()
        }
        out["tolerances"] = bound.tolerances
    return out


def layout_report_to_dict(report: LayoutReport) -> dict[str, Any]:
    """JSON form of a layout check.

    Returns
    -------
    dict
        ``{"sensors", "rank", "condition" (None when infinite), "ok", "worst",
        "axis_counts": {"x", "y", "z", "oblique"}, "weakest_motion",
        "findings": [{"severity", "message", "code", "sensors"}]}``.
    """
    x, y, z, o = report.axis_counts
    return {
        "sensors": report.sensors,
        "rank": report.rank,
        "condition": _none_if_inf(report.condition),
        "ok": report.ok,
        "worst": report.worst,
        "axis_counts": {"x": x, "y": y, "z": z, "oblique": o},
        "weakest_motion": report.weakest_motion,
        "findings": [
            {"severity": f.severity, "message": f.message, "code": f.code, "sensors": list(f.sensors)}
            for f in report.findings
        ],
    }


def predicted_figures_to_dict(figures: PredictedFigures) -> dict[str, Any]:
    """JSON form of predicted figures (lists and floats; infinite and NaN values as None)."""
    return {
        "score": _none_if_inf(figures.score),
        "center_of_gravity_std": _plain(figures.center_of_gravity_std),
        "principal_moments_std": _plain(figures.principal_moments_std),
        "principal_moments_rel_std": _plain(figures.principal_moments_rel_std),
        "condition": _none_if_inf(figures.condition),
        "failed": figures.failed,
    }


def prediction_to_dict(prediction: Prediction) -> dict[str, Any]:
    """JSON form of a prediction: the figures, ``inertia_std`` and the full uncertainty."""
    out = predicted_figures_to_dict(prediction.figures)
    out["inertia_std"] = _plain(prediction.inertia_std)
    out["uncertainty"] = uncertainty_to_dict(prediction.uncertainty)
    return out


def sensor_plan_to_dict(plan: SensorPlan, *, ranking: int = 5) -> dict[str, Any]:
    """JSON form of sensor suggestions.

    Parameters
    ----------
    plan : SensorPlan
    ranking : int
        How many of the best candidates of each step to list.

    Returns
    -------
    dict
        ``{"baseline": {figures}, "steps": [{"step", "candidate", "position",
        "direction", "figures", "ranking": [{"candidate", "position",
        "direction", "score"}]}], "noise", "draws"}``.
    """

    def entry(c: int, score: float) -> dict[str, Any]:
        return {
            "candidate": c,
            "position": plan.candidate_positions[c].tolist(),
            "direction": plan.candidate_directions[c].tolist(),
            "score": _none_if_inf(score),
        }

    return {
        "baseline": predicted_figures_to_dict(plan.baseline),
        "steps": [
            {
                "step": s.step,
                "candidate": s.candidate,
                "position": s.position.tolist(),
                "direction": s.direction.tolist(),
                "figures": predicted_figures_to_dict(s.figures),
                "ranking": [entry(c, v) for c, v in s.ranking[:ranking]],
            }
            for s in plan.steps
        ],
        "noise": noise_to_dict(plan.noise),
        "draws": plan.draws,
    }


def plan_to_dict(plan: PlanResult) -> dict[str, Any]:
    """JSON form of ``rigidid plan``: units, layout findings, prediction, the predicted budget per source
    (``sensor_budget``, ``tolerances``) and suggestions (null when absent); with a records test planned, the
    refit's predicted budget (``records_sensor_budget``) and the test (``records_test``)."""
    return {
        "rigidid_version": __version__,
        "units": {**plan.units, "time": "s"},
        "layout": layout_report_to_dict(plan.report),
        "prediction": None if plan.prediction is None else prediction_to_dict(plan.prediction),
        "suggestions": None if plan.suggestions is None else sensor_plan_to_dict(plan.suggestions),
        "references": None if plan.references is None else reference_report_to_dict(plan.references),
        "sensor_budget": None if plan.sensor_budget is None else {
            source: {"center_of_gravity": _vec(parts["center_of_gravity"]),
                     "inertia_tensor": _rows(parts["inertia_tensor"]),
                     "stiffness_diagonal": _vec(parts["stiffness_diagonal"])}
            for source, parts in plan.sensor_budget.items()
        },
        "tolerances": plan.tolerances,
        **({} if plan.records_budget is None else {"records_sensor_budget": {
            source: {"center_of_gravity": _vec(parts["center_of_gravity"]),
                     "inertia_tensor": _rows(parts["inertia_tensor"]),
                     "stiffness_diagonal": _vec(parts["stiffness_diagonal"])}
            for source, parts in plan.records_budget.items()
        }, "records_test": plan.records_test}),
        **({} if plan.mount_split is None else {"mount_split": {
            "unknowns": plan.mount_split[0], "rank": plan.mount_split[1],
            "unique": plan.mount_split[0] == plan.mount_split[1], "statement": plan.mount_split[2],
        }}),
        **({} if plan.mount_prediction is None else {"mount_model_prediction": {
            "center_of_gravity_std": _vec(plan.mount_prediction.center_of_gravity_std),
            "inertia_std": _rows(plan.mount_prediction.inertia_std),
            "flagged": plan.mount_prediction.flagged, "draws": plan.mount_prediction.draws,
        }}),
    }  # fmt: skip


def reference_report_to_dict(report: ReferenceReport) -> dict[str, Any]:
    """JSON form of ``plan --references``: whether the references excite all six rigid-body motions.

    Returns
    -------
    dict
        ``{"references", "point", "load_rank", "coverage": {load: fraction},
        "weakest_load", "rank", "condition" (None when infinite),
        "weakest_parameter", "participation" (per mode, or None),
        "mode_frequencies_hz" (or None), "ok", "statement", "suggestion",
        "suggested_reference": {"position", "direction"},
        "suggested_condition" (None when infinite)}``.
    """
    from rigidid.core.plan import RIGID_LOADS

    return {
        "references": report.references,
        "point": report.point.tolist(),
        "load_rank": report.load_rank,
        "coverage": {name: float(v) for name, v in zip(RIGID_LOADS, report.coverage, strict=True)},
        "weakest_load": report.weakest_load,
        "rank": report.rank,
        "condition": _none_if_inf(report.condition),
        "weakest_parameter": report.weakest_parameter,
        "participation": None if report.participation is None else report.participation.tolist(),
        "mode_frequencies_hz": None if report.mode_frequencies is None else report.mode_frequencies.tolist(),
        "ok": report.ok,
        "statement": report.statement,
        "suggestion": report.suggestion,
        "suggested_reference": {
            "position": report.suggested_position.tolist(),
            "direction": report.suggested_direction.tolist(),
        },
        "suggested_condition": _none_if_inf(report.suggested_condition),
    }


def _stabilisation(diagram: Sequence[OrderPoles]) -> list[dict[str, Any]]:
    """The stabilisation diagram: per model order, its physical poles and which were stable."""
    return [
        {
            "order": entry.order,
            "frequency_hz": _vec(entry.frequency_hz),
            "damping_ratio": _vec(entry.damping_ratio),
            "stable": [bool(v) for v in entry.stable],
        }
        for entry in diagram
    ]


def estimate_to_dict(estimate: ModalEstimate) -> dict[str, Any]:
    """JSON form of a modal estimation from records, with its stabilisation diagram.

    Returns
    -------
    dict
        ``{"method", "sample_interval", "decimation", "band", "channels_fitted",
        "adequate_order", "impacts": [{"onset", "peak", "start"}], "modes":
        [{"mode", "frequency_hz", "damping_ratio", "stable_count",
        "model_order"}], "stabilisation": [{"order", "frequency_hz",
        "damping_ratio", "stable"}]}``.
    """
    return {
        "method": estimate.method,
        "sample_interval": estimate.sample_interval,
        "decimation": estimate.decimation,
        "band": list(estimate.band),
        "channels_fitted": estimate.channels_fitted,
        "adequate_order": estimate.adequate_order,
        "impacts": [{"onset": i.onset, "peak": i.peak, "start": i.start} for i in estimate.impacts],
        "modes": [
            {
                "mode": k + 1,
                "frequency_hz": float(estimate.frequency_hz[k]),
                "damping_ratio": float(estimate.damping_ratio[k]),
                "stable_count": int(estimate.stable_count[k]),
                "model_order": int(estimate.model_order[k]),
            }
            for k in range(len(estimate.frequency_hz))
        ],
        "stabilisation": _stabilisation(estimate.diagram),
    }


def _frf_intervals(ml: MassLine) -> dict[str, Any] | None:
    """The ``intervals`` block of an FRF route's answer (None without intervals)."""
    if ml.intervals is None:
        return None
    return {
        "method": ml.intervals.method,
        "mass": interval_to_dict(ml.intervals.mass),
        "center_of_gravity": interval_to_dict(ml.intervals.center_of_gravity),
        "inertia_tensor": interval_to_dict(ml.intervals.inertia_tensor),
    }


def massline_to_dict(result: MassLineResult) -> dict[str, Any]:
    """The JSON of ``identify --method massline`` (FORMATS.md, "Mass line result")."""
    ml = result.massline
    out: dict[str, Any] = {
        "rigidid_version": __version__,
        "route": result.route,
        "route_reason": result.reason,
        "units": dict(result.units),
        "mass_measured": float(ml.mass),
        "center_of_gravity": _vec(ml.center_of_gravity),
        "inertia_tensor": _rows(ml.inertia_tensor),
        "band_hz": [float(ml.band[0]), float(ml.band[1])],
        "band_source": ml.band_source,
        "frequencies_used": int(ml.frequencies_used),
        "relative_residual": float(ml.residual),
        "corrections": list(ml.corrections),
        "supports": ml.supports,
        "supports_reason": ml.supports_reason,
        "mass_given": None,
        "mass_difference": None,
        "mass_difference_relative": None,
        "misfit_noise_units": None if ml.misfit_noise_units is None else float(ml.misfit_noise_units),
        "misfit_where": ml.misfit_where,
        "intervals": _frf_intervals(ml),
    }
    if result.mass_given is not None:
        out["mass_given"] = float(result.mass_given)
        out["mass_difference"] = float(ml.mass - result.mass_given)
        out["mass_difference_relative"] = float(ml.mass / result.mass_given - 1.0)
    out["routes"] = [
        {
            "route": a.route,
            "applies": a.applies,
            "chosen": a.applies and a.route == result.route,
            "reason": a.reason,
            "mass_measured": None if a.massline is None else float(a.massline.mass),
            "center_of_gravity": None if a.massline is None else _vec(a.massline.center_of_gravity),
            "inertia_tensor": None if a.massline is None else _rows(a.massline.inertia_tensor),
            "misfit_noise_units": None
            if a.massline is None or a.massline.misfit_noise_units is None
            else float(a.massline.misfit_noise_units),
            "intervals": None if a.massline is None else _frf_intervals(a.massline),
        }
        for a in result.routes
    ]
    sb = result.scaled
    out["scaled_modes"] = (
        None
        if sb is None
        else {
            "mass": float(sb.mass),
            "center_of_gravity": _vec(sb.center_of_gravity),
            "inertia_tensor": _rows(sb.inertia_tensor),
            "stiffness_matrix": _rows(sb.stiffness_matrix),
            "damping_matrix": _rows(sb.damping_matrix),
        }
    )
    return out


def frf_modes_to_dict(fitted: FrfModes) -> dict[str, Any]:
    """JSON form of modes fitted to FRFs (``modes --frf --json``), with its stabilisation diagram.

    Returns
    -------
    dict
        ``{"method": "plscf", "band", "residue_band", "relative_residual", "modes": [{"mode",
        "frequency_hz", "damping_ratio", "stable_count", "scaling"}], "stabilisation": [{"order",
        "frequency_hz", "damping_ratio", "stable"}]}`` (the diagram as for records).
    """
    return {
        "method": "plscf",
        "band": [float(v) for v in fitted.band],
        "residue_band": [float(v) for v in fitted.residue_band],
        "relative_residual": float(fitted.residual),
        "modes": [
            {
                "mode": k + 1,
                "frequency_hz": float(fitted.frequency_hz[k]),
                "damping_ratio": float(fitted.damping_ratio[k]),
                "stable_count": int(fitted.stable_count[k]),
                "scaling": "modal_a" if fitted.scaled[k] else "unit_max",
            }
            for k in range(fitted.poles.size)
        ],
        "stabilisation": _stabilisation(fitted.diagram),
    }
