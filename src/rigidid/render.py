"""Rich tables of results. Nothing here prints; the JSON forms are in :mod:`rigidid.jsonout`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid.results import IdentifyResult, PlanResult

if TYPE_CHECKING:
    from rich.console import Group
    from rich.table import Table

    from rigidid.core.noise import NoiseLevels
    from rigidid.core.plan import ReferenceReport
    from rigidid.core.timedomain import ModalEstimate
    from rigidid.results import MassLineResult

__all__ = ["estimate_tables", "massline_tables", "plan_tables", "result_csv_files", "result_tables"]

DOF = ("x", "y", "z", "rx", "ry", "rz")


ROUNDING_ZERO = 1e-9
"""A square matrix's entry ``a_ij`` below this fraction of ``sqrt(|a_ii a_jj|)`` prints as 0: exact data
leave entries at about 1e-10 of that scale where the truth is zero."""


def _fmt(v: float) -> str:
    """Five significant digits in at most 10 characters: plain from 0.01 to 99999, else engineering notation.

    ``245410 -> 245.41e3``, ``1.70996e7 -> 17.100e6``, ``0.00043617 -> 436.17e-6``; four digits
    with a two-digit exponent (``-4.0635e-11 -> -40.64e-12``).
    """
    if v == 0.0 or not np.isfinite(v):
        return "0" if v == 0.0 else str(v)
    e = int(np.floor(np.log10(abs(v))))
    if -2 <= e < 5:
        return f"{v:.{max(0, 4 - e)}f}"
    e3 = 3 * (e // 3)
    digits = 5 if -10 < e3 < 10 else 4  # a two-digit exponent costs a digit of the mantissa
    mantissa = v / 10.0**e3
    if abs(round(mantissa, digits - 1 - (e - e3))) >= 1000.0:  # rounding carried to the next power of 1000
        e3 += 3
        e = e3
        digits = 5 if -10 < e3 < 10 else 4
        mantissa /= 1000.0
    return f"{mantissa:.{max(0, digits - 1 - (e - e3))}f}e{e3}"


def _unit(text: str) -> str:
    """A unit as the tables show it: one word (``N·mm/rad``), so a wrapped title never breaks inside it."""
    return text.replace(" ", "\u00b7")


def _matrix_table(title: str, a: NDArray[np.float64], labels: Sequence[str], caption: str | None = None) -> Table:
    from rich import box
    from rich.table import Table

    table = Table(
        title=title,
        caption=caption,
        title_justify="left",
        caption_justify="left",
        box=box.SIMPLE_HEAD,
        show_edge=False,
        collapse_padding=True,
        pad_edge=False,
    )
    table.add_column("")
    for name in labels:
        table.add_column(name, justify="right")
    # entries below the rounding of their diagonal's scale are numerical zeros, not figures (60.174e-9 beside
    # 1e5); sqrt(|a_ii a_jj|) has the entry's own unit in the mixed-unit blocks of K and C
    floor = np.zeros_like(a)
    if a.ndim == 2 and a.shape[0] == a.shape[1] and np.all(np.isfinite(a)):
        scale = np.sqrt(np.abs(np.diag(a)))
        floor = ROUNDING_ZERO * np.outer(scale, scale)
    for name, row, low in zip(labels, a, floor, strict=True):
        table.add_row(name, *(_fmt(0.0 if abs(float(v)) < f else float(v)) for v, f in zip(row, low, strict=True)))
    return table


def result_tables(result: IdentifyResult, force_unit: str | None = None) -> Group:
    """Rich tables of CG, inertia, principal axes, stiffness, damping and diagnostics.

    Parameters
    ----------
    result : IdentifyResult
    force_unit : {"N", "kN", "lbf"}, optional
        Stiffness and damping in this force unit (default N for kg, g and t,
        lbf for lb and slug); without a mass they stay per unit mass.

    Returns
    -------
    rich.console.Group
        Render it with a rich console; nothing is printed here.
    """
    from rich.console import Group

    return Group(
        *_mass_tables(result),
        *_scaled_tables(result),
        *_support_tables(result, force_unit),
        *_mount_tables(result, force_unit),
        _energy_table(result),
        *_uncertainty_tables(result, force_unit),
        _modes_table(result),
        _diagnostics_table(result),
    )


def _mass_tables(result: IdentifyResult) -> list[Table]:
    """Centre of gravity, inertia tensor, principal moments and axes."""
    from rich.table import Table

    ident = result.identification
    length, mass = result.units["length"], result.units["mass"]
    absolute = ident.mass is not None
    per = "" if absolute else f" / {mass}"
    m = ident.mass if ident.mass is not None else 1.0
    head = Table(title="Centre of gravity", title_justify="left")
    for axis in ("x", "y", "z"):
        head.add_column(f"{axis} ({length})", justify="right")
    head.add_row(*(_fmt(float(v)) for v in ident.center_of_gravity))
    note = None if absolute else "no mass given: values per unit mass (pass --mass or set mass in the layout)"
    inertia = _matrix_table(
        f"Inertia tensor about the CG ({mass}·{length}^2{per})",
        m * ident.inertia_per_mass,
        ("x", "y", "z"),
        "off-diagonal entries are minus the products of inertia" + (f"; {note}" if note else ""),
    )
    principal = Table(title="Principal moments and axes", title_justify="left")
    principal.add_column(f"moment ({mass}·{length}^2{per})", justify="right")
    for axis in ("x", "y", "z"):
        principal.add_column(f"axis {axis}", justify="right")
    moments = m * ident.principal_moments_per_mass
    for k in range(3):
        principal.add_row(_fmt(float(moments[k])), *(f"{float(v):+.4f}" for v in ident.principal_axes[:, k]))
    return [head, inertia, principal]


def _scaled_tables(result: IdentifyResult) -> list[Table]:
    """The body from the modes scaled by the force (modes.csv ``modal_a``): mass measured, CG, inertia."""
    from rich.table import Table

    sb = result.scaled
    if sb is None:
        return []
    length, mass = result.units["length"], result.units["mass"]
    table = Table(title="Scaled modes (modal_a: the force scales them)", title_justify="left", show_header=False)
    table.add_row("mass measured", f"{_fmt(sb.mass)} {mass}")
    given = result.identification.mass
    if given is not None:
        diff = sb.mass - given
        table.add_row("mass given", f"{_fmt(given)} {mass}")
        table.add_row("difference", f"{_fmt(diff)} {mass} ({100.0 * diff / given:+.2f} %)")
    table.add_row(f"CG ({length})", _vector(sb.center_of_gravity))
    inertia = _matrix_table(
        f"Inertia tensor about the CG from the scaled modes ({mass}·{length}^2)", sb.inertia_tensor, ("x", "y", "z")
    )
    return [table, inertia]


def _mount_tables(result: IdentifyResult, force_unit: str | None) -> list[Table]:
    """Per-mount rates along each mount's axes, and the torque roll axis, when asked for."""
    from rich.table import Table

    from rigidid.units import rate_units

    tables = []
    if result.mounts is not None:
        mounts = result.mounts
        rates = mounts.rates
        per_mass = result.identification.mass is None
        factor, k_unit, c_unit = rate_units(result.units["length"], result.units["mass"], force_unit, per_mass=per_mass)
        table = Table(
            title=f"Mounts: rates along their axes (stiffness {_unit(k_unit)}, damping {_unit(c_unit)})",
            caption=f"fit residual {rates.stiffness_residual:.2e} of |K|; {rates.statement}",
            title_justify="left",
            caption_justify="left",
        )
        for name in ("mount", "k1", "k2", "k3", "c1", "c2", "c3"):
            table.add_column(name, justify="left" if name == "mount" else "right")
        for k, name in enumerate(mounts.ids):
            damping = ["-"] * 3 if rates.damping is None else [_fmt(factor * v) for v in rates.damping[k]]
            table.add_row(name, *(_fmt(factor * v) for v in rates.stiffness[k]), *damping)
            if mounts.nominal is not None:  # the data sheet beside the test (the JSON's nominal_stiffness)
                table.add_row("  data sheet", *(_fmt(factor * v) for v in mounts.nominal[k]), "", "", "",
                              style="dim")  # fmt: skip
        tables.append(table)
    if result.mount_model is not None:
        fit = result.mount_model
        model = fit.model
        table = Table(title="Mount model", title_justify="left", show_header=False)
        table.add_column("item")
        table.add_column("value")
        table.add_row("unknowns / equations", f"{model.parameters} / {model.equations}")
        free = "-" if fit.free_residual is None else f"{fit.free_residual:.3g}"
        table.add_row(
            "eigenproblem residual",
            f"{fit.residual:.3g} (free route: {free})",
        )
        if model.p_value is not None and model.f_dof is not None:
            table.add_row(
                "F test against any linear model",
                f"F = {model.f_statistic:.3g} with ({model.f_dof[0]}, {model.f_dof[1]}) dof, p = {model.p_value:.3g}",
            )
        verdict = "not tested" if fit.verdict is None else "the mounts explain the modes"
        if fit.verdict is False:
            verdict = "INADEQUATE: a mount position or axis is off, or a support is missing; trust the free route"
        table.add_row("verdict", verdict)
        tables.append(table)
    if result.torque_roll_axis is not None:
        tra = result.torque_roll_axis
        table = Table(title="Torque roll axis", title_justify="left", show_header=False)
        table.add_column("item")
        table.add_column("value")
        table.add_row("torque axis", _vector(tra.torque_axis))
        table.add_row("rotation direction J^-1 t", _vector(tra.direction))
        table.add_row("angle to the torque axis", f"{tra.angle_to_torque_deg:.2f} deg")
        angles = ", ".join(f"{a:.2f}" for a in tra.angle_to_principal_deg)
        table.add_row("angles to the principal axes", f"{angles} deg")
        tables.append(table)
    return tables


