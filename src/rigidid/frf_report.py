"""The HTML report of the FRF routes (mass line, scaled modes): tables, FRF figures, stabilisation diagram.

:func:`render_frf_report` returns one self-contained HTML document, as
:func:`rigidid.reporting.render_report` does for the modes and records routes:
inline CSS, figures as base64 PNG, no network. The routes computed from the same
FRFs are tabled side by side, each figure with its 95 % interval in the tables'
units.

Figures
-------
``frf``
    One panel per reference: the magnitudes of the measured accelerances summed
    over the responses, and each route's model of them (the mass line
    ``T M^-1 T_f^T``, the free rigid body of eq. (19) of [1] seen through the
    sensor transformation of eq. (3); the rigid body on its supports
    ``-w^2 T (K + i w C - w^2 M)^-1 T_f^T`` for the scaled modes and for the
    mass line's exact support fit), the bands the routes used shaded.
``massline``
    The measured accelerances over the mass line, per reference: 1 where the body
    moves as a free rigid mass, so the plateau shows where the mass line holds;
    with a route's fitted supports (``K``, ``C``), its model over the same line.
``stabilisation``
    Route residues without a modes file: the poles of the pLSCF sweep per order
    over the summed FRF power.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid import __version__
from rigidid.core.energy import DOF_LABELS
from rigidid.core.geometry import sensor_matrix
from rigidid.errors import InputError
from rigidid.progress import ProgressCallback, no_progress
from rigidid.reporting import (
    CSS,
    check_stabilisation,
    esc,
    figure_html,
    fmt_num,
    matrix_html,
    new_figure,
    png_bytes,
    stabilisation_figure,
    table_html,
    test_html,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from rigidid.results import MassLineResult, TestInfo

__all__ = ["FRF_FIGURE_NAMES", "MeasuredFrfs", "mass_line_model", "render_frf_report", "rigid_model"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

FRF_FIGURE_NAMES: tuple[str, ...] = ("frf", "massline", "stabilisation")
"""Names of the FRF report's figures, in report order."""

_ROUTE_NAMES = {"massline": "mass line", "residues": "scaled modes (residues)"}
_ROUTE_COLOURS = {"massline": "#c0392b", "residues": "#1f5fa8"}


@dataclass(frozen=True, init=False)
class MeasuredFrfs:
    """Measured FRFs with the geometry of their responses and references (what the figures need).

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz, ascending.
    frf : array_like of complex, shape (p, q, f)
        Accelerance (layout length / s^2 per force unit, i.e. 1 / mass unit).
    positions, directions : array_like, shape (p, 3)
        Sensors (layout length; unit axes).
    reference_positions, reference_directions : array_like, shape (q, 3)
        Force points and directions.
    sensor_ids, reference_ids : sequence of str
    """

    frequencies: Array
    frf: CArray
    positions: Array
    directions: Array
    reference_positions: Array
    reference_directions: Array
    sensor_ids: tuple[str, ...]
    reference_ids: tuple[str, ...]

    def __init__(
        self,
        frequencies: ArrayLike,
        frf: ArrayLike,
        positions: ArrayLike,
        directions: ArrayLike,
        reference_positions: ArrayLike,
        reference_directions: ArrayLike,
        sensor_ids: Sequence[str],
        reference_ids: Sequence[str],
    ) -> None:
        fields = {
            "frequencies": np.asarray(frequencies, dtype=float).reshape(-1),
            "frf": np.asarray(frf, dtype=complex),
            "positions": np.asarray(positions, dtype=float).reshape(-1, 3),
            "directions": np.asarray(directions, dtype=float).reshape(-1, 3),
            "reference_positions": np.asarray(reference_positions, dtype=float).reshape(-1, 3),
            "reference_directions": np.asarray(reference_directions, dtype=float).reshape(-1, 3),
            "sensor_ids": tuple(str(s) for s in sensor_ids),
            "reference_ids": tuple(str(s) for s in reference_ids),
        }
        for name, value in fields.items():
            object.__setattr__(self, name, value)
        p, q = self.positions.shape[0], self.reference_positions.shape[0]
        if self.frf.shape != (p, q, self.frequencies.size) or len(self.sensor_ids) != p or len(self.reference_ids) != q:
            raise InputError(
                f"FRFs of shape {self.frf.shape} for {p} sensors, {q} references and {self.frequencies.size} lines",
                source="frf",
            )


