"""A self-contained HTML report of an identification, with matplotlib figures.

:func:`render_report` returns one HTML document: inline CSS, figures embedded
as base64 PNG, one inline script of rigidid's own (the interactive mode shapes,
:mod:`rigidid.modeviewer`), no fonts, libraries or any other external
resource, so it opens anywhere without a network. :func:`save_pngs` writes the same figures as PNG
files; ``render_report(..., png=folder)`` writes the page's own images (drawn once, :func:`write_pngs`).
matplotlib is imported inside the functions that draw (an optional
dependency), and figures are drawn on the Agg canvas without touching
pyplot's global state, each at fixed margins (:func:`new_figure`): matplotlib's constrained
layout measures every artist before drawing, a third of the time of a figure of 3-D views.

Figures
-------
``layout``
    The sensors (arrows along their measuring directions), the CG, the
    principal axes of inertia (arrows from the CG, half the largest
    sensor-to-CG distance long) and the mounts when given: a 3D view and the
    top (x-y), front (x-z) and side (y-z) projections, equal scales.
``modes``
    The six measured modes used, each as the rigid-body motion of the CG that
    best fits its readings (``Identification.mode_shapes_cg``), a 2 x 3 grid
    of 3D views: the sensor points and the CG at rest (grey) and displaced by
    the mode (coloured), joined by the sensor outline (:func:`sensor_outline`)
    and spokes to the CG; titled by mode label.
``decoupling``
    Heat maps of the modal kinetic-energy distribution
    (:mod:`rigidid.core.energy`) of the same motions, in the test axes and in
    the principal axes, in %: one definition with the terminal table and the
    result JSON's ``energy_distribution``.
``stabilisation``
    Only when a stabilisation diagram is given; over the summed spectrum of
    the records when given.
"""

from __future__ import annotations

import base64
import html
import io
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid import __version__
from rigidid.core.energy import (
    DOF_LABELS,
    PRINCIPAL_DOF_LABELS,
    kinetic_energy_distribution,
    kinetic_energy_distribution_principal,
)
from rigidid.core.geometry import sensor_outline
from rigidid.errors import InputError, RigididError
from rigidid.io.atomic import write_bytes_atomic
from rigidid.modeviewer import VIEWER_CSS, mode_viewer_html
from rigidid.progress import ProgressCallback, no_progress

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from rigidid.core.identify import Identification
    from rigidid.core.mounts import TorqueRollAxis
    from rigidid.core.record_spread import RecordSpread
    from rigidid.core.timedomain.refine import RecordBound
    from rigidid.core.timedomain.stabilisation import OrderPoles
    from rigidid.core.uncertainty import Uncertainty
    from rigidid.results import Mounts, TestInfo

__all__ = ["FIGURE_NAMES", "identified_mount_labels", "render_report", "save_pngs", "stiffness_labels"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

FIGURE_NAMES: tuple[str, ...] = ("layout", "modes", "decoupling", "stabilisation")
"""Names (and PNG file stems) of the figures, in report order."""

_DPI = 110
_SENSOR_COLOUR = "#1f5fa8"
_CG_COLOUR = "#c0392b"
_AXIS_COLOURS = ("#2e8b57", "#d68910", "#7d3c98")
_MOUNT_COLOUR = "#333333"
_ROLL_COLOUR = "#e67e22"
_MODE_COLOUR = "#c0392b"

Intervals: TypeAlias = "Uncertainty | RecordSpread | RecordBound"
"""The typed intervals a report shows: Monte Carlo, record segments, the refit's Cramér-Rao bound."""

Stabilisation = Sequence["tuple[int, ArrayLike, ArrayLike] | OrderPoles"]
"""``[(order, frequency_hz (n,), stable (n,) bool), ...]`` or ``OrderPoles``: one entry per model order."""


def _point_motion(phi: CArray, points: Array, cg: Array) -> CArray:
    """Translations (k, 3) of `points` for CG motion ``phi`` (6,): ``x + theta x (r - g)``."""
    result: CArray = phi[:3][None, :] + np.cross(phi[3:][None, :], points - cg[None, :])
    return result


def _scene_size(*point_sets: Array) -> float:
    pts = np.vstack([p.reshape(-1, 3) for p in point_sets if p.size])
    size = float(np.max(np.ptp(pts, axis=0)))
    return size if size > 0.0 else 1.0


# --------------------------------------------------------------------------- units and numbers


def _units(units: Mapping[str, str]) -> tuple[str, str]:
    try:
        return str(units["length"]), str(units["mass"])
    except KeyError as exc:
        raise InputError(f"units need 'length' and 'mass', missing {exc.args[0]!r}", source="units") from None


def _block_units(length: str, mass: str | None, time_power: int) -> tuple[str, str, str]:
    """Units of the translation, coupling and rotation blocks of a 6x6 K (power 2) or C (power 1)."""
    s = "s²" if time_power == 2 else "s"
    if mass is None:
        return f"1/{s}", f"{length}/{s}", f"{length}²/{s}"
    return f"{mass}/{s}", f"{mass}·{length}/{s}", f"{mass}·{length}²/{s}"


def fmt_num(v: float | None, digits: int = 5) -> str:
    """`digits` significant digits; plain notation (thin-space thousands) from 1e-3 to 1e9."""
    if v is None or not math.isfinite(v):
        return "\u2013"  # en dash
    if v == 0.0:
        return "0"
    magnitude = math.floor(math.log10(abs(v)))
    if not -3 <= magnitude < 9:
        return f"{v:.{digits - 1}e}"
    decimals = max(0, digits - 1 - magnitude)
    rounded = round(v, digits - 1 - magnitude)
    text = f"{rounded:,.{decimals}f}".replace(",", "\u2009")
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _residual(v: float) -> str:
    """A relative residual: below 1e-12 it is round-off, shown as 0."""
    return "0" if abs(v) < 1e-12 else fmt_num(v, 3)


def esc(text: object) -> str:
    return html.escape(str(text), quote=True)


# --------------------------------------------------------------------------- figures


def new_figure(width: float, height: float, margins: Mapping[str, float] | None = None) -> Figure:
    """An Agg figure `width` x `height` inches: laid out by matplotlib's constrained layout, or at fixed `margins`.

    `margins` are the arguments of ``Figure.subplots_adjust`` (fractions of the figure): the report's own
    figures are laid out so, which spares the constrained layout's measuring of every artist (a third of
    the drawing time of a figure of 3-D views).
    """
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:  # pragma: no cover - depends on the environment
        raise RigididError("the report needs the optional package matplotlib (pip install matplotlib)") from None
    fig = Figure(figsize=(width, height), dpi=_DPI, layout="constrained" if margins is None else None)
    if margins is not None:
        fig.subplots_adjust(**margins)
    FigureCanvasAgg(fig)
    return fig


def _equal_3d(ax: Any, points: Array, zoom: float = 1.0) -> None:
    """Limits around `points` with one scale on all three axes (thin extents padded to 30 %)."""
    from matplotlib.ticker import MaxNLocator

    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (lo + hi)
    largest = float(np.max(hi - lo)) or 1.0
    half = 0.55 * np.maximum(hi - lo, 0.3 * largest)
    ax.set_xlim(centre[0] - half[0], centre[0] + half[0])
    ax.set_ylim(centre[1] - half[1], centre[1] + half[1])
    ax.set_zlim(centre[2] - half[2], centre[2] + half[2])
    ax.set_box_aspect(tuple(half), zoom=zoom)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(nbins=5, steps=[1, 2, 2.5, 5, 10]))


@dataclass(frozen=True)
class _Scene:
    """What the layout figure draws, in the layout's axes (length unit)."""

    positions: Array
    directions: Array
    labels: list[tuple[Array, str]]  # one label per distinct position: triaxial sets share one
    g: Array
    axes: Array
    tips: Array
    mounts: Array
    mount_labels: list[str]
    outline: list[int]
    arrow: float
    size: float
    roll_axis: Array | None = None  # unit direction of the torque roll axis, through the CG


def _sensor_labels(positions: Array, sensor_ids: Sequence[str], size: float) -> list[tuple[Array, str]]:
    """One label per distinct sensor position: ``A+x/A+y/A+z`` for a triaxial set, not three on top of each other."""
    groups: list[tuple[Array, list[str]]] = []
    for sid, p in zip(sensor_ids, positions, strict=True):
        for q, names in groups:
            if float(np.linalg.norm(p - q)) <= 1e-6 * size:
                names.append(sid)
                break
        else:
            groups.append((p, [sid]))
    return [(q, "/".join(names)) for q, names in groups]