def _energy_table(result: IdentifyResult) -> Table:
    """The decoupling table: each mode's kinetic energy per motion at the CG."""
    from rich.table import Table

    from rigidid.core.energy import kinetic_energy_distribution

    ident = result.identification
    energy = Table(
        title="Kinetic energy distribution at the CG (%)",
        caption="decoupling table: share of each mode's kinetic energy per motion; rows sum to 100",
        title_justify="left",
        caption_justify="left",
    )
    energy.add_column("mode", justify="right")
    for name in DOF:
        energy.add_column(name, justify="right")
    table = kinetic_energy_distribution(ident.inertia_per_mass, ident.mode_shapes_cg)
    for label, row in zip(result.modes_used, table, strict=True):
        top = int(np.argmax(row))
        energy.add_row(
            str(label), *(f"[bold]{100 * v:.1f}[/bold]" if i == top else f"{100 * v:.1f}" for i, v in enumerate(row))
        )
    return energy


def _uncertainty_tables(result: IdentifyResult, force_unit: str | None) -> list[Table]:
    """Monte Carlo intervals and record-segment intervals, when computed."""
    length = result.units["length"]
    tables = []
    if result.uncertainty is not None:
        unc = result.uncertainty
        caption = _noise_caption(unc.noise, length)
        caption += f"; {unc.failed} draws failed" if unc.failed else ""
        caption += f"; {unc.implausible} draws physically implausible" if unc.implausible else ""
        title = f"Uncertainty ({unc.draws} Monte Carlo draws, 95 % intervals)"
        tables.append(_interval_table(result, unc, title, caption, force_unit))
    if result.standard_errors is not None and result.uncertainty is None:
        tables.append(_standard_error_table(result, force_unit))
    if result.record_spread is not None:
        spread = result.record_spread
        title = (
            f"Uncertainty from the records ({spread.used} of {spread.segments} interleaved segments, 95 % intervals)"
        )
        caption = "spread of the segment estimates scaled to all the data; noise only, not sensor placement errors"
        tables.append(_interval_table(result, spread, title, caption, force_unit))
    if result.record_bound is not None:
        bound = result.record_bound
        title = "Uncertainty from the records (Cramér-Rao bound at the output-error fit, 95 % intervals)"
        caption = (
            f"{bound.residuals} residuals, normalised cost {bound.normalised_cost:.3g} (about 1 at a good fit), "
            f"noise levels from the {bound.noise_from}; noise only, not sensor placement errors"
        )
        tables.append(_interval_table(result, bound, title, caption, force_unit))
    return tables