def _unit_rows(directions: Array) -> Array:
    out: Array = directions / np.linalg.norm(directions, axis=1)[:, None]
    return out


def mass_line_model(data: MeasuredFrfs, mass: float, cg: Array, inertia: Array) -> Array:
    """The mass line ``T M^-1 T_f^T`` (p, q): the accelerance of the free rigid body (eqs. (3), (19) of [1]).

    Parameters
    ----------
    data : MeasuredFrfs
    mass : float
    cg : ndarray, shape (3,)
        Centre of gravity (length).
    inertia : ndarray, shape (3, 3)
        Inertia tensor about the CG (mass length^2).

    Returns
    -------
    ndarray, shape (p, q)
    """
    m = np.zeros((6, 6))
    m[:3, :3] = mass * np.eye(3)
    m[3:, 3:] = np.asarray(inertia, dtype=float)
    t = sensor_matrix(data.positions, _unit_rows(data.directions), cg)
    tf = sensor_matrix(data.reference_positions, _unit_rows(data.reference_directions), cg)
    out = np.asarray(t @ np.linalg.solve(m, tf.T), dtype=float)
    return out


def rigid_model(data: MeasuredFrfs, mass_matrix: Array, stiffness: Array, damping: Array, cg: Array) -> CArray:
    """Accelerance of the rigid body on its supports, ``-w^2 T (K + i w C - w^2 M)^-1 T_f^T`` (p, q, f).

    Parameters
    ----------
    data : MeasuredFrfs
    mass_matrix, stiffness, damping : ndarray, shape (6, 6)
        At the CG (mass, mass / s^2, mass / s; rotations in rad), DOF x, y, z, rx, ry, rz.
    cg : ndarray, shape (3,)

    Returns
    -------
    ndarray of complex, shape (p, q, f)
    """
    t = sensor_matrix(data.positions, _unit_rows(data.directions), cg)
    tf = sensor_matrix(data.reference_positions, _unit_rows(data.reference_directions), cg)
    w = 2.0 * math.pi * data.frequencies
    out = np.empty(data.frf.shape, dtype=complex)
    for k, wk in enumerate(w):
        dynamic = stiffness + 1j * wk * damping - wk**2 * mass_matrix
        out[:, :, k] = -(wk**2) * (t @ np.linalg.solve(dynamic, tf.T))
    return out


def _route_model(route: MassLineResult, data: MeasuredFrfs) -> CArray:
    """The model a route fitted, on every line: the rigid body on supports (scaled modes, or the mass line's exact
    support fit) or the mass line."""
    ml = route.massline
    if route.scaled is not None:
        s = route.scaled
        return rigid_model(data, s.mass_matrix, s.stiffness_matrix, s.damping_matrix, s.center_of_gravity)
    if ml.support_matrices is not None:
        mass_matrix = np.zeros((6, 6))
        mass_matrix[:3, :3] = ml.mass * np.eye(3)
        mass_matrix[3:, 3:] = ml.inertia_tensor
        return rigid_model(data, mass_matrix, *ml.support_matrices, ml.center_of_gravity)
    level = mass_line_model(data, ml.mass, ml.center_of_gravity, ml.inertia_tensor)
    return np.repeat(level[:, :, None].astype(complex), data.frequencies.size, axis=2)


def _on_supports(route: MassLineResult) -> bool:
    """Whether the route fitted the supports' stiffness and damping (scaled modes, or the exact support fit)."""
    return route.scaled is not None or route.massline.support_matrices is not None


