"""Formatting results: JSON-ready dicts and rich tables. Nothing here prints."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid import __version__
from rigidid.api import IdentifyResult

if TYPE_CHECKING:
    from rich.console import Group
    from rich.table import Table

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
    return {
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
        "diagnostics": {
            "layout_condition": diag.layout_condition,
            "layout_rank": diag.layout_rank,
            "structure_residual": diag.structure_residual,
            "modes": modes,
            "candidate_modes": candidates,
            "warnings": list(diag.warnings),
        },
    }


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
    if result.candidate_residuals is not None:
        text = ", ".join(f"{label}: {r:.2e}" for label, r in result.candidate_residuals.items())
        summary.add_row("rigid fit of every mode", text)
    for message in diag.warnings:
        summary.add_row("[yellow]warning[/yellow]", message)
    parts.append(summary)
    return Group(*parts)