def _standard_error_table(result: IdentifyResult, force_unit: str | None) -> Table:
    """The default linearised standard errors, as the interval table (estimate +- 1.96 std)."""
    from types import SimpleNamespace

    from rigidid.core.uncertainty import IntervalEstimate

    err = result.standard_errors
    assert err is not None
    ident = result.identification
    scale = 1.0 if ident.mass is None else ident.mass

    def interval(value: NDArray[np.float64], std: NDArray[np.float64]) -> IntervalEstimate:
        return IntervalEstimate(value, std, value - 1.96 * std, value + 1.96 * std)

    unc = SimpleNamespace(
        per_mass=err.per_mass,
        center_of_gravity=interval(ident.center_of_gravity, err.center_of_gravity),
        inertia=interval(scale * ident.inertia_per_mass, err.inertia),
        principal_moments=interval(scale * ident.principal_moments_per_mass, err.principal_moments),
        stiffness_diagonal=interval(scale * np.diag(ident.stiffness_per_mass), np.diag(err.stiffness)),
    )
    axes = ", ".join(f"{v:.2g}" for v in err.principal_axes_deg)
    caption = _noise_caption(err.noise, result.units["length"])
    caption += f"; principal axes +- {axes} deg (1 std)"
    if result.torque_roll_axis_std_deg is not None:
        caption += f"; torque roll axis +- {result.torque_roll_axis_std_deg:.2g} deg"
    if err.misfit is not None:
        caption += f"; misfit {err.misfit:.3g} on {err.misfit_dof} degrees of freedom"
        caption += f" (std scaled by {err.inflation:.3g})" if err.inflation > 1.0 else ""
    title = "Standard errors (linearised at the estimate, 95 % intervals; --uncertainty N for Monte Carlo)"
    return _interval_table(result, unc, title, caption, force_unit)