def _layout_3d(ax3: Any, scene: _Scene, everything: Array, length: str) -> None:
    pos, g = scene.positions, scene.g
    ring = pos[scene.outline]
    ax3.plot(ring[:, 0], ring[:, 1], ring[:, 2], color="#9aa7b5", lw=1.0)
    ax3.scatter(*pos.T, color=_SENSOR_COLOUR, s=28, depthshade=False)
    ax3.quiver(*pos.T, *(scene.arrow * scene.directions).T, color=_SENSOR_COLOUR, lw=1.6, arrow_length_ratio=0.3)
    for p, text in scene.labels:
        ax3.text(*(p + 0.025 * scene.size), text, fontsize=10, color=_SENSOR_COLOUR)
    ax3.scatter(*g, color=_CG_COLOUR, s=120, marker="*", depthshade=False, zorder=5)
    ax3.text(*(g - np.array([0.0, 0.0, 0.06 * scene.size])), "CG", fontsize=12, color=_CG_COLOUR, fontweight="bold")
    for k in range(3):
        ax3.quiver(*g, *(scene.tips[k] - g), color=_AXIS_COLOURS[k], lw=2.2, arrow_length_ratio=0.15)
        ax3.text(*scene.tips[k], f" {k + 1}", fontsize=11, color=_AXIS_COLOURS[k], fontweight="bold")
    if scene.mounts.size:
        ax3.scatter(*scene.mounts.T, color=_MOUNT_COLOUR, marker="^", s=60, depthshade=False)
        for k, m in enumerate(scene.mounts):
            ax3.text(*(m - np.array([0.0, 0.0, 0.05 * scene.size])), _mount_tag(k), fontsize=11,
                     color=_MOUNT_COLOUR, fontweight="bold")  # fmt: skip
    if scene.roll_axis is not None:
        ends = g[None, :] + 0.45 * scene.size * np.outer([-1.0, 1.0], scene.roll_axis)
        ax3.plot(*ends.T, color=_ROLL_COLOUR, lw=2.0, ls="--")
        ax3.text(*ends[1], " torque roll axis", fontsize=10, color=_ROLL_COLOUR)
    _equal_3d(ax3, everything, zoom=1.2)
    ax3.set_xlabel(f"x [{length}]")
    ax3.set_ylabel(f"y [{length}]")
    ax3.set_zlabel(f"z [{length}]")
    ax3.view_init(elev=18, azim=-60)


def _projection(
    ax: Any, scene: _Scene, a: int, b: int, title: str, limits: tuple[Array, Array], length: str
) -> tuple[list[Any], Array]:
    """One orthographic view onto the plane of axes `a` and `b`, at the shared scale `limits` (centre, half)."""
    pos, dirs, g, arrow = scene.positions, scene.directions, scene.g, scene.arrow
    ring = pos[scene.outline]
    ax.plot(ring[:, a], ring[:, b], color="#9aa7b5", lw=1.0, zorder=1)
    ax.scatter(pos[:, a], pos[:, b], color=_SENSOR_COLOUR, s=24, zorder=3)
    towards = np.cross(np.eye(3)[a], np.eye(3)[b])  # the axis pointing at the viewer
    for p, d in zip(pos, dirs, strict=True):
        if abs(d[a]) + abs(d[b]) > 1e-9:
            ax.annotate(
                "",
                xy=(p[a] + arrow * d[a], p[b] + arrow * d[b]),
                xytext=(p[a], p[b]),
                arrowprops={"arrowstyle": "-|>", "color": _SENSOR_COLOUR, "lw": 1.4},
                zorder=3,
            )
        else:  # along the line of sight: a dot (towards the viewer) or a cross (away) in a circle
            ax.scatter([p[a]], [p[b]], s=130, facecolors="none", edgecolors=_SENSOR_COLOUR, zorder=2)
            if float(towards @ d) < 0.0:
                ax.scatter([p[a]], [p[b]], s=60, marker="x", color=_SENSOR_COLOUR, zorder=4)
    labels: list[Any] = []  # placed afterwards, in this order of priority (_place_labels)
    for k in range(3):
        tip = scene.tips[k]
        if np.hypot(tip[a] - g[a], tip[b] - g[b]) > 0.05 * float(np.linalg.norm(tip - g)):
            ax.annotate(
                "",
                xy=(tip[a], tip[b]),
                xytext=(g[a], g[b]),
                arrowprops={"arrowstyle": "-|>", "color": _AXIS_COLOURS[k], "lw": 2.0},
                zorder=4,
            )
            labels.append(ax.annotate(
                str(k + 1), (tip[a], tip[b]), xytext=(3, 3), textcoords="offset points", fontsize=12,
                color=_AXIS_COLOURS[k], fontweight="bold",
            ))  # fmt: skip
    ax.scatter([g[a]], [g[b]], color=_CG_COLOUR, marker="*", s=180, zorder=5)
    labels.insert(0, ax.annotate(
        "CG", (g[a], g[b]), xytext=(7, -14), textcoords="offset points", fontsize=12, color=_CG_COLOUR,
        fontweight="bold",
    ))  # fmt: skip
    if scene.mounts.size:
        ax.scatter(scene.mounts[:, a], scene.mounts[:, b], color=_MOUNT_COLOUR, marker="^", s=60, zorder=2)
        for k, m in enumerate(scene.mounts):
            labels.append(ax.annotate(
                _mount_tag(k), (m[a], m[b]), xytext=(6, -12), textcoords="offset points", fontsize=11,
                color=_MOUNT_COLOUR, fontweight="bold",
            ))  # fmt: skip
    for p, text in scene.labels:
        labels.append(
            ax.annotate(
                text, (p[a], p[b]), xytext=(5, 5), textcoords="offset points", fontsize=10, color=_SENSOR_COLOUR
            )
        )
    if scene.roll_axis is not None:
        ends = g[None, :] + 0.45 * scene.size * np.outer([-1.0, 1.0], scene.roll_axis)
        ax.plot(ends[:, a], ends[:, b], color=_ROLL_COLOUR, lw=1.6, ls="--", zorder=2)
    centre, half = limits
    ax.set_xlim(centre[a] - half[a], centre[a] + half[a])
    ax.set_ylim(centre[b] - half[b], centre[b] + half[b])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{'xyz'[a]} [{length}]")
    ax.set_ylabel(f"{'xyz'[b]} [{length}]")
    ax.grid(True, color="#e3e7ec", lw=0.8)
    ax.set_title(title, fontsize=12)
    points = np.vstack([pos[:, [a, b]], g[None, [a, b]], scene.mounts.reshape(-1, 3)[:, [a, b]]])
    return labels, points


def _mount_tag(k: int) -> str:
    """The short name of mount `k` on the figures (``M1``...); its rates are listed beside the figure."""
    return f"M{k + 1}"


_LABEL_SPOTS = (
    ((6, 6), "left", "bottom"), ((6, -6), "left", "top"), ((-6, 6), "right", "bottom"), ((-6, -6), "right", "top"),
    ((0, 12), "center", "bottom"), ((0, -12), "center", "top"), ((14, 0), "left", "center"),
    ((-14, 0), "right", "center"), ((8, 20), "left", "bottom"), ((-8, 20), "right", "bottom"),
    ((8, -20), "left", "top"), ((-8, -20), "right", "top"), ((0, 30), "center", "bottom"),
    ((0, -30), "center", "top"),
)  # fmt: skip
"""Where a label may sit beside its point (offset in points, alignment), tried in this order."""


def _place_labels(ax: Any, labels: Sequence[Any], points: Array, renderer: Any) -> int:
    """Move each label to the first spot beside its point that overlaps no label placed before and no marker.

    Labels come in order of priority; a label with no free spot keeps the first one. Returns how many
    labels found no free spot (0 when none overlap).
    """
    from matplotlib.transforms import Bbox

    marker = 5.0 * renderer.points_to_pixels(1.0)  # half the size of a marker, in pixels
    taken = [Bbox.from_extents(x - marker, y - marker, x + marker, y + marker)
             for x, y in ax.transData.transform(points)]  # fmt: skip
    crowded = 0
    for label in labels:
        for offset, ha, va in (*_LABEL_SPOTS, _LABEL_SPOTS[0]):
            label.xyann = offset
            label.set_horizontalalignment(ha)
            label.set_verticalalignment(va)
            box = label.get_window_extent(renderer).expanded(1.04, 1.08)
            if not any(box.overlaps(other) for other in taken):
                break
        else:
            crowded += 1
        taken.append(label.get_window_extent(renderer))
    return crowded


