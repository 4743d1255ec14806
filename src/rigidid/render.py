"""Rich tables of results. Nothing here prints; the JSON forms are in :mod:`rigidid.jsonout`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid.api import IdentifyResult, PlanResult
from rigidid.jsonout import noise_to_dict

if TYPE_CHECKING:
    from rich.console import Group
    from rich.table import Table

    from rigidid.core.timedomain import ModalEstimate

__all__ = ["estimate_tables", "plan_tables", "result_tables"]

DOF = ("x", "y", "z", "rx", "ry", "rz")


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
        caption = _noise_caption(noise_to_dict(unc.noise), length)
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
            caption=_noise_caption(noise_to_dict(plan.prediction.uncertainty.noise), length),
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