def _modes_table(result: IdentifyResult) -> Table:
    """The modes used against the identified model's modes."""
    from rich.table import Table

    ident = result.identification
    diag = ident.diagnostics
    modes = Table(title="Modes used", title_justify="left")
    for name in ("mode", "f (Hz)", "zeta (-)", "rigid fit (-)", "model f (Hz)", "model zeta (-)", "MAC (-)"):
        modes.add_column(name, justify="right")
    for k, label in enumerate(result.modes_used):
        modes.add_row(
            str(label),
            f"{ident.frequency_hz[k]:.4f}",
            f"{ident.damping_ratio[k]:.5f}",
            f"{diag.rigid_fit_residual[k]:.2e}",
            f"{diag.model_frequency_hz[k]:.4f}",
            f"{diag.model_damping_ratio[k]:.5f}",
            f"{diag.model_mac[k]:.4f}",
        )
    return modes


def _diagnostics_table(result: IdentifyResult) -> Table:
    """Method, mode choice, conditioning, structure residual, observability and the warnings."""
    from rich.table import Table

    ident = result.identification
    diag = ident.diagnostics
    summary = Table(title="Diagnostics", title_justify="left", show_header=False)
    summary.add_column("item")
    summary.add_column("value")
    summary.add_row("method", ident.method)
    summary.add_row(
        "modes chosen",
        {"all": "all six given", "given": "by --modes", "automatic": "six most rigid-body-like"}[result.selection],
    )
    summary.add_row("layout condition number", f"{diag.layout_condition:.4g} (rank {diag.layout_rank})")
    summary.add_row("structure residual", f"{diag.structure_residual:.3e}")
    summary.add_row("inertia observability", f"{diag.inertia_observability:.3g} (typical 0.1-0.3)")
    if result.candidate_residuals is not None:
        text = ", ".join(f"{label}: {r:.2e}" for label, r in result.candidate_residuals.items())
        summary.add_row("rigid fit of every mode", text)
    for message in diag.warnings:
        summary.add_row("[yellow]warning[/yellow]", message)
    return summary


def _support_tables(result: IdentifyResult, force_unit: str | None) -> list[Table]:
    """Stiffness and damping at the CG: in force units with a mass, else per unit mass."""
    from rigidid.units import force_units

    ident = result.identification
    length, mass = result.units["length"], result.units["mass"]
    tables = []
    if ident.mass is None:
        for name, mat, t in (("Stiffness", ident.stiffness_per_mass, "s^2"), ("Damping", ident.damping_per_mass, "s")):
            caption = (
                f"units / {mass}: {mass}/{t} (x-z rows and columns), {mass}·{length}/{t} (coupling), "
                f"{mass}·{length}^2/{t} (rx-rz block); rotations in rad"
            )
            tables.append(_matrix_table(f"{name} of the supports at the CG, per unit mass", mat, DOF, caption))
        return tables
    fu = force_units(length, mass, force_unit)
    for name, per_mass, u in (
        ("Stiffness", ident.stiffness_per_mass, fu.stiffness),
        ("Damping", ident.damping_per_mass, fu.damping),
    ):
        mat = ident.mass * per_mass
        title = f"{name} of the supports at the CG ({_unit(u['translation'])}, {_unit(u['rotation'])})"
        caption = (
            f"x-z block {_unit(u['translation'])}, rx-rz block {_unit(u['rotation'])}, coupling blocks "
            f"{_unit(u['coupling'])}; "
            "rotations in rad"
        )
        tables.append(_matrix_table(title, fu.factor * mat, DOF, caption))
    tables.append(_diagonal_table(result, force_unit))
    return tables