def _layout_key(notes: Any, scene: _Scene, moments: Array, moment_unit: str, length: str) -> None:
    """The legend of the layout figure and its numbers (CG, principal moments)."""
    from matplotlib.lines import Line2D

    notes.axis("off")
    handles = [
        Line2D([], [], color=_SENSOR_COLOUR, marker="o", lw=1.4, label="sensor → measuring direction"),
        Line2D(
            [], [], color=_SENSOR_COLOUR, marker="o", mfc="none", ms=10, lw=0,
            label="⊙ / ⊗ direction towards / away from viewer",
        ),
        Line2D([], [], color=_CG_COLOUR, marker="*", ms=13, lw=0, label="centre of gravity (CG)"),
        *(Line2D([], [], color=_AXIS_COLOURS[k], lw=2.2, label=f"principal axis {k + 1}") for k in range(3)),
    ]  # fmt: skip
    if scene.mounts.size:
        handles.append(Line2D([], [], color=_MOUNT_COLOUR, marker="^", ms=8, lw=0, label="mount M1, M2, ..."))
    if scene.roll_axis is not None:
        handles.append(Line2D([], [], color=_ROLL_COLOUR, lw=2.0, ls="--", label="torque roll axis (J⁻¹t, CG)"))
    notes.legend(handles=handles, loc="upper left", fontsize=11, frameon=False)
    mounts = "".join(f"\n  {_mount_tag(k)} {text}" for k, text in enumerate(scene.mount_labels[: len(scene.mounts)]))
    text = (
        f"CG = ({', '.join(fmt_num(float(v), 4) for v in scene.g)}) {length}\n"
        f"principal moments [{moment_unit}]:\n  "
        + ", ".join(f"{k + 1}: {fmt_num(float(m), 4)}" for k, m in enumerate(moments))
        + (f"\nmounts:{mounts}" if mounts else "")
    )
    notes.text(0.0, 0.02, text, transform=notes.transAxes, fontsize=11, va="bottom", family="DejaVu Sans")


def _unit(v: ArrayLike) -> Array:
    u = np.asarray(v, dtype=float).reshape(3)
    norm = float(np.linalg.norm(u))
    if not (math.isfinite(norm) and norm > 0.0):
        raise InputError("the torque roll axis must be a finite non-zero vector", source="roll_axis")
    return u / norm


def _layout_figure(
    ident: Identification,
    positions: Array,
    directions: Array,
    sensor_ids: Sequence[str],
    length: str,
    mass: str,
    mounts: Array,
    mount_labels: Sequence[str] = (),
    roll_axis: ArrayLike | None = None,
) -> Figure:
    """3D view above a third-angle drawing: top view over front view, side view right of it."""
    g = ident.center_of_gravity
    has_mass = ident.principal_moments is not None
    moments = ident.principal_moments if ident.principal_moments is not None else ident.principal_moments_per_mass
    moment_unit = f"{mass}·{length}²" if has_mass else f"{length}² (per unit mass)"
    size = _scene_size(positions, g[None, :], mounts)
    axis_len = 0.5 * float(np.max(np.linalg.norm(positions - g, axis=1))) or 0.2 * size
    scene = _Scene(
        positions=positions,
        directions=directions,
        labels=_sensor_labels(positions, sensor_ids, size),
        g=g,
        axes=ident.principal_axes,
        tips=g[None, :] + axis_len * ident.principal_axes.T,
        mounts=mounts,
        mount_labels=list(mount_labels),
        outline=sensor_outline(positions),
        arrow=0.12 * size,
        size=size,
        roll_axis=None if roll_axis is None else _unit(roll_axis),
    )
    everything = np.vstack(
        [positions, positions + scene.arrow * directions, g[None, :], scene.tips, mounts.reshape(-1, 3)]
    )
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    centre = 0.5 * (lo + hi)
    half = 0.5 * np.maximum(hi - lo, 0.25 * float(np.max(hi - lo))) + 0.08 * float(np.max(hi - lo))

    fig = new_figure(12.0, 13.0, {"left": 0.07, "right": 0.985, "bottom": 0.04, "top": 0.955, "hspace": 0.3})
    grid = fig.add_gridspec(
        3, 2, width_ratios=[half[0], half[1]], height_ratios=[1.15 * (half[0] + half[1]) / 2.0, half[1], half[2]]
    )
    _layout_3d(fig.add_subplot(grid[0, :], projection="3d"), scene, everything, length)
    top = fig.add_subplot(grid[1, 0])
    front = fig.add_subplot(grid[2, 0], sharex=top)
    side = fig.add_subplot(grid[2, 1], sharey=front)
    views = [(ax, *_projection(ax, scene, a, b, label, (centre, half), length))
             for ax, (a, b), label in ((top, (0, 1), "top view (x-y)"), (front, (0, 2), "front view (x-z)"),
                                       (side, (1, 2), "side view (y-z)"))]  # fmt: skip
    _layout_key(fig.add_subplot(grid[1, 1]), scene, moments, moment_unit, length)
    fig.suptitle("Sensors, centre of gravity and principal axes of inertia", fontsize=13)
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]  # the Agg canvas of new_figure
    for ax, labels, points in views:
        ax.apply_aspect()  # the axes' final box (equal scales), as drawn: then the labels are placed
        _place_labels(ax, labels, points, renderer)
    return fig


@dataclass(frozen=True)
class _Decoupling:
    """The decoupling table: ONE definition for the report's heat map, its numbers and the mode titles.

    The modes are the measured modes used, in the order given, each as the rigid
    motion of the CG that best explains it (``Identification.mode_shapes_cg``),
    the same rows as the terminal table and ``energy_distribution`` of the
    result JSON.
    """

    labels: list[str]
    frequency_hz: Array
    damping_ratio: Array
    shapes: CArray
    plain: Array
    principal: Array


def _decoupling(ident: Identification, mode_labels: Sequence[int] | None) -> _Decoupling:
    n = ident.frequency_hz.shape[0]
    labels = [str(m) for m in mode_labels] if mode_labels is not None else [str(k + 1) for k in range(n)]
    if len(labels) != n:
        raise InputError(f"{len(labels)} mode labels for {n} modes", source="mode_labels")
    shapes = ident.mode_shapes_cg
    return _Decoupling(
        labels=labels,
        frequency_hz=ident.frequency_hz,
        damping_ratio=ident.damping_ratio,
        shapes=shapes,
        plain=kinetic_energy_distribution(ident.inertia_per_mass, shapes),
        principal=kinetic_energy_distribution_principal(ident.inertia_per_mass, shapes),
    )


def _mode_title(label: str, f: float, z: float, fractions: Array) -> str:
    top = np.argsort(-fractions)[:2]
    parts = ", ".join(f"{DOF_LABELS[i]} {100 * fractions[i]:.1f} %" for i in top if fractions[i] >= 0.05)
    return f"Mode {label}: {f:#.4g} Hz, ζ {100 * z:.2g} %\n{parts}"