def _frf_figure(
    data: MeasuredFrfs, routes: Sequence[MassLineResult], models: Sequence[CArray], mass_unit: str
) -> Figure:
    """Summed FRF magnitudes per reference: measured, each route's model, each route's band."""
    q = len(data.reference_ids)
    height = 3.0 + 2.2 * q  # fixed margins (inches over the height): the legend below, the titles above
    fig = new_figure(11.0, height, {"left": 0.08, "right": 0.98, "bottom": 1.0 / height, "top": 1 - 0.3 / height})
    axes = fig.subplots(q, 1, sharex=True, squeeze=False)[:, 0]
    f = data.frequencies
    for j, ax in enumerate(axes):
        ax.semilogy(f, np.abs(data.frf[:, j, :]).sum(axis=0), color="#9aa7b5", lw=3.0, label="measured")
        for route, model in zip(routes, models, strict=True):
            colour = _ROUTE_COLOURS.get(route.route, "#7d3c98")
            name = _ROUTE_NAMES.get(route.route, route.route)
            kind = "rigid body on supports" if _on_supports(route) else "mass line"
            ax.semilogy(f, np.abs(model[:, j, :]).sum(axis=0), "--", color=colour, lw=1.2, label=f"{name}: {kind}")
            lo, hi = route.massline.band
            ax.axvspan(lo, hi, color=colour, alpha=0.08, lw=0, label=f"{name}: band")
        ax.set_ylabel(f"Σ|H| [1/{mass_unit}]", fontsize=9)
        ax.set_title(f"force at reference {data.reference_ids[j]}", fontsize=10, loc="left")
        ax.grid(True, which="both", color="#e3e7ec", lw=0.6)
    axes[-1].set_xlabel("frequency [Hz]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 3), fontsize=9, frameon=False)
    return fig


def _massline_figure(data: MeasuredFrfs, routes: Sequence[MassLineResult], models: Sequence[CArray]) -> Figure:
    """Measured accelerance over each route's mass line (summed over responses), per reference: 1 on the plateau;
    with a route's fitted supports, its model over the same mass line (broad grey, under the measured lines): where
    the supports lift it."""
    fig = new_figure(11.0, 4.2, {"left": 0.08, "right": 0.98, "bottom": 0.23, "top": 0.97})
    ax = fig.add_subplot(1, 1, 1)
    f = data.frequencies
    styles = ("-", "--", ":", "-.")
    for route, model in zip(routes, models, strict=True):
        ml = route.massline
        level = np.abs(mass_line_model(data, ml.mass, ml.center_of_gravity, ml.inertia_tensor)).sum(axis=0)
        colour = _ROUTE_COLOURS.get(route.route, "#7d3c98")
        name = _ROUTE_NAMES.get(route.route, route.route)
        for j, ref in enumerate(data.reference_ids):
            ratio = np.abs(data.frf[:, j, :]).sum(axis=0) / level[j]
            ax.plot(f, ratio, styles[j % len(styles)], color=colour, lw=1.0, label=f"{name}, reference {ref}")
        if _on_supports(route):
            fitted = np.abs(model).sum(axis=0) / level[:, None]
            for j in range(len(data.reference_ids)):
                label = f"{name}: fitted on its supports (K, C)" if j == 0 else None
                ax.plot(f, fitted[j], styles[j % len(styles)], color="#222222", lw=2.4, alpha=0.25, zorder=1,
                        label=label)  # fmt: skip
        ax.axvspan(*ml.band, color=colour, alpha=0.08, lw=0)
    ax.axhline(1.0, color="#555555", lw=0.8)
    ax.set_yscale("log")
    ax.set_ylim(0.1, 10.0)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("Σ|H| / Σ|mass line|", fontsize=9)
    ax.grid(True, which="both", color="#e3e7ec", lw=0.6)
    rows = -(-len(ax.get_legend_handles_labels()[1]) // 3)
    fig.subplots_adjust(bottom=(0.55 + 0.17 * rows) / 4.2)  # the axis label clear of the legend's rows
    fig.legend(loc="outside lower center", ncols=3, fontsize=8, frameon=False)
    return fig


def frf_figures(
    data: MeasuredFrfs, routes: Sequence[MassLineResult], mass_unit: str, progress: ProgressCallback | None = None
) -> dict[str, Figure]:
    """The FRF report's figures by name (:data:`FRF_FIGURE_NAMES`; ``stabilisation`` only with a fitted route)."""
    step = progress or no_progress
    models = [_route_model(route, data) for route in routes]
    fitted = next((route.fitted for route in routes if route.fitted is not None), None)
    figures = {}
    step("drawing the report's figures", 0, 3)
    figures["frf"] = _frf_figure(data, routes, models, mass_unit)
    step("drawing the report's figures", 1, 3)
    figures["massline"] = _massline_figure(data, routes, models)
    if fitted is not None:
        entries = check_stabilisation(fitted.diagram)
        power = (np.abs(data.frf) ** 2).sum(axis=(0, 1))
        figures["stabilisation"] = stabilisation_figure(
            np.abs(fitted.poles) / (2.0 * math.pi), entries, (data.frequencies, power),
            ("sum of the FRFs' squared magnitudes", "Σ|H|² (over responses and references)"),
        )  # fmt: skip
    step("drawing the report's figures", 3, 3)
    return figures


def _interval_text(interval: Any, index: tuple[int, ...]) -> str:
    """``± half-width`` of the 95 % interval (estimate ± 1.96 std), or a dash without one."""
    if interval is None:
        return "\u2013"
    half = 0.5 * (float(np.asarray(interval.high)[index]) - float(np.asarray(interval.low)[index]))
    return f"± {fmt_num(half, 3)}"


def _routes_rows(routes: Sequence[MassLineResult], length: str, mass_unit: str) -> tuple[list[list[str]], list[str]]:
    """Rows of the side-by-side table (quantity, component, unit, per route: estimate and 95 % interval, and with
    two routes their difference over the combined standard error), and the entries where that exceeds
    :data:`SEPARATION`."""
    quantities: list[tuple[str, str, str, Any, tuple[int, ...]]] = [("mass", "", mass_unit, "mass", ())]
    quantities += [
        ("centre of gravity" if k == 0 else "", "xyz"[k], length, "center_of_gravity", (k,)) for k in range(3)
    ]
    pairs = [(i, j) for i in range(3) for j in range(i, 3)]
    quantities += [
        ("inertia tensor about the CG" if n == 0 else "", "xyz"[i] + "xyz"[j], f"{mass_unit}·{length}²",
         "inertia_tensor", (i, j))
        for n, (i, j) in enumerate(pairs)
    ]  # fmt: skip
    rows, apart, group = [], [], ""
    for name, component, unit, attr, index in quantities:
        group = name or group
        row = [esc(name), esc(component), esc(unit)]
        stds = []
        for route in routes:
            ml = route.massline
            value = float(np.asarray(getattr(ml, attr))[index])
            intervals = None if ml.intervals is None else getattr(ml.intervals, attr)
            row += [fmt_num(value), _interval_text(intervals, index)]
            stds.append(None if intervals is None else float(np.asarray(intervals.std)[index]))
        if len(routes) == 2:
            values = [float(np.asarray(getattr(r.massline, attr))[index]) for r in routes]
            known = [v for v in stds if v is not None]
            scale = math.hypot(*known) if len(known) == 2 else 0.0
            separation = abs(values[0] - values[1]) / scale if scale > 0.0 else None
            row.append("\u2013" if separation is None else fmt_num(separation, 2))
            if separation is not None and separation > SEPARATION:
                apart.append(f"{group} {component}".strip())
        rows.append(row)
    return rows, apart


SEPARATION = 3.0
"""Two routes whose estimates differ by more than this many combined standard errors are flagged."""


def _routes_html(routes: Sequence[MassLineResult], length: str, mass_unit: str) -> str:
    """The routes side by side, with their intervals in the same units, and what each route did."""
    header = ["quantity", "component", "unit"]
    for route in routes:
        name = _ROUTE_NAMES.get(route.route, route.route)
        header += [f"{name}: estimate", "95 % interval"]
    methods = "; ".join(
        f"{_ROUTE_NAMES.get(r.route, r.route)}: "
        + (r.massline.intervals.method if r.massline.intervals is not None else "no interval (the fit has no noise)")
        for r in routes
    )
    caption = f"Every figure in the units of its row. 95 % interval: estimate ± 1.96 standard errors; {methods}."
    if len(routes) == 2:
        header.append("routes differ by (combined SE)")
        caption += " Last column: the two routes' difference over the root sum of squares of their standard errors."
    rows, apart = _routes_rows(routes, length, mass_unit)
    parts = ["<h2>Mass, centre of gravity and inertia</h2>", table_html(header, rows, caption=caption, label_cols=3)]
    if apart:
        parts.append(
            f'<div class="warn">⚠ The routes differ by more than {fmt_num(SEPARATION)} combined standard errors in: '
            f"{esc(', '.join(apart))}. One route's model does not hold on these FRFs or its intervals are too "
            "narrow; see how each route fitted below before signing either.</div>"
        )
    given = routes[0].mass_given
    if given is not None:
        diffs = ", ".join(
            f"{esc(_ROUTE_NAMES.get(r.route, r.route))} {fmt_num(r.massline.mass - given)} {esc(mass_unit)} "
            f"({fmt_num(100.0 * (r.massline.mass - given) / given, 3)} %)"
            for r in routes
        )
        parts.append(f"<p>Mass given {fmt_num(given)} {esc(mass_unit)}; measured minus given: {diffs}.</p>")
    rows = []
    for r in routes:
        ml = r.massline
        noise = "\u2013" if ml.misfit_noise_units is None else fmt_num(ml.misfit_noise_units, 3)
        rows.append([
            esc(_ROUTE_NAMES.get(r.route, r.route)), f"{fmt_num(ml.band[0], 4)} \u2013 {fmt_num(ml.band[1], 4)} Hz",
            esc(ml.band_source), str(ml.frequencies_used), f"{fmt_num(100.0 * ml.residual, 3)} %", noise,
            esc(ml.supports),
        ])  # fmt: skip
    why = "".join(f"<li><b>{esc(_ROUTE_NAMES.get(r.route, r.route))}</b>: {esc(r.reason)}</li>" for r in routes)
    parts += [
        "<h3>How each route fitted</h3>",
        table_html(
            ["route", "band", "band from", "lines", "misfit (RMS)", "misfit / noise", "supports"], rows,
            caption="misfit / noise: the fit's RMS misfit over the noise seen along frequency, about 1 when the "
            "model explains the FRFs.",
        ),
        f"<ul>{why}</ul>",
    ]  # fmt: skip
    return "\n".join(parts)


def _supports_html(route: MassLineResult, length: str, mass_unit: str, force_unit: str | None) -> str:
    """Stiffness and damping at the CG from the scaled modes, in force units."""
    from rigidid.units import force_units

    if route.scaled is None:
        return ""
    fu = force_units(length, mass_unit, force_unit)
    parts = []
    for name, matrix, spelt in (
        ("Stiffness", route.scaled.stiffness_matrix, fu.stiffness),
        ("Damping", route.scaled.damping_matrix, fu.damping),
    ):
        caption = (
            f"From the scaled rigid-body modes. Units: x-z block [{spelt['translation']}], coupling blocks "
            f"[{spelt['coupling']}], rx-rz block [{spelt['rotation']}]; rotations in rad."
        )
        heading = f"<h2>{name} matrix at the CG (scaled modes)</h2>"
        parts += [heading, matrix_html(fu.factor * matrix, DOF_LABELS, caption)]
    return "\n".join(parts)


def _tried_html(chosen: MassLineResult, mass_unit: str) -> str:
    """Every route tried (``--method auto``, or compared): applies or not, its mass, the one chosen and why."""
    if not chosen.routes:
        return ""
    rows = []
    for answer in chosen.routes:
        ml = answer.massline
        interval = None if ml is None or ml.intervals is None else ml.intervals.mass
        mass = "\u2013" if ml is None else f"{fmt_num(ml.mass)} {_interval_text(interval, ())}"
        verdict = "chosen" if answer.route == chosen.route else ("applies" if answer.applies else "does not apply")
        rows.append([esc(_ROUTE_NAMES.get(answer.route, answer.route)), verdict, mass, esc(answer.reason)])
    return "\n".join([
        "<h2>Routes tried</h2>",
        table_html(
            ["route", "verdict", f"mass [{mass_unit}]", "why"], rows,
            caption="Every FRF route the data were tried with; the one chosen is tabled first below. "
            + chosen.reason.split("; ")[0] + ".",
        ),
    ])  # fmt: skip


def _head(
    title: str, data: MeasuredFrfs, routes: Sequence[MassLineResult], inputs: Sequence[str], created: str | None
) -> str:
    import datetime

    when = created or datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    length, mass_unit = routes[0].units["length"], routes[0].units["mass"]
    names = ", ".join(_ROUTE_NAMES.get(r.route, r.route) for r in routes)
    files = f'<p class="meta">input: {esc(", ".join(inputs))}</p>' if inputs else ""
    f = data.frequencies
    return "\n".join([
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{esc(title)}</title><style>{CSS}</style></head><body>",
        f"<h1>{esc(title)}</h1>",
        f'<p class="meta">rigidid {esc(__version__)} · {esc(when)} · FRF routes: {esc(names)} · units: length '
        f"{esc(length)}, mass {esc(mass_unit)}, time s · {len(data.sensor_ids)} responses \u00d7 "
        f"{len(data.reference_ids)} references, {f.size} lines {fmt_num(float(f[0]), 4)}\u2013"
        f"{fmt_num(float(f[-1]), 4)} Hz</p>",
        files,
    ])  # fmt: skip


def render_frf_report(
    data: MeasuredFrfs,
    routes: Sequence[MassLineResult],
    *,
    title: str = "rigidid report",
    inputs: Sequence[str] = (),
    force_unit: str | None = None,
    test: TestInfo | None = None,
    created: str | None = None,
    progress: ProgressCallback | None = None,
    figures: Mapping[str, bytes] | None = None,
) -> str:
    """One self-contained HTML document reporting the FRF routes side by side.

    Parameters
    ----------
    data : MeasuredFrfs
        The measured FRFs and their geometry.
    routes : sequence of MassLineResult
        The routes computed from these FRFs (:func:`rigidid.api.frf.identify_massline`), the chosen one first.
    title : str
        Heading and ``<title>``.
    inputs : sequence of str
        Input file names, listed under the title.
    force_unit : {"N", "kN", "lbf"}, optional
        Force unit of the scaled modes' stiffness and damping.
    test : TestInfo, optional
        The layout's ``test`` block, shown under the title.
    created : str, optional
        Date shown under the title (default: now, UTC).
    progress : callable, optional
        ``progress(task, done, total)`` while the figures are drawn.
    figures : mapping of str to bytes, optional
        The figures drawn already as PNG (:func:`frf_figures` through
        :func:`rigidid.reporting.png_bytes`), e.g. to write them as files too.

    Returns
    -------
    str
        The HTML text: every route tried (whether it applies, the chosen one and why), the routes' mass,
        CG and inertia with their 95 % intervals side by side, how each
        fitted, the scaled modes' stiffness and damping, and the figures (module documentation).
    """
    if not routes:
        raise InputError("an FRF report needs at least one route", source="routes")
    length, mass_unit = routes[0].units["length"], routes[0].units["mass"]
    if figures is None:
        figures = {name: png_bytes(fig) for name, fig in frf_figures(data, routes, mass_unit, progress).items()}
    pngs = dict(figures)
    parts = [
        _head(title, data, routes, inputs, created),
        test_html(test),
        _tried_html(routes[0], mass_unit),
        _routes_html(routes, length, mass_unit),
        *(_supports_html(r, length, mass_unit, force_unit) for r in routes[:1]),
        "<h2>FRFs and the fits</h2>",
        figure_html(
            pngs["frf"], "FRF magnitudes with the fits",
            "Per reference, the magnitudes of the measured accelerances summed over the responses (thick grey) and "
            "each route's model of them (dashed): the mass line T M⁻¹ T_fᵀ, or the rigid body on its supports from the "
            "scaled modes; shaded: the band each route fitted.",
        ),
        "<h2>Mass line</h2>",
        figure_html(
            pngs["massline"], "the measured FRFs over the mass line",
            "The measured accelerances over each route's mass line, summed over the responses, per reference: 1 where "
            "the body moves as a free rigid mass (above the rigid-body modes, below the first elastic mode).",
        ),
    ]  # fmt: skip
    if "stabilisation" in pngs:
        parts += [
            "<h2>Stabilisation diagram</h2>",
            figure_html(
                pngs["stabilisation"], "stabilisation diagram",
                "Poles of the pLSCF sweep per order; vertical lines: the six rigid-body modes the residues were "
                "fitted with; grey: the FRFs' summed power (right axis).",
            ),
        ]  # fmt: skip
    parts.append("</body></html>")
    return "\n".join(p for p in parts if p)