def _diagonal_table(result: IdentifyResult, force_unit: str | None) -> Table:
    """The diagonals of stiffness and damping, in the units of the matrices above (one unit throughout)."""
    from rich.table import Table

    from rigidid.units import force_units

    ident = result.identification
    assert ident.mass is not None
    fu = force_units(result.units["length"], result.units["mass"], force_unit)
    table = Table(title="Supports at the CG, diagonal terms", title_justify="left")
    for name in ("dof", "stiffness", "unit", "damping", "unit "):
        table.add_column(name, justify="left" if name.startswith(("dof", "unit")) else "right")
    for i, dof in enumerate(DOF):
        block = "translation" if i < 3 else "rotation"
        k = ident.mass * fu.factor * float(ident.stiffness_per_mass[i, i])
        c = ident.mass * fu.factor * float(ident.damping_per_mass[i, i])
        table.add_row(dof, _fmt(k), _unit(fu.stiffness[block]), _fmt(c), _unit(fu.damping[block]))
    return table


def _interval_table(result: IdentifyResult, unc: Any, title: str, caption: str, force_unit: str | None = None) -> Table:
    """Estimate, standard deviation and 95 % interval of the main results."""
    from rich.table import Table

    from rigidid.units import force_units

    length, mass = result.units["length"], result.units["mass"]
    per = f" / {mass}" if unc.per_mass else ""
    table = Table(title=title, caption=caption, title_justify="left", caption_justify="left")
    for name in ("quantity", "estimate", "std", "95 % interval"):
        table.add_column(name, justify="left" if name == "quantity" else "right")

    def rows(
        name: str,
        unit: str,
        interval: Any,
        labels: Sequence[str],
        flat: Sequence[int] | None = None,
        scale: float = 1.0,
    ) -> None:
        values = [scale * np.ravel(getattr(interval, key)) for key in ("estimate", "std", "low", "high")]
        for label, i in zip(labels, flat if flat is not None else range(len(labels)), strict=True):
            est, std, low, high = (float(v[i]) for v in values)
            table.add_row(f"{name}{label} ({_unit(unit)})", _fmt(est), _fmt(std), f"{_fmt(low)} .. {_fmt(high)}")

    rows("CG ", length, unc.center_of_gravity, ("x", "y", "z"))
    # upper triangle of the symmetric tensor, flat indices into the 3x3 entries
    rows("J_", f"{mass}·{length}^2{per}", unc.inertia, ("xx", "yy", "zz", "xy", "xz", "yz"), (0, 4, 8, 1, 2, 5))
    rows("principal moment ", f"{mass}·{length}^2{per}", unc.principal_moments, ("1", "2", "3"))
    if unc.per_mass:
        rows("stiffness ", f"{mass}/s^2{per}", unc.stiffness_diagonal, DOF[:3])
        rows("stiffness ", f"{mass}·{length}^2/s^2{per}", unc.stiffness_diagonal, DOF[3:], (3, 4, 5))
    else:
        fu = force_units(length, mass, force_unit)
        rows("stiffness ", fu.stiffness["translation"], unc.stiffness_diagonal, DOF[:3], scale=fu.factor)
        rows("stiffness ", fu.stiffness["rotation"], unc.stiffness_diagonal, DOF[3:], (3, 4, 5), scale=fu.factor)
    return table


def _noise_caption(noise: NoiseLevels, length: str) -> str:
    parts = [
        f"frequency {100 * noise.frequency:.3g} %",
        f"damping {100 * noise.damping:.3g} %",
        f"shape {100 * noise.shape:.3g} %",
    ]
    if noise.position:
        parts.append(f"position {noise.position:.3g} {length}")
    if noise.angle_deg:
        parts.append(f"direction {noise.angle_deg:.3g} deg")
    return "standard deviations assumed: " + ", ".join(parts)


_SEVERITY_STYLE = {"error": "bold red", "warning": "yellow", "info": "cyan"}


def _vector(v: Sequence[float] | NDArray[np.float64]) -> str:
    return "(" + ", ".join(_fmt(float(x)) for x in v) + ")"