def _modes_figure(ident: Identification, positions: Array, length: str, table: _Decoupling) -> Figure:
    g = ident.center_of_gravity
    shapes = table.shapes
    outline = sensor_outline(positions)
    size = _scene_size(positions, g[None, :])
    margins = {"left": 0.01, "right": 0.99, "bottom": 0.02, "top": 0.87, "wspace": 0.05, "hspace": 0.2}
    fig = new_figure(13.0, 7.4, margins)
    points = np.vstack([positions, g[None, :]])
    for k in range(shapes.shape[1]):
        ax = fig.add_subplot(2, 3, k + 1, projection="3d")
        motion = _point_motion(shapes[:, k], points, g)
        peak = motion.reshape(-1)[np.argmax(np.abs(motion).reshape(-1))]
        real = np.real(motion / peak) if abs(peak) > 0.0 else np.zeros_like(points)
        amplitude = float(np.max(np.linalg.norm(real[:-1], axis=1))) or 1.0
        moved = points + (0.25 * size / amplitude) * real
        for pts, colour, style, width in ((points, "#8a97a5", "--", 1.0), (moved, _MODE_COLOUR, "-", 1.8)):
            ring = pts[outline]
            ax.plot(ring[:, 0], ring[:, 1], ring[:, 2], color=colour, ls=style, lw=width)
            ax.scatter(*pts[:-1].T, color=colour, s=16, depthshade=False)
            ax.scatter(*pts[-1], color=colour, s=70, marker="*", depthshade=False)
        paths = np.stack([points, moved, np.full_like(points, np.nan)], axis=1).reshape(-1, 3)
        ax.plot(*paths.T, color=_MODE_COLOUR, lw=0.7, ls=":")  # the path of every point: one line, broken by NaN
        _equal_3d(ax, np.vstack([points, moved]), zoom=1.1)
        title = _mode_title(
            table.labels[k], float(table.frequency_hz[k]), float(table.damping_ratio[k]), table.plain[k]
        )
        ax.set_title(title, fontsize=12)
        ax.set_xlabel(f"x [{length}]", fontsize=10, labelpad=-2)
        ax.set_ylabel(f"y [{length}]", fontsize=10, labelpad=-2)
        ax.set_zlabel(f"z [{length}]", fontsize=10, labelpad=-2)
        ax.tick_params(labelsize=7, pad=0)
        ax.view_init(elev=22, azim=-60)
    fig.suptitle(
        "Rigid-body motion of each measured mode used: sensor outline at rest (grey, dashed) and displaced (red), "
        "dotted: path of each sensor; ★ = CG",
        fontsize=11,
    )
    return fig


def _decoupling_figure(table: _Decoupling) -> Figure:
    rows = [f"{label}: {f:#.4g} Hz" for label, f in zip(table.labels, table.frequency_hz, strict=True)]
    fig = new_figure(11.0, 4.4, {"left": 0.09, "right": 0.96, "bottom": 0.07, "top": 0.93, "wspace": 0.04})
    panels = (
        (table.plain, DOF_LABELS, "test axes"),
        (table.principal, PRINCIPAL_DOF_LABELS, "rotations about the principal axes"),
    )
    image = None
    for i, (shares, columns, label) in enumerate(panels):
        ax = fig.add_subplot(1, 2, i + 1)
        percent = 100.0 * shares
        image = ax.imshow(np.clip(percent, 0.0, 100.0), cmap="Blues", vmin=0.0, vmax=100.0, aspect="auto")
        for r in range(percent.shape[0]):
            for c in range(percent.shape[1]):
                ax.text(
                    c,
                    r,
                    f"{percent[r, c]:.1f}",
                    ha="center",
                    va="center",
                    fontsize=9,
                    color="white" if percent[r, c] > 55.0 else "#1a1a1a",
                )
        ax.set_xticks(range(6), columns, fontsize=10)
        ax.set_yticks(range(len(rows)), rows if i == 0 else [""] * len(rows), fontsize=10)
        ax.set_title(f"Kinetic energy per DOF [%], {label}", fontsize=11)
        ax.tick_params(length=0)
    if image is not None:
        fig.colorbar(image, ax=fig.axes, shrink=0.9, fraction=0.05, pad=0.02, label="% of the mode's kinetic energy")
    return fig


def check_stabilisation(stabilisation: Stabilisation) -> list[tuple[int, Array, NDArray[np.bool_]]]:
    from rigidid.core.timedomain.stabilisation import OrderPoles

    out = []
    for i, entry in enumerate(stabilisation):
        try:
            freq: ArrayLike
            stable: ArrayLike
            if isinstance(entry, OrderPoles):  # poles in rad/s
                order, freq, stable = entry.order, np.abs(entry.poles) / (2.0 * math.pi), entry.stable
            else:
                order, freq, stable = entry
            f = np.asarray(freq, dtype=float).reshape(-1)
            s = np.asarray(stable, dtype=bool).reshape(-1)
            o = int(order)
        except (TypeError, ValueError) as exc:
            raise InputError(
                f"expected (order, frequencies, stable flags): {exc}", source="stabilisation", location=f"entry {i}"
            ) from None
        if f.shape != s.shape:
            raise InputError(
                f"{f.size} frequencies but {s.size} stable flags", source="stabilisation", location=f"entry {i}"
            )
        out.append((o, f, s))
    return out


def stabilisation_figure(
    used_hz: Array,
    entries: list[tuple[int, Array, NDArray[np.bool_]]],
    spectrum: tuple[Array, Array] | None = None,
    spectrum_names: tuple[str, str] = (
        "sum of the records' spectra",
        "power spectral density (sum over channels and records)",
    ),
) -> Figure:
    """Poles per model order over a summed spectrum; vertical lines at the frequencies `used_hz`; legend below.

    `spectrum_names` are the legend entry and the right axis' label of the spectrum.
    """
    fig = new_figure(11.0, 5.4, {"left": 0.07, "right": 0.92, "bottom": 0.17, "top": 0.94})
    ax = fig.add_subplot(1, 1, 1)
    handles: list[Any] = []
    top = max([float(np.max(f)) for _, f, _ in entries if f.size] + [float(np.max(used_hz))])
    ax.set_xlim(0.0, 1.1 * top)
    if spectrum is not None:
        freq, power = spectrum
        back = ax.twinx()
        shown = (power > 0.0) & (freq <= 1.1 * top)
        back.fill_between(freq[shown], power[shown], color="#d9dee5", lw=0.0, zorder=0)
        (line,) = back.plot(freq[shown], power[shown], color="#9aa7b5", lw=0.8, label=spectrum_names[0])
        back.set_yscale("log")
        back.set_ylabel(spectrum_names[1], color="#6b7886", fontsize=9)
        back.tick_params(axis="y", colors="#6b7886", labelsize=8)
        ax.set_zorder(back.get_zorder() + 1)  # poles in front of the spectrum
        ax.patch.set_visible(False)
        handles.append(line)
    for f in used_hz:
        ax.axvline(float(f), color=_CG_COLOUR, lw=0.9, alpha=0.6, zorder=1)
    first = [True, True]
    for order, f, s in entries:
        if np.any(~s):
            handle = ax.scatter(
                f[~s], np.full(int(np.sum(~s)), order), marker="x", s=14, color="#7d8a98", label="not stable", zorder=2
            )
            if first[0]:
                handles.append(handle)
            first[0] = False
        if np.any(s):
            handle = ax.scatter(
                f[s], np.full(int(np.sum(s)), order), marker="o", s=22, color=_SENSOR_COLOUR, label="stable", zorder=3
            )
            if first[1]:
                handles.append(handle)
            first[1] = False
    (used,) = ax.plot([], [], color=_CG_COLOUR, lw=0.9, label="modes used")
    handles.append(used)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    ax.grid(True, color="#e3e7ec", lw=0.8)
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=9, frameon=False)
    ax.set_title("Stabilisation diagram", fontsize=11)
    return fig


def _as_arrays(
    positions: ArrayLike, directions: ArrayLike, sensor_ids: Sequence[str], mounts: Sequence[ArrayLike] | None
) -> tuple[Array, Array, list[str], Array]:
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = np.asarray(directions, dtype=float).reshape(-1, 3)
    ids = [str(s) for s in sensor_ids]
    if dirs.shape != pos.shape or len(ids) != pos.shape[0]:
        raise InputError(f"{pos.shape[0]} positions, {dirs.shape[0]} directions and {len(ids)} sensor ids")
    norms = np.linalg.norm(dirs, axis=1)
    if np.any(~(norms > 0.0)) or not np.all(np.isfinite(pos)):
        raise InputError("positions must be finite and directions non-zero")
    m = np.zeros((0, 3)) if not mounts else np.asarray([np.asarray(p, dtype=float).reshape(3) for p in mounts])
    return pos, dirs / norms[:, None], ids, m


