"""Formatting results: JSON-ready dicts and rich tables. Nothing here prints."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid import __version__
from rigidid.api import IdentifyResult, PlanResult

if TYPE_CHECKING:
    from rich.console import Group
    from rich.table import Table

    from rigidid.core.timedomain import ModalEstimate

__all__ = ["result_tables", "result_to_dict"]

DOF = ("x", "y", "z", "rx", "ry", "rz")


def _rows(a: NDArray[np.float64] | None) -> list[list[float]] | None:
    return None if a is None else [[float(v) for v in row] for row in a]


def _vec(a: NDArray[np.float64] | None) -> list[float] | None:
    return None if a is None else [float(v) for v in a]


def result_to_dict(result: IdentifyResult) -> dict[str, Any]:
    """The result JSON of FORMATS.md (validated by :class:`rigidid.models.ResultFile`).

    Parameters
    ----------
    result : IdentifyResult

    Returns
    -------
    dict
        Plain lists and floats, ready for :func:`json.dumps`.
    """
    ident = result.identification
    diag = ident.diagnostics
    modes = [
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
    candidates = None
    if result.candidate_residuals is not None:
        candidates = [{"mode": label, "rigid_fit_residual": r} for label, r in result.candidate_residuals.items()]
    from rigidid.core.energy import kinetic_energy_distribution, kinetic_energy_distribution_principal

    energy = {
        "dof": ["x", "y", "z", "rx", "ry", "rz"],
        "principal_dof": ["x", "y", "z", "r1", "r2", "r3"],
        "modes": list(result.modes_used),
        "cg_axes": _rows(kinetic_energy_distribution(ident.inertia_per_mass, ident.mode_shapes_cg)),
        "principal_axes": _rows(kinetic_energy_distribution_principal(ident.inertia_per_mass, ident.mode_shapes_cg)),
    }
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
    if result.uncertainty is not None:
        from rigidid.core.uncertainty import uncertainty_to_dict

        out["uncertainty"] = uncertainty_to_dict(result.uncertainty)
    if result.record_spread is not None:
        from rigidid.core.record_spread import record_spread_to_dict

        out["uncertainty_records"] = record_spread_to_dict(result.record_spread)
    if result.record_bound is not None:
        from rigidid.core.timedomain.refine import record_bound_to_dict

        out["uncertainty_records_crb"] = record_bound_to_dict(result.record_bound)
    return out


def _fmt(v: float) -> str:
    return f"{v:.6g}" if abs(v) >= 1e-3 or v == 0.0 else f"{v:.3e}"


def _matrix_table(title: str, a: NDArray[np.float64], labels: Sequence[str], caption: str | None = None) -> Table:
    from rich.table import Table

    table = Table(title=title, caption=caption, title_justify="left", caption_justify="left")
    table.add_column("")
    for name in labels:
        table.add_column(name, justify="right")
    for name, row in zip(labels, a, strict=True):
        table.add_row(name, *(_fmt(float(v)) for v in row))
    return table


def result_tables(result: IdentifyResult) -> Group:
    """Rich tables of CG, inertia, principal axes, stiffness, damping and diagnostics.

    Parameters
    ----------
    result : IdentifyResult

    Returns
    -------
    rich.console.Group
        Render it with a rich console; nothing is printed here.
    """
    from rich.console import Group
    from rich.table import Table

    ident = result.identification
    length, mass = result.units["length"], result.units["mass"]
    absolute = ident.mass is not None
    per = "" if absolute else f" / {mass}"
    m = ident.mass if ident.mass is not None else 1.0
    parts: list[Any] = []

    head = Table(title="Centre of gravity", title_justify="left")
    for axis in ("x", "y", "z"):
        head.add_column(f"{axis} ({length})", justify="right")
    head.add_row(*(_fmt(float(v)) for v in ident.center_of_gravity))
    parts.append(head)

    note = None if absolute else "no mass given: values per unit mass (pass --mass or set mass in the layout)"
    parts.append(
        _matrix_table(
            f"Inertia tensor about the CG ({mass} {length}^2{per})",
            m * ident.inertia_per_mass,
            ("x", "y", "z"),
            "off-diagonal entries are minus the products of inertia" + (f"; {note}" if note else ""),
        )
    )
    principal = Table(title="Principal moments and axes", title_justify="left")
    principal.add_column(f"moment ({mass} {length}^2{per})", justify="right")
    for axis in ("x", "y", "z"):
        principal.add_column(f"axis {axis}", justify="right")
    moments = m * ident.principal_moments_per_mass
    for k in range(3):
        principal.add_row(_fmt(float(moments[k])), *(f"{float(v):+.4f}" for v in ident.principal_axes[:, k]))
    parts.append(principal)

    for name, mat, t in (("Stiffness", ident.stiffness_per_mass, "s^2"), ("Damping", ident.damping_per_mass, "s")):
        caption = (
            f"units{per}: {mass}/{t} (x-z rows and columns), {mass} {length}/{t} (coupling), "
            f"{mass} {length}^2/{t} (rx-rz block); rotations in rad"
        )
        parts.append(_matrix_table(f"{name} of the supports at the CG", m * mat, DOF, caption))

    from rigidid.core.energy import kinetic_energy_distribution

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
    parts.append(energy)

    if result.uncertainty is not None:
        unc = result.uncertainty
        caption = _noise_caption(unc.noise.as_dict(), length)
        caption += f"; {unc.failed} draws failed" if unc.failed else ""
        caption += f"; {unc.implausible} draws physically implausible" if unc.implausible else ""
        title = f"Uncertainty ({unc.draws} Monte Carlo draws, 95 % intervals)"
        parts.append(_interval_table(result, unc, title, caption))
    if result.record_spread is not None:
        spread = result.record_spread
        title = (
            f"Uncertainty from the records ({spread.used} of {spread.segments} interleaved segments, 95 % intervals)"
        )
        caption = "spread of the segment estimates scaled to all the data; noise only, not sensor placement errors"
        parts.append(_interval_table(result, spread, title, caption))
    if result.record_bound is not None:
        bound = result.record_bound
        title = "Uncertainty from the records (Cramér-Rao bound at the output-error fit, 95 % intervals)"
        caption = (
            f"{bound.residuals} residuals, normalised cost {bound.normalised_cost:.3g} (about 1 at a good fit), "
            f"noise levels from the {bound.noise_from}; noise only, not sensor placement errors"
        )
        parts.append(_interval_table(result, bound, title, caption))

    diag = ident.diagnostics
    modes = Table(title="Modes used", title_justify="left")
    for name in ("mode", "f (Hz)", "zeta", "rigid fit", "model f (Hz)", "model zeta", "MAC"):
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
    parts.append(modes)

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
    parts.append(summary)
    return Group(*parts)


def _interval_table(result: IdentifyResult, unc: Any, title: str, caption: str) -> Table:
    """Estimate, standard deviation and 95 % interval of the main results."""
    from rich.table import Table

    length, mass = result.units["length"], result.units["mass"]
    per = f" / {mass}" if unc.per_mass else ""
    table = Table(title=title, caption=caption, title_justify="left", caption_justify="left")
    for name in ("quantity", "estimate", "std", "95 % interval"):
        table.add_column(name, justify="left" if name == "quantity" else "right")

    def rows(name: str, unit: str, interval: Any, labels: Sequence[str], flat: Sequence[int] | None = None) -> None:
        values = [np.ravel(getattr(interval, key)) for key in ("estimate", "std", "low", "high")]
        for label, i in zip(labels, flat if flat is not None else range(len(labels)), strict=True):
            est, std, low, high = (float(v[i]) for v in values)
            table.add_row(f"{name}{label} ({unit})", _fmt(est), _fmt(std), f"{_fmt(low)} .. {_fmt(high)}")

    rows("CG ", length, unc.center_of_gravity, ("x", "y", "z"))
    # upper triangle of the symmetric tensor, flat indices into the 3x3 entries
    rows("J_", f"{mass} {length}^2{per}", unc.inertia, ("xx", "yy", "zz", "xy", "xz", "yz"), (0, 4, 8, 1, 2, 5))
    rows("principal moment ", f"{mass} {length}^2{per}", unc.principal_moments, ("1", "2", "3"))
    rows("stiffness ", f"{mass}/s^2{per}", unc.stiffness_diagonal, DOF[:3])
    rows("stiffness ", f"{mass} {length}^2/s^2{per}", unc.stiffness_diagonal, DOF[3:], (3, 4, 5))
    return table


def _noise_caption(noise: dict[str, float], length: str) -> str:
    parts = [
        f"frequency {100 * noise['frequency']:.3g} %",
        f"damping {100 * noise['damping']:.3g} %",
        f"shape {100 * noise['shape']:.3g} %",
    ]
    if noise.get("position"):
        parts.append(f"position {noise['position']:.3g} {length}")
    if noise.get("angle_deg"):
        parts.append(f"direction {noise['angle_deg']:.3g} deg")
    return "standard deviations assumed: " + ", ".join(parts)


def plan_to_dict(plan: PlanResult) -> dict[str, Any]:
    """JSON form of ``rigidid plan``: units, layout findings, prediction and suggestions (null when absent)."""
    from rigidid.core.plan import layout_report_to_dict, prediction_to_dict, sensor_plan_to_dict

    return {
        "rigidid_version": __version__,
        "units": {**plan.units, "time": "s"},
        "layout": layout_report_to_dict(plan.report),
        "prediction": None if plan.prediction is None else prediction_to_dict(plan.prediction),
        "suggestions": None if plan.suggestions is None else sensor_plan_to_dict(plan.suggestions),
    }


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
            caption=_noise_caption(plan.prediction.uncertainty.noise.as_dict(), length),
            title_justify="left",
            caption_justify="left",
        )
        pred.add_column("quantity")
        pred.add_column("std", justify="right")
        for axis, v in zip("xyz", fig.center_of_gravity_std, strict=True):
            pred.add_row(f"CG {axis} ({length})", _fmt(float(v)))
        for k in range(3):
            pred.add_row(
                f"principal moment {k + 1} ({mass} {length}^2)",
                f"{_fmt(float(fig.principal_moments_std[k]))} ({100 * fig.principal_moments_rel_std[k]:.2g} %)",
            )
        parts.append(pred)
    if plan.suggestions is not None:
        sug = Table(title="Sensors to add (greedy, best first)", title_justify="left")
        for name in ("step", "position", "direction", "CG std", "moments rel. std", "score"):
            sug.add_column(name, justify="right")
        base = plan.suggestions.baseline
        sug.add_row(
            "now",
            "",
            "",
            _vector(base.center_of_gravity_std),
            _vector(base.principal_moments_rel_std),
            _fmt(base.score),
        )
        for step in plan.suggestions.steps:
            f = step.figures
            sug.add_row(
                str(step.step),
                _vector(step.position),
                _vector(step.direction),
                _vector(f.center_of_gravity_std),
                _vector(f.principal_moments_rel_std),
                _fmt(f.score),
            )
        parts.append(sug)
    return Group(*parts)


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
        "stabilisation": [
            {
                "order": entry.order,
                "frequency_hz": _vec(entry.frequency_hz),
                "damping_ratio": _vec(entry.damping_ratio),
                "stable": [bool(v) for v in entry.stable],
            }
            for entry in estimate.diagram
        ],
    }


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