def plan_tables(plan: PlanResult) -> Group:
    """Rich tables of ``rigidid plan``: layout summary and findings, predictions, suggested sensors."""
    from rich.console import Group
    from rich.table import Table

    report = plan.report
    length, mass = plan.units["length"], plan.units["mass"]
    summary = Table(title="Sensor layout", title_justify="left", show_header=False)
    summary.add_column("item")
    summary.add_column("value")
    summary.add_row("sensors", str(report.sensors))
    x, y, z, oblique = report.axis_counts
    summary.add_row("along x / y / z / oblique", f"{x} / {y} / {z} / {oblique}")
    summary.add_row("rank (6 needed)", str(report.rank))
    summary.add_row("condition number", "infinite" if not np.isfinite(report.condition) else f"{report.condition:.3g}")
    summary.add_row("hardest motion to see", report.weakest_motion)
    verdict = "ready" if report.ok else "not usable as it is"
    summary.add_row("verdict", f"[{_SEVERITY_STYLE[report.worst]}]{verdict}[/]" if report.findings else verdict)
    if plan.mount_split is not None:
        summary.add_row("per-mount rates", plan.mount_split[2])
    if plan.mount_prediction is not None:
        mp = plan.mount_prediction
        summary.add_row(
            f"mount model: predicted std ({f'{mp.draws} draws' if mp.draws else 'first order'})",
            f"CG {', '.join(_fmt(float(v)) for v in mp.center_of_gravity_std)} {length}; inertia diagonal "
            f"{', '.join(_fmt(float(v)) for v in np.diag(mp.inertia_std))} {mass}·{length}^2",
        )
    parts: list[Any] = [summary]
    if report.findings:
        findings = Table(title="Findings", title_justify="left")
        findings.add_column("severity")
        findings.add_column("finding")
        for finding in report.findings:
            findings.add_row(f"[{_SEVERITY_STYLE[finding.severity]}]{finding.severity}[/]", finding.message)
        parts.append(findings)
    if plan.prediction is not None:
        fig = plan.prediction.figures
        pred = Table(
            title="Predicted uncertainty (standard deviation)",
            caption=_noise_caption(plan.prediction.uncertainty.noise, length),
            title_justify="left",
            caption_justify="left",
        )
        pred.add_column("quantity")
        pred.add_column("std", justify="right")
        for axis, v in zip("xyz", fig.center_of_gravity_std, strict=True):
            pred.add_row(f"CG {axis} ({length})", _fmt(float(v)))
        for k in range(3):
            pred.add_row(
                f"principal moment {k + 1} ({mass}·{length}^2)",
                f"{_fmt(float(fig.principal_moments_std[k]))} ({100 * fig.principal_moments_rel_std[k]:.2g} %)",
            )
        parts.append(pred)
    if plan.sensor_budget is not None:
        parts.append(_budget_table(plan.sensor_budget, plan.tolerances or {}, length, mass))
    if plan.records_budget is not None:
        parts.append(_budget_table(plan.records_budget, plan.tolerances or {}, length, mass, plan.records_test))
    if plan.suggestions is not None:
        parts.append(_suggestions_table(plan.suggestions, length))
    if plan.references is not None:
        parts.append(_reference_table(plan.references))
    return Group(*parts)


def _budget_table(
    budget: dict[str, dict[str, Any]],
    tolerances: dict[str, float],
    length: str,
    mass: str,
    records: dict[str, Any] | None = None,
) -> Table:
    """``plan`` with a body: the predicted standard deviation of each figure per source (noise, each tolerance);
    with `records` (the planned records test), the records route's: the refit's own."""
    from rich.table import Table

    stated = ", ".join(f"{k} {v:g}" for k, v in tolerances.items())
    if records is None:
        title = "Predicted budget (standard deviation per source)"
        caption = f"tolerances (bounds): {stated}; combined: all sources in quadrature"
    else:
        title = "Predicted sensor budget, records route (identify --records: the refit's own)"
        caption = (
            f"{len(records['impacts'])} impacts, {records['sample_rate_hz']:g} Hz, {records['duration_s']:g} s "
            f"(fitted at 1/{records['fit_decimation']}), noise {records['noise']:g} of each channel's RMS; "
            f"tolerances (bounds): {stated}; sensors: the four in quadrature; combined: with the noise"
        )
    table = Table(title=title, caption=caption, title_justify="left", caption_justify="left")
    table.add_column("quantity")
    for source in budget:
        table.add_column(source, justify="right")
    rows: list[tuple[str, str, int]] = [(f"CG {a} ({length})", "center_of_gravity", i) for i, a in enumerate("xyz")]
    rows += [(f"I{a}{a} ({mass}·{length}^2)", "inertia_tensor", i) for i, a in enumerate("xyz")]
    units = [f"{mass}/s^2"] * 3 + [f"{mass}·{length}^2/s^2"] * 3
    rows += [(f"K {name} ({unit})", "stiffness_diagonal", i)
             for i, (name, unit) in enumerate(zip(("x", "y", "z", "rx", "ry", "rz"), units, strict=True))]  # fmt: skip
    for label, key, i in rows:
        values = [np.asarray(parts[key]) for parts in budget.values()]
        table.add_row(label, *(_fmt(float(v[i, i] if v.ndim == 2 else v[i])) for v in values))
    return table