def _figures(
    ident: Identification,
    positions: ArrayLike,
    directions: ArrayLike,
    sensor_ids: Sequence[str],
    units: Mapping[str, str],
    mounts: Sequence[ArrayLike] | None,
    stabilisation: Stabilisation | None,
    *,
    mode_labels: Sequence[int] | None = None,
    mount_labels: Sequence[str] = (),
    spectrum: tuple[ArrayLike, ArrayLike] | None = None,
    progress: ProgressCallback | None = None,
    roll_axis: ArrayLike | None = None,
) -> dict[str, Figure]:
    length, mass = _units(units)
    pos, dirs, ids, m = _as_arrays(positions, directions, sensor_ids, mounts)
    entries = None if stabilisation is None else check_stabilisation(stabilisation)  # check before drawing
    table = _decoupling(ident, mode_labels)
    back = None
    if spectrum is not None:
        back = (np.asarray(spectrum[0], dtype=float).ravel(), np.asarray(spectrum[1], dtype=float).ravel())
        if back[0].shape != back[1].shape:
            raise InputError("frequencies and spectrum differ in length", source="spectrum")
    step = progress or no_progress
    drawers: list[tuple[str, Callable[[], Figure]]] = [
        ("layout", lambda: _layout_figure(ident, pos, dirs, ids, length, mass, m, mount_labels, roll_axis)),
        ("modes", lambda: _modes_figure(ident, pos, length, table)),
        ("decoupling", lambda: _decoupling_figure(table)),
    ]
    if entries is not None:
        drawers.append(("stabilisation", lambda: stabilisation_figure(ident.frequency_hz, entries, back)))
    figures = {}
    for k, (name, draw) in enumerate(drawers):
        step("drawing the report's figures", k, len(drawers))
        figures[name] = draw()
    step("drawing the report's figures", len(drawers), len(drawers))
    return figures


def png_bytes(fig: Figure) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=_DPI, metadata={"Software": None})  # no URL in the file
    return buffer.getvalue()


# --------------------------------------------------------------------------- HTML

CSS = (
    """
body { font-family: "DejaVu Sans", "Segoe UI", Helvetica, Arial, sans-serif; font-size: 15px; color: #1a1a1a;
       max-width: 1180px; margin: 24px auto; padding: 0 16px; line-height: 1.45; }
h1 { font-size: 26px; margin-bottom: 4px; }
h2 { font-size: 20px; margin-top: 34px; border-bottom: 2px solid #d5dbe2; padding-bottom: 4px; }
h3 { font-size: 16px; margin: 18px 0 6px; }
p.meta { color: #4a5663; margin-top: 0; }
table { border-collapse: collapse; margin: 6px 0 12px; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #d5dbe2; padding: 4px 10px; text-align: right; }
th { background: #eef2f6; font-weight: 600; }
td.label, th.label { text-align: left; }
td:not(.label) { white-space: nowrap; }
.wide { overflow-x: auto; max-width: 100%; }
caption { caption-side: bottom; text-align: left; color: #4a5663; font-size: 13px; padding-top: 4px; }
figure { margin: 10px 0 20px; }
figure img { max-width: 100%; height: auto; border: 1px solid #e3e7ec; }
figcaption { color: #4a5663; font-size: 13px; margin-top: 4px; }
.warn { background: #fff4e0; border-left: 4px solid #d68910; padding: 6px 12px; margin: 6px 0; }
.flex { display: flex; flex-wrap: wrap; gap: 28px; align-items: flex-start; }
details summary { cursor: pointer; color: #1f5fa8; }
table.test th { text-align: left; background: none; border: none; padding: 1px 14px 1px 0; color: #4a5663; }
table.test td { text-align: left; border: none; padding: 1px 0; white-space: pre-wrap; }
@media print {
  @page { size: A4; margin: 14mm 12mm; }
  body { max-width: none; margin: 0; padding: 0; font-size: 9.5pt; color: #000; }
  h1 { font-size: 16pt; } h2 { font-size: 12.5pt; margin-top: 14pt; break-after: avoid; }
  h3 { font-size: 10.5pt; break-after: avoid; }
  table, figure, .warn { break-inside: avoid; }
  th, td { padding: 2px 6px; }
  .wide { overflow: visible; } td:not(.label) { white-space: normal; }  /* on paper nothing may be cut off */
  caption, figcaption { font-size: 8.5pt; }
  figure img { max-width: 100%; border: none; }
  details > summary { display: none; }
  .flex { gap: 12pt; }
}
"""
    + VIEWER_CSS
)


def table_html(
    header: Sequence[str], rows: Sequence[Sequence[str]], *, caption: str | None = None, label_cols: int = 1
) -> str:
    head = "".join(
        f'<th class="label">{esc(h)}</th>' if i < label_cols else f"<th>{esc(h)}</th>" for i, h in enumerate(header)
    )
    body = "".join(
        "<tr>"
        + "".join(f'<td class="label">{c}</td>' if i < label_cols else f"<td>{c}</td>" for i, c in enumerate(row))
        + "</tr>"
        for row in rows
    )
    cap = f"<caption>{esc(caption)}</caption>" if caption else ""
    # in a box of the page's width that scrolls sideways when the table is wider (the page itself never does)
    return f'<div class="wide"><table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>'


def matrix_html(a: Array, labels: Sequence[str], caption: str | None = None) -> str:
    """A square matrix as a table; entries below 1e-9 of ``sqrt(|a_ii a_jj|)`` (their own unit) print as 0."""
    from rigidid.render import ROUNDING_ZERO

    floor = np.zeros_like(a)
    if a.ndim == 2 and a.shape[0] == a.shape[1] and np.all(np.isfinite(a)):
        scale = np.sqrt(np.abs(np.diag(a)))
        floor = ROUNDING_ZERO * np.outer(scale, scale)
    shown = np.where(np.abs(a) < floor, 0.0, a)
    rows = [[esc(labels[i]), *(fmt_num(float(v)) for v in shown[i])] for i in range(a.shape[0])]
    return table_html(["", *labels], rows, caption=caption)