def _suggestions_table(suggestions: Any, length: str) -> Table:
    """``plan --add``: the sensors to add, best first, each column with its unit."""
    from rich.table import Table

    sug = Table(
        title="Sensors to add (greedy, best first)",
        caption="score: |CG std| over the body's radius of gyration plus |moments' relative std| (smaller is better)",
        title_justify="left",
        caption_justify="left",
    )
    for name in (
        "step", f"position ({length})", "direction (unit)", f"CG std ({length})", "moments rel. std (-)",
        "score (-)",
    ):  # fmt: skip
        sug.add_column(name, justify="right")
    base = suggestions.baseline
    sug.add_row(
        "now",
        "",
        "",
        _vector(base.center_of_gravity_std),
        _vector(base.principal_moments_rel_std),
        _fmt(base.score),
    )
    for step in suggestions.steps:
        f = step.figures
        sug.add_row(
            str(step.step),
            _vector(step.position),
            _vector(step.direction),
            _vector(f.center_of_gravity_std),
            _vector(f.principal_moments_rel_std),
            _fmt(f.score),
        )
    return sug


def _reference_table(report: ReferenceReport) -> Table:
    """``plan --references``: the reference (hammer) points against the six rigid-body motions."""
    from rich.table import Table

    from rigidid.core.plan import RIGID_LOADS

    table = Table(title="Reference (hammer) points", title_justify="left", show_header=False)
    table.add_column("item")
    table.add_column("value")
    table.add_row("references", str(report.references))
    table.add_row("inertial parameters determined (10 needed)", str(report.rank))
    table.add_row("condition number", "infinite" if not np.isfinite(report.condition) else f"{report.condition:.3g}")
    table.add_row("load coverage", ", ".join(f"{n} {v:.0%}" for n, v in zip(RIGID_LOADS, report.coverage, strict=True)))
    if report.participation is not None and report.mode_frequencies is not None:
        table.add_row(
            "mode participation",
            ", ".join(
                f"{f:.3g} Hz {p:.0%}" for f, p in zip(report.mode_frequencies, report.participation, strict=True)
            ),
        )
    table.add_row("verdict", ("ready: " if report.ok else "[red]not usable as it is[/]: ") + report.statement)
    table.add_row("to add", report.suggestion)
    return table


def estimate_tables(estimate: ModalEstimate) -> Group:
    """Rich summary of a modal estimation: the modes found and the stabilisation sweep."""
    from rich.console import Group
    from rich.table import Table

    modes = Table(
        title=f"Modes estimated from the records ({estimate.method.upper()})",
        caption=(
            f"band {estimate.band[0]:.4g}-{estimate.band[1]:.4g} Hz, decimation x{estimate.decimation}, "
            f"{estimate.channels_fitted} channels fitted, {len(estimate.impacts)} records, "
            f"{len(estimate.diagram)} model orders swept"
        ),
        title_justify="left",
        caption_justify="left",
    )
    for name in ("mode", "f (Hz)", "zeta", "stable at orders", "taken from order"):
        modes.add_column(name, justify="right")
    for k in range(len(estimate.frequency_hz)):
        modes.add_row(
            str(k + 1),
            f"{estimate.frequency_hz[k]:.4f}",
            f"{estimate.damping_ratio[k]:.5f}",
            str(int(estimate.stable_count[k])),
            str(int(estimate.model_order[k])),
        )
    sweep = Table(title="Stabilisation (poles per model order)", title_justify="left")
    for name in ("order", "physical poles", "stable"):
        sweep.add_column(name, justify="right")
    for entry in estimate.diagram:
        sweep.add_row(str(entry.order), str(len(entry.poles)), str(int(np.sum(entry.stable))))
    return Group(modes, sweep)