def figure_html(png: bytes, alt: str, caption: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return (
        f'<figure><img src="data:image/png;base64,{data}" alt="{esc(alt)}">'
        f"<figcaption>{esc(caption)}</figcaption></figure>"
    )


def _percent(v: float) -> str:
    return f"{fmt_num(100.0 * v, 3)} %"


def _interval_caption(source: Uncertainty | RecordSpread | RecordBound, length: str) -> tuple[str, str]:
    """A heading and a caption (in words and formatted numbers) saying where the intervals come from."""
    from rigidid.core.record_spread import RecordSpread
    from rigidid.core.uncertainty import Uncertainty

    if isinstance(source, Uncertainty):
        n = source.noise
        noise = (
            f"frequency {_percent(n.frequency)}, damping {_percent(n.damping)}, shape {_percent(n.shape)} of each "
            f"mode's RMS, position {fmt_num(n.position, 3)} {length}, angle {fmt_num(n.angle_deg, 3)}°"
        )
        seed = "" if source.seed is None else f", seed {source.seed}"
        return "Monte Carlo", (
            f"{source.draws} draws of the measurement errors ({source.failed} failed, {source.implausible} "
            f"implausible{seed}); standard deviations assumed: {noise}. Interval: 2.5 and 97.5 percentiles."
        )
    if isinstance(source, RecordSpread):
        return "record segments", (
            f"{source.used} of {source.segments} interleaved segments of the records identified apart; the "
            f"spread of their estimates over √{source.used}; interval with Student's t. Measurement noise only."
        )
    cost = fmt_num(source.normalised_cost, 3)
    return "Cramér-Rao bound on the records", (
        f"the refit on the records (output error): standard errors from its {source.variance_from} covariance, "
        f"noise from the {source.noise_from}, normalised cost {cost} (about 1 at a good fit); "
        f"interval: estimate ± 1.96 standard errors."
    )


def _uncertainty_rows(
    source: Uncertainty | RecordSpread | RecordBound, length: str, mass: str, force_unit: str | None
) -> list[list[str]]:
    """One row per component, in the units of the tables above (force units for K and C)."""
    from rigidid.units import force_units

    per_mass = source.per_mass
    inertia_unit = f"{length}²" if per_mass else f"{mass}·{length}²"
    quantities: list[tuple[str, Any, list[str], list[str], float]] = [
        ("centre of gravity", source.center_of_gravity, ["x", "y", "z"], [length] * 3, 1.0),
        ("inertia tensor" + (" per mass" if per_mass else ""), source.inertia,
         [f"{a}{b}" for a in "xyz" for b in "xyz"], [inertia_unit] * 9, 1.0),
        ("principal moments" + (" per mass" if per_mass else ""), source.principal_moments, ["1", "2", "3"],
         [inertia_unit] * 3, 1.0),
    ]  # fmt: skip
    diagonals = [("stiffness", source.stiffness_diagonal, 2)]
    damping = getattr(source, "damping_diagonal", None)
    if damping is not None:
        diagonals.append(("damping", damping, 1))
    for name, interval, power in diagonals:
        if per_mass:
            t, _, r = _block_units(length, None, power)
            factor, label = 1.0, f"{name} diagonal per mass"
        else:
            fu = force_units(length, mass, force_unit)
            spelt = fu.stiffness if power == 2 else fu.damping
            t, r, factor, label = spelt["translation"], spelt["rotation"], fu.factor, f"{name} diagonal"
        quantities.append((label, interval, list(DOF_LABELS), [t] * 3 + [r] * 3, factor))
    rows: list[list[str]] = []
    for name, interval, labels, units, factor in quantities:
        est, std = factor * np.asarray(interval.estimate), factor * np.asarray(interval.std)
        low, high = factor * np.asarray(interval.low), factor * np.asarray(interval.high)
        for k, index in enumerate(np.ndindex(est.shape)):
            if est.shape == (3, 3) and index[0] > index[1]:
                continue  # symmetric tensor: the upper triangle says it all
            rows.append([
                esc(name) if k == 0 else "", esc(labels[k]), esc(units[k]), fmt_num(float(est[index])),
                fmt_num(float(std[index]), 3), f"{fmt_num(float(low[index]))} … {fmt_num(float(high[index]))}",
            ])  # fmt: skip
    return rows


def _uncertainty_html(
    sources: Sequence[Uncertainty | RecordSpread | RecordBound], length: str, mass: str, force_unit: str | None
) -> str:
    """One table per source of intervals, in the units of the result tables, with a caption in words."""
    parts = []
    for source in sources:
        heading, caption = _interval_caption(source, length)
        if not np.asarray(source.center_of_gravity.estimate).shape == (3,):
            raise InputError("the intervals of the CG are not three numbers", source="uncertainty")
        rows = _uncertainty_rows(source, length, mass, force_unit)
        parts.append(f"<h3>{esc(heading)}</h3>")
        parts.append(
            table_html(["quantity", "component", "unit", "estimate", "std", "95 % interval"], rows, caption=caption,
                   label_cols=3)
        )  # fmt: skip
    return "\n".join(parts)


def render_report(
    identification: Identification,
    positions: ArrayLike,
    directions: ArrayLike,
    sensor_ids: Sequence[str],
    units: Mapping[str, str],
    *,
    mounts: Sequence[ArrayLike] | None = None,
    stabilisation: Stabilisation | None = None,
    uncertainty: Intervals | Sequence[Intervals] | None = None,
    title: str = "rigidid report",
    mode_labels: Sequence[int] | None = None,
    inputs: Sequence[str] = (),
    force_unit: str | None = None,
    mount_stiffness: Sequence[ArrayLike] | None = None,
    spectrum: tuple[ArrayLike, ArrayLike] | None = None,
    created: str | None = None,
    progress: ProgressCallback | None = None,
    identified_mounts: Mounts | None = None,
    torque_roll_axis: TorqueRollAxis | None = None,
    test: TestInfo | None = None,
    png: str | os.PathLike[str] | None = None,
) -> str:
    """One self-contained HTML document reporting an identification.

    Parameters
    ----------
    identification : Identification
        The result of :func:`rigidid.core.identify.identify`.
    positions : array_like, shape (p, 3)
        Sensor positions (length unit).
    directions : array_like, shape (p, 3)
        Measuring axes (normalised here).
    sensor_ids : sequence of str, length p
        Labels of the sensors.
    units : mapping
        ``{"length": ..., "mass": ...}`` as in ``layout.json``.
    mounts : sequence of array_like of shape (3,), optional
        Mount positions (length unit), drawn in the layout figure.
    stabilisation : sequence of (int, array_like, array_like), optional
        A stabilisation diagram: one ``(order, frequency_hz, stable)`` entry
        per model order, ``frequency_hz`` the (n,) pole frequencies in Hz
        found at that order and ``stable`` an (n,) bool array marking the
        stable ones. Objects with ``order``, ``poles`` (rad/s) and
        ``stable`` attributes (``OrderPoles`` of
        :mod:`rigidid.core.timedomain.stabilisation`) are accepted as well.
    uncertainty : Uncertainty, RecordSpread or RecordBound, or a sequence of them, optional
        Intervals of the identified quantities (Monte Carlo, record segments, the
        refit's Cramér-Rao bound): one table each, in the units of the result
        tables (stiffness and damping in force units with a mass), with a
        caption saying where they come from.
    title : str
        Heading and ``<title>`` of the document.
    mode_labels : sequence of int, optional
        Labels of the modes used (default 1..6), shown wherever a mode is named.
    inputs : sequence of str
        Names of the input files, listed under the title.
    force_unit : {"N", "kN", "lbf"}, optional
        Force unit of stiffness and damping when the mass is known (default N
        for kg, g, t; lbf for lb, slug; see :mod:`rigidid.units`).
    mount_stiffness : sequence of array_like of shape (3, 3), optional
        Stiffness of each mount (mass/s^2), written beside its marker in the
        force unit.
    spectrum : (array_like, array_like), optional
        Frequencies (Hz) and the summed power spectrum of the records, drawn
        behind the stabilisation diagram.
    created : str, optional
        Date and time shown under the title (default: now, UTC).
    progress : callable, optional
        ``progress(task, done, total)`` while the figures are drawn.
    identified_mounts : Mounts, optional
        Per-mount rates identified from the test (``IdentifyResult.mounts``): drawn at
        the mounts (positions from here, replacing `mounts` and `mount_stiffness`)
        and tabled in force units (per unit mass without a mass).
    torque_roll_axis : TorqueRollAxis, optional
        Drawn through the CG and tabled.
    test : TestInfo, optional
        The test's id, specimen, date, operator and notes (the layout's ``test``
        block), shown under the title.
    png : path-like, optional
        An existing folder to write the same figures into as PNG files (as
        :func:`save_pngs`, from the images the page embeds: drawn once).

    Returns
    -------
    str
        The HTML text (UTF-8): result tables (CG, inertia tensor, principal
        moments and axes, stiffness and damping matrices with units, modes,
        diagnostics), the decoupling table, the figures (see the module
        documentation) as embedded PNG, and the uncertainty table when given.

    Raises
    ------
    InputError
        Inconsistent sensor arrays, units without length or mass, a malformed
        stabilisation or uncertainty argument.
    RigididError
        If matplotlib is not installed.
    """
    length, mass_unit = _units(units)
    if identified_mounts is not None:
        mounts = list(identified_mounts.positions)
    pos, dirs, ids, mount_pos = _as_arrays(positions, directions, sensor_ids, mounts)
    sources = [] if uncertainty is None else list(uncertainty) if isinstance(uncertainty, Sequence) else [uncertainty]
    uncertainty_table = _uncertainty_html(sources, length, mass_unit, force_unit) if sources else None
    ident = identification
    table = _decoupling(ident, mode_labels)
    mount_labels = stiffness_labels(mount_stiffness, length, mass_unit, force_unit)
    has_mass = ident.mass is not None
    drawn_labels = (
        mount_labels
        if identified_mounts is None
        else identified_mount_labels(identified_mounts, units, has_mass=has_mass, force_unit=force_unit)
    )
    roll = None if torque_roll_axis is None else torque_roll_axis.direction
    figures = _figures(
        ident, pos, dirs, ids, units, mounts, stabilisation, mode_labels=mode_labels, mount_labels=drawn_labels,
        spectrum=spectrum, progress=progress, roll_axis=roll,
    )  # fmt: skip
    pngs = {name: png_bytes(fig) for name, fig in figures.items()}
    if png is not None:
        write_pngs(png, pngs)
    parts = [
        head_html(title, ident, ids, length, mass_unit, inputs, created),
        test_html(test),
        *(f'<div class="warn">⚠ {esc(message)}</div>' for message in ident.diagnostics.warnings),
        _mass_properties_html(ident, length, mass_unit),
        _modes_html(ident, table),
        _supports_html(ident, length, mass_unit, force_unit),
        _decoupling_html(table, pngs["decoupling"]),
        _layout_html(pngs["layout"], pos, dirs, ids, length, mount_pos, [] if identified_mounts else mount_labels),
        _identified_mounts_html(identified_mounts, torque_roll_axis, units, has_mass, force_unit),
        "<h2>Mode shapes</h2>",
        _viewer_html(ident, pos, ids, table, length),
        figure_html(
            pngs["modes"],
            "rigid-body mode shapes",
            "Each measured mode used, as the rigid-body motion that best fits its sensor readings (the rows of the "
            "decoupling table); the largest sensor displacement is drawn as a quarter of the layout size. Complex "
            "modes are shown at the phase of their largest motion.",
        ),
    ]
    if "stabilisation" in pngs:
        parts.append("<h2>Stabilisation diagram</h2>")
        behind = "; grey: the sum of the records' power spectra (right axis)" if spectrum is not None else ""
        parts.append(
            figure_html(
                pngs["stabilisation"],
                "stabilisation diagram",
                f"Poles per model order; vertical lines: the measured modes used{behind}.",
            )
        )
    if uncertainty_table is not None:
        parts += ["<h2>Uncertainty</h2>", uncertainty_table]
    parts += [_diagnostics_html(ident), "</body></html>"]
    return "\n".join(parts)


def _viewer_html(ident: Identification, pos: Array, ids: Sequence[str], table: _Decoupling, length: str) -> str:
    """The interactive 3D view of the modes (:mod:`rigidid.modeviewer`), titled as the static figure."""
    titles = [
        _mode_title(label, float(f), float(z), fractions).replace("\n", " · ")
        for label, f, z, fractions in zip(
            table.labels, table.frequency_hz, table.damping_ratio, table.plain, strict=True
        )
    ]
    return mode_viewer_html(pos, ids, ident.center_of_gravity, table.shapes, titles, length)


def head_html(
    title: str,
    ident: Identification,
    ids: Sequence[str],
    length: str,
    mass_unit: str,
    inputs: Sequence[str],
    created: str | None,
) -> str:
    """Document head, title, and the line of what this is: version, date, inputs, units, mass."""
    import datetime

    when = created or datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    mass_text = f"{fmt_num(ident.mass)} {mass_unit}" if ident.mass is not None else "not given (results per unit mass)"
    files = f'<p class="meta">input: {esc(", ".join(inputs))}</p>' if inputs else ""
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{esc(title)}</title><style>{CSS}</style></head><body>",
            f"<h1>{esc(title)}</h1>",
            f'<p class="meta">rigidid {esc(__version__)} · {esc(when)} · method {esc(ident.method)} · units: '
            f"length {esc(length)}, mass {esc(mass_unit)}, time s · mass {esc(mass_text)} · {len(ids)} sensors</p>",
            files,
        ]
    )


def test_html(test: TestInfo | None) -> str:
    """The test block under the title: id, specimen, date, operator, notes (what is given)."""
    if test is None:
        return ""
    fields = [("test", test.id), ("specimen", test.specimen), ("date of measurement", test.date),
              ("operator", test.operator), ("notes", test.notes)]  # fmt: skip
    rows = "".join(f"<tr><th>{esc(k)}</th><td>{esc(v)}</td></tr>" for k, v in fields if v)
    return f'<table class="test">{rows}</table>' if rows else ""


def _mass_properties_html(ident: Identification, length: str, mass_unit: str) -> str:
    has_mass = ident.mass is not None
    parts = ["<h2>Centre of gravity and inertia</h2>", '<div class="flex"><div><h3>Centre of gravity</h3>']
    parts.append(
        table_html(
            ["", f"[{length}]"],
            [[a, fmt_num(float(v))] for a, v in zip("xyz", ident.center_of_gravity, strict=True)],
            caption="in the layout's axes",
        )
    )
    inertia = ident.inertia_tensor if ident.inertia_tensor is not None else ident.inertia_per_mass
    inertia_unit = f"{mass_unit}·{length}²" if has_mass else f"{length}² (per unit mass)"
    parts.append("</div><div><h3>Inertia tensor about the CG</h3>")
    parts.append(
        matrix_html(
            inertia,
            ["x", "y", "z"],
            caption=f"[{inertia_unit}]; off-diagonal entries are tensor entries (minus the products of inertia)",
        )
    )
    moments = ident.principal_moments if ident.principal_moments is not None else ident.principal_moments_per_mass
    axes = ident.principal_axes
    parts.append("</div><div><h3>Principal moments and axes</h3>")
    parts.append(
        table_html(
            ["axis", f"moment [{inertia_unit}]", "x", "y", "z"],
            [[str(k + 1), fmt_num(float(moments[k])), *(fmt_num(float(v), 4) for v in axes[:, k])] for k in range(3)],
            caption="ascending moments; unit axis vectors in the layout's axes",
        )
    )
    parts.append("</div></div>")
    return "\n".join(parts)


def _modes_html(ident: Identification, table: _Decoupling) -> str:
    diag = ident.diagnostics
    rows = [
        [
            esc(table.labels[k]),
            fmt_num(float(ident.frequency_hz[k])),
            fmt_num(100 * float(ident.damping_ratio[k]), 4),
            fmt_num(float(diag.model_frequency_hz[k])),
            fmt_num(100 * float(diag.model_damping_ratio[k]), 4),
            f"{float(diag.model_mac[k]):.4f}",
            _residual(float(diag.rigid_fit_residual[k])),
        ]
        for k in range(ident.frequency_hz.shape[0])
    ]
    return "<h2>Modes</h2>" + table_html(
        [
            "mode",
            "measured f [Hz]",
            "measured ζ [%]",
            "model f [Hz]",
            "model ζ [%]",
            "MAC [-]",
            "rigid-fit residual [-]",
        ],
        rows,
        caption="measured modes used, by label, and the matching modes of the identified model",
    )


def _supports_html(ident: Identification, length: str, mass_unit: str, force_unit: str | None) -> str:
    """Stiffness and damping at the CG: in force units with a mass, else per unit mass."""
    from rigidid.units import force_units

    parts = []
    fu = force_units(length, mass_unit, force_unit) if ident.mass is not None else None
    for name, per_mass, power in (
        ("Stiffness", ident.stiffness_per_mass, 2),
        ("Damping", ident.damping_per_mass, 1),
    ):
        if fu is None or ident.mass is None:
            blocks = _block_units(length, None, power)
            parts.append(f"<h2>{name} matrix at the CG per unit mass</h2>")
            caption = f"units: x-z block [{blocks[0]}], coupling blocks [{blocks[1]}], rx-rz block [{blocks[2]}]"
            parts.append(matrix_html(per_mass, DOF_LABELS, caption=caption))
            continue
        u = fu.stiffness if power == 2 else fu.damping
        blocks_mass = _block_units(length, mass_unit, power)
        parts.append(f"<h2>{name} matrix at the CG</h2>")
        caption = (
            f"units: x-z block [{u['translation']}], coupling blocks [{u['coupling']}], rx-rz block "
            f"[{u['rotation']}]; rotations in rad. In the layout's units (result JSON {name.lower()}_matrix): "
            f"x-z block [{blocks_mass[0]}], coupling blocks [{blocks_mass[1]}], rx-rz block [{blocks_mass[2]}]; "
            f"multiplied by {fmt_num(fu.factor, 6)} they give the force units."
        )
        parts.append(matrix_html(fu.factor * ident.mass * per_mass, DOF_LABELS, caption=caption))
    return "\n".join(parts)


def _decoupling_html(table: _Decoupling, png: bytes) -> str:
    parts = ["<h2>Decoupling: kinetic energy distribution</h2>"]
    parts.append(
        figure_html(
            png,
            "kinetic energy distribution heat map",
            "Share of each measured mode's kinetic energy in each DOF at the CG (cycle-averaged for complex modes); "
            "rows sum to 100 %; the same numbers as the terminal table and energy_distribution in the result JSON. "
            "Left: test axes (entries can be negative with products of inertia; shown as 0 in colour). Right: "
            "rotations about the principal axes 1, 2, 3.",
        )
    )
    numbers = [
        [
            esc(f"{label} ({f:#.4g} Hz)"),
            *(f"{100 * v:.1f}" for v in table.plain[k]),
            *(f"{100 * v:.1f}" for v in table.principal[k]),
        ]
        for k, (label, f) in enumerate(zip(table.labels, table.frequency_hz, strict=True))
    ]
    parts.append("<details><summary>the numbers [%]</summary>")
    parts.append(
        table_html(
            ["mode", *DOF_LABELS, *(f"{c}\u2032" for c in PRINCIPAL_DOF_LABELS)],
            numbers,
            caption="primed columns: rotations about the principal axes",
        )
    )
    parts.append("</details>")
    return "\n".join(parts)


def _rate_units(units: Mapping[str, str], has_mass: bool, force_unit: str | None) -> tuple[float, str, str]:
    """Factor from the rates' units (mass/s², mass/s) to the tables', and the stiffness and damping units."""
    from rigidid.units import rate_units

    length, mass = _units(units)
    factor, k_unit, c_unit = rate_units(length, mass, force_unit, per_mass=not has_mass)
    return factor, k_unit.replace("^2", "²"), c_unit