def result_csv_files(result: IdentifyResult, force_unit: str | None = None) -> dict[str, str]:
    """Each result matrix as CSV text for spreadsheets: file name -> text.

    Parameters
    ----------
    result : IdentifyResult
    force_unit : {"N", "kN", "lbf"}, optional
        Force unit of ``stiffness.csv`` and ``damping.csv`` (as :func:`result_tables`).

    Returns
    -------
    dict
        ``center_of_gravity.csv``, ``inertia.csv``, ``principal.csv``,
        ``stiffness.csv``, ``damping.csv``, ``energy_distribution.csv``: a header
        row naming the columns (with units), then one row per matrix row with
        its label first; numbers with 17 significant digits (``repr``).
    """
    from rigidid.core.energy import kinetic_energy_distribution
    from rigidid.units import force_units

    ident = result.identification
    length, mass = result.units["length"], result.units["mass"]
    has_mass = ident.mass is not None

    def text(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
        lines = [",".join(header)]
        lines += [",".join(v if isinstance(v, str) else repr(float(v)) for v in row) for row in rows]  # type: ignore[arg-type]
        return "\n".join(lines) + "\n"

    inertia = ident.inertia_tensor if ident.inertia_tensor is not None else ident.inertia_per_mass
    j_unit = f"{mass}·{length}^2" if has_mass else f"{length}^2 per {mass}"
    moments = ident.principal_moments if ident.principal_moments is not None else ident.principal_moments_per_mass
    out = {
        "center_of_gravity.csv": text(
            ["axis", f"cg ({length})"], [[a, v] for a, v in zip("xyz", ident.center_of_gravity, strict=True)]
        ),
        "inertia.csv": text([f"({j_unit})", "x", "y", "z"], [[a, *row] for a, row in zip("xyz", inertia, strict=True)]),
        "principal.csv": text(
            ["axis", f"moment ({j_unit})", "x", "y", "z"],
            [[str(k + 1), moments[k], *ident.principal_axes[:, k]] for k in range(3)],
        ),
    }
    if has_mass:
        fu = force_units(length, mass, force_unit)
        assert ident.stiffness_matrix is not None and ident.damping_matrix is not None
        pairs = (
            ("stiffness.csv", fu.factor * ident.stiffness_matrix, fu.stiffness),
            ("damping.csv", fu.factor * ident.damping_matrix, fu.damping),
        )
        for name, mat, u in pairs:
            corner = f"({u['translation']}; {u['coupling']}; {u['rotation']})"
            out[name] = text([corner, *DOF], [[d, *row] for d, row in zip(DOF, mat, strict=True)])
    else:
        for name, mat, t in (
            ("stiffness.csv", ident.stiffness_per_mass, "s^2"),
            ("damping.csv", ident.damping_per_mass, "s"),
        ):
            corner = f"(per {mass}: 1/{t}; {length}/{t}; {length}^2/{t})"
            out[name] = text([corner, *DOF], [[d, *row] for d, row in zip(DOF, mat, strict=True)])
    energy = kinetic_energy_distribution(ident.inertia_per_mass, ident.mode_shapes_cg)
    out["energy_distribution.csv"] = text(
        ["mode (fractions)", *DOF], [[str(label), *row] for label, row in zip(result.modes_used, energy, strict=True)]
    )
    return out


def massline_tables(result: MassLineResult) -> Group:
    """Rich tables of the mass-line result: mass (measured, given, difference), CG, inertia."""
    from rich.console import Group
    from rich.table import Table

    ml = result.massline
    length, mass = result.units["length"], result.units["mass"]
    title = "Mass line" if result.route == "massline" else "Scaled modes"
    table = Table(title=f"{title} (route: {result.route})", title_justify="left", show_header=False, box=None)
    table.add_row("mass measured", f"{_fmt(ml.mass)} {mass}")
    if result.mass_given is not None:
        diff = ml.mass - result.mass_given
        table.add_row("mass given", f"{_fmt(result.mass_given)} {mass}")
        table.add_row("difference", f"{_fmt(diff)} {mass} ({100.0 * diff / result.mass_given:+.2f} %)")
    table.add_row(f"CG ({length})", _vector(ml.center_of_gravity))
    table.add_row("band", f"{ml.band[0]:.4g}-{ml.band[1]:.4g} Hz ({ml.band_source}, {ml.frequencies_used} lines)")
    table.add_row("misfit", f"{100.0 * ml.residual:.2f} % RMS")
    inertia = _matrix_table(f"Inertia tensor about the CG ({mass}·{length}^2)", ml.inertia_tensor, ("x", "y", "z"))
    return Group(table, inertia)