def identified_mount_labels(
    identified: Mounts, units: Mapping[str, str], *, has_mass: bool = True, force_unit: str | None = None
) -> list[str]:
    """``front-left: k 180/160/420 N/mm`` per mount: its identified rates along its own axes.

    Parameters
    ----------
    identified : Mounts
        ``IdentifyResult.mounts``.
    units : mapping
        ``{"length", "mass"}`` of the layout.
    has_mass : bool
        Whether the identification knows the mass (else the rates are per unit mass).
    force_unit : str, optional
        As for :func:`render_report`.
    """
    factor, unit, _ = _rate_units(units, has_mass, force_unit)
    return [
        f"{name}: k " + "/".join(fmt_num(float(v), 3) for v in factor * identified.rates.stiffness[k]) + f" {unit}"
        for k, name in enumerate(identified.ids)
    ]


def _triple(values: ArrayLike | None, factor: float = 1.0) -> str:
    if values is None:
        return "-"
    return " / ".join(fmt_num(factor * float(v), 4) for v in np.asarray(values, dtype=float))


def _identified_mounts_html(
    identified: Mounts | None, roll: TorqueRollAxis | None, units: Mapping[str, str], has_mass: bool,
    force_unit: str | None,
) -> str:  # fmt: skip
    """The identified per-mount rates and the torque roll axis, as tables (empty without either)."""
    parts: list[str] = []
    length = _units(units)[0]
    if identified is not None:
        factor, k_unit, c_unit = _rate_units(units, has_mass, force_unit)
        rates = identified.rates
        damping = rates.damping
        rows = [
            [esc(name), _triple(identified.positions[k]),
             "; ".join(_direction_text(rates.axes[k][:, a]) for a in range(3)),
             _triple(rates.stiffness[k], factor), "-" if damping is None else _triple(damping[k], factor),
             "-" if identified.nominal is None else _triple(identified.nominal[k], factor),
             esc((identified.groups[k] if identified.groups else None) or "-")]
            for k, name in enumerate(identified.ids)
        ]  # fmt: skip
        parts += ["<h2>Mounts (identified)</h2>", table_html(
            ["mount", f"position [{length}]", "axes", f"stiffness [{k_unit}]", f"damping [{c_unit}]",
             f"data-sheet stiffness [{k_unit}]", "group"], rows,
            caption=f"rates along each mount's axes, fitted to the identified stiffness and damping at the CG; "
            f"residual |K - K_mounts| / |K| = {_residual(float(rates.stiffness_residual))}; {rates.statement}",
        )]  # fmt: skip
    if roll is not None:
        parts += ["<h2>Torque roll axis</h2>", table_html(
            ["torque axis", "roll axis (J⁻¹t)", "angle to torque axis [°]", "angles to principal axes 1/2/3 [°]"],
            [[esc(_direction_text(np.asarray(roll.torque_axis, dtype=float))),
              esc(_direction_text(np.asarray(roll.direction, dtype=float))),
              fmt_num(float(roll.angle_to_torque_deg), 3), _triple(roll.angle_to_principal_deg)]],
            caption="the axis through the CG the free body starts to turn about under a pure torque about the "
            "torque axis (dashed orange in the layout figure)",
        )]  # fmt: skip
    return "\n".join(parts)


def stiffness_labels(
    stiffness: Sequence[ArrayLike] | None, length: str, mass_unit: str, force_unit: str | None
) -> list[str]:
    """``k 180/160/420 N/mm`` per mount: the diagonal of its stiffness (mass/s², 3x3) in the force unit."""
    if not stiffness:
        return []
    from rigidid.units import force_units

    fu = force_units(length, mass_unit, force_unit)
    labels = []
    for k in stiffness:
        diag = fu.factor * np.diag(np.asarray(k, dtype=float).reshape(3, 3))
        labels.append("k " + "/".join(fmt_num(float(v), 3) for v in diag) + f" {fu.stiffness['translation']}")
    return labels


def _layout_html(
    png: bytes, pos: Array, dirs: Array, ids: Sequence[str], length: str, mounts: Array, mount_labels: Sequence[str]
) -> str:
    parts = ["<h2>Layout</h2>"]
    mount_text = ""
    if mounts.size:
        mount_text = " Mounts: black triangles" + (", with their stiffness along x/y/z." if mount_labels else ".")
    parts.append(
        figure_html(
            png,
            "sensor layout with CG and principal axes",
            f"Sensors (blue, arrows along the measuring directions; in the projections ⊙ points towards, ⊗ away "
            f"from the viewer; sensors at one point share one label), CG (red star) and principal axes 1, 2, 3 "
            f"from the CG; lengths in {length}.{mount_text}",
        )
    )
    parts.append(
        table_html(
            ["sensor", f"x [{length}]", f"y [{length}]", f"z [{length}]", "direction"],
            [
                [esc(sid), *(fmt_num(float(v)) for v in p), esc(_direction_text(d))]
                for sid, p, d in zip(ids, pos, dirs, strict=True)
            ],
        )
    )
    if mount_labels:
        parts.append(
            table_html(
                ["mount", f"x [{length}]", f"y [{length}]", f"z [{length}]", "stiffness x/y/z"],
                [
                    [str(k + 1), *(fmt_num(float(v)) for v in m), esc(text.removeprefix("k "))]
                    for k, (m, text) in enumerate(zip(mounts, mount_labels, strict=False))
                ],
                caption="from the body description",
            )
        )
    return "\n".join(parts)


def _diagnostics_html(ident: Identification) -> str:
    diag = ident.diagnostics
    return "<h2>Diagnostics</h2>" + table_html(
        ["quantity", "value"],
        [
            ["layout condition number", fmt_num(diag.layout_condition, 4)],
            ["layout rank", str(diag.layout_rank)],
            ["structure residual |DQ - (DQ)ᵀ| / |DQ|", _residual(diag.structure_residual)],
            ["largest rigid-fit residual", _residual(float(np.max(diag.rigid_fit_residual)))],
            ["smallest model MAC", f"{float(np.min(diag.model_mac)):.4f}"],
            ["warnings", f"{len(diag.warnings)} (listed at the top)" if diag.warnings else "none"],
        ],
    )


def _direction_text(d: Array) -> str:
    for i, name in enumerate("xyz"):
        if abs(abs(d[i]) - 1.0) < 1e-12:
            return ("+" if d[i] > 0 else "-") + name
    return "[" + ", ".join(f"{v:.4g}" for v in d) + "]"


# --------------------------------------------------------------------------- PNG files


def save_pngs(
    directory: str | os.PathLike[str],
    identification: Identification,
    positions: ArrayLike,
    directions: ArrayLike,
    sensor_ids: Sequence[str],
    units: Mapping[str, str],
    *,
    mounts: Sequence[ArrayLike] | None = None,
    stabilisation: Stabilisation | None = None,
    **extras: Any,
) -> list[Path]:
    """Write the report's figures as PNG files.

    Parameters
    ----------
    directory : path-like
        An existing folder.
    identification, positions, directions, sensor_ids, units, mounts, stabilisation
        As :func:`render_report`.
    **extras
        ``mode_labels``, ``mount_labels``, ``spectrum``, ``progress`` as for
        the figures of :func:`render_report`.

    Returns
    -------
    list of Path
        ``layout.png``, ``modes.png``, ``decoupling.png`` and, with a
        stabilisation diagram, ``stabilisation.png`` in `directory` (each
        written atomically, replacing a file of that name).

    Raises
    ------
    InputError
        As :func:`render_report`, or a folder that does not exist or is not
        writable.
    """
    folder = Path(directory)
    if not folder.is_dir():
        raise InputError("not an existing folder", source=str(folder))
    figures = _figures(identification, positions, directions, sensor_ids, units, mounts, stabilisation, **extras)
    return write_pngs(folder, {name: png_bytes(fig) for name, fig in figures.items()})


def write_pngs(directory: str | os.PathLike[str], pngs: Mapping[str, bytes]) -> list[Path]:
    """Write `pngs` (figure name -> PNG bytes) as ``<name>.png`` into `directory`, in the order of FIGURE_NAMES.

    Returns the paths written, each atomically (replacing a file of that name).
    """
    folder = Path(directory)
    if not folder.is_dir():
        raise InputError("not an existing folder", source=str(folder))
    paths = []
    for name in FIGURE_NAMES:
        if name in pngs:
            path = folder / f"{name}.png"
            write_bytes_atomic(path, pngs[name])
            paths.append(path)
    return paths
