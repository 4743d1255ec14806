"""A self-contained HTML report of an identification, with matplotlib figures.

:func:`render_report` returns one HTML document: inline CSS, figures embedded
as base64 PNG, no scripts, fonts or any other external resource, so it opens
anywhere without a network. :func:`save_pngs` writes the same figures as PNG
files. matplotlib is imported inside the functions that draw (an optional
dependency), and figures are drawn on the Agg canvas without touching
pyplot's global state.

Figures
-------
``layout``
    The sensors (arrows along their measuring directions), the CG, the
    principal axes of inertia (arrows from the CG, half the largest
    sensor-to-CG distance long) and the mounts when given: a 3D view and the
    top (x-y), front (x-z) and side (y-z) projections, equal scales.
``modes``
    The six rigid-body modes of the identified model, a 2 x 3 grid of 3D
    views: the sensor points and the CG at rest (grey) and displaced by the
    mode (coloured), joined by the sensor outline (:func:`sensor_outline`)
    and spokes to the CG.
``decoupling``
    Heat maps of the modal kinetic-energy distribution
    (:mod:`rigidid.core.energy`) in the test axes and in the principal axes.
``stabilisation``
    Only when a stabilisation diagram is given.
"""

from __future__ import annotations

import base64
import html
import io
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from rigidid.core.identify import Identification
    from rigidid.core.timedomain.stabilisation import OrderPoles

__all__ = ["FIGURE_NAMES", "render_report", "save_pngs"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

FIGURE_NAMES: tuple[str, ...] = ("layout", "modes", "decoupling", "stabilisation")
"""Names (and PNG file stems) of the figures, in report order."""

_DPI = 110
_SENSOR_COLOUR = "#1f5fa8"
_CG_COLOUR = "#c0392b"
_AXIS_COLOURS = ("#2e8b57", "#d68910", "#7d3c98")
_MOUNT_COLOUR = "#333333"
_MODE_COLOUR = "#c0392b"

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


def _num(v: float | None, digits: int = 5) -> str:
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
    return "0" if abs(v) < 1e-12 else _num(v, 3)


def _esc(text: object) -> str:
    return html.escape(str(text), quote=True)


# --------------------------------------------------------------------------- figures


def _new_figure(width: float, height: float) -> Figure:
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:  # pragma: no cover - depends on the environment
        raise RigididError("the report needs the optional package matplotlib (pip install matplotlib)") from None
    fig = Figure(figsize=(width, height), dpi=_DPI, layout="constrained")
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


def _layout_figure(
    ident: Identification,
    positions: Array,
    directions: Array,
    sensor_ids: Sequence[str],
    length: str,
    mass: str,
    mounts: Array,
) -> Figure:
    """3D view above a third-angle drawing: top view over front view, side view right of it."""
    g = ident.center_of_gravity
    axes = ident.principal_axes
    has_mass = ident.principal_moments is not None
    moments = ident.principal_moments if ident.principal_moments is not None else ident.principal_moments_per_mass
    moment_unit = f"{mass}·{length}²" if has_mass else f"{length}² (per unit mass)"
    size = _scene_size(positions, g[None, :], mounts)
    arrow = 0.12 * size
    axis_len = 0.5 * float(np.max(np.linalg.norm(positions - g, axis=1))) or 0.2 * size
    outline = sensor_outline(positions)
    tips = g[None, :] + axis_len * axes.T
    everything = np.vstack([positions, positions + arrow * directions, g[None, :], tips, mounts.reshape(-1, 3)])
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    centre = 0.5 * (lo + hi)
    half = 0.5 * np.maximum(hi - lo, 0.25 * float(np.max(hi - lo))) + 0.08 * float(np.max(hi - lo))

    fig = _new_figure(12.0, 13.0)
    grid = fig.add_gridspec(
        3, 2, width_ratios=[half[0], half[1]], height_ratios=[1.15 * (half[0] + half[1]) / 2.0, half[1], half[2]]
    )
    ax3 = fig.add_subplot(grid[0, :], projection="3d")
    top = fig.add_subplot(grid[1, 0])
    front = fig.add_subplot(grid[2, 0], sharex=top)
    side = fig.add_subplot(grid[2, 1], sharey=front)
    notes = fig.add_subplot(grid[1, 1])
    views = [(top, (0, 1), "top view (x-y)"), (front, (0, 2), "front view (x-z)"), (side, (1, 2), "side view (y-z)")]
    names = "xyz"

    # 3D view
    ring = positions[outline]
    ax3.plot(ring[:, 0], ring[:, 1], ring[:, 2], color="#9aa7b5", lw=1.0)
    ax3.scatter(*positions.T, color=_SENSOR_COLOUR, s=28, depthshade=False)
    ax3.quiver(*positions.T, *(arrow * directions).T, color=_SENSOR_COLOUR, lw=1.6, arrow_length_ratio=0.3)
    for sid, p in zip(sensor_ids, positions, strict=True):
        ax3.text(*(p + 0.025 * size), sid, fontsize=10, color=_SENSOR_COLOUR)
    ax3.scatter(*g, color=_CG_COLOUR, s=120, marker="*", depthshade=False, zorder=5)
    ax3.text(*(g - np.array([0.0, 0.0, 0.06 * size])), "CG", fontsize=10, color=_CG_COLOUR, fontweight="bold")
    for k in range(3):
        ax3.quiver(*g, *(axis_len * axes[:, k]), color=_AXIS_COLOURS[k], lw=2.2, arrow_length_ratio=0.15)
        ax3.text(*tips[k], f" {k + 1}", fontsize=11, color=_AXIS_COLOURS[k], fontweight="bold")
    if mounts.size:
        ax3.scatter(*mounts.T, color=_MOUNT_COLOUR, marker="^", s=60, depthshade=False)
    _equal_3d(ax3, everything, zoom=1.2)
    ax3.set_xlabel(f"x [{length}]")
    ax3.set_ylabel(f"y [{length}]")
    ax3.set_zlabel(f"z [{length}]")
    ax3.view_init(elev=18, azim=-60)

    # projections, all at one scale
    for ax, (a, b), label in views:
        ax.plot(ring[:, a], ring[:, b], color="#9aa7b5", lw=1.0, zorder=1)
        ax.scatter(positions[:, a], positions[:, b], color=_SENSOR_COLOUR, s=24, zorder=3)
        towards = np.cross(np.eye(3)[a], np.eye(3)[b])  # the axis pointing at the viewer
        for sid, p, d in zip(sensor_ids, positions, directions, strict=True):
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
            ax.annotate(sid, (p[a], p[b]), xytext=(5, 5), textcoords="offset points", fontsize=10, color=_SENSOR_COLOUR)
        for k in range(3):
            if np.hypot(axes[a, k], axes[b, k]) > 0.05:
                ax.annotate(
                    "",
                    xy=(tips[k, a], tips[k, b]),
                    xytext=(g[a], g[b]),
                    arrowprops={"arrowstyle": "-|>", "color": _AXIS_COLOURS[k], "lw": 2.0},
                    zorder=4,
                )
                ax.annotate(
                    str(k + 1),
                    (tips[k, a], tips[k, b]),
                    xytext=(3, 3),
                    textcoords="offset points",
                    fontsize=11,
                    color=_AXIS_COLOURS[k],
                    fontweight="bold",
                )
        ax.scatter([g[a]], [g[b]], color=_CG_COLOUR, marker="*", s=180, zorder=5)
        ax.annotate(
            "CG",
            (g[a], g[b]),
            xytext=(7, -14),
            textcoords="offset points",
            fontsize=10,
            color=_CG_COLOUR,
            fontweight="bold",
        )
        if mounts.size:
            ax.scatter(mounts[:, a], mounts[:, b], color=_MOUNT_COLOUR, marker="^", s=60, zorder=2)
        ax.set_xlim(centre[a] - half[a], centre[a] + half[a])
        ax.set_ylim(centre[b] - half[b], centre[b] + half[b])
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(f"{names[a]} [{length}]")
        ax.set_ylabel(f"{names[b]} [{length}]")
        ax.grid(True, color="#e3e7ec", lw=0.8)
        ax.set_title(label, fontsize=11)

    # key and numbers
    notes.axis("off")
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color=_SENSOR_COLOUR, marker="o", lw=1.4, label="sensor → measuring direction"),
        Line2D(
            [],
            [],
            color=_SENSOR_COLOUR,
            marker="o",
            mfc="none",
            ms=10,
            lw=0,
            label="⊙ / ⊗ direction towards / away from viewer",
        ),
        Line2D([], [], color=_CG_COLOUR, marker="*", ms=13, lw=0, label="centre of gravity (CG)"),
        *(Line2D([], [], color=_AXIS_COLOURS[k], lw=2.2, label=f"principal axis {k + 1}") for k in range(3)),
    ]
    if mounts.size:
        handles.append(Line2D([], [], color=_MOUNT_COLOUR, marker="^", ms=8, lw=0, label="mount"))
    notes.legend(handles=handles, loc="upper left", fontsize=10, frameon=False)
    text = (
        f"CG = ({', '.join(_num(float(v), 4) for v in g)}) {length}\n"
        f"principal moments [{moment_unit}]:\n  "
        + ", ".join(f"{k + 1}: {_num(float(m), 4)}" for k, m in enumerate(moments))
    )
    notes.text(0.0, 0.02, text, transform=notes.transAxes, fontsize=10, va="bottom", family="DejaVu Sans")
    fig.suptitle("Sensors, centre of gravity and principal axes of inertia", fontsize=12)
    return fig


def _mode_title(k: int, pole: complex, fractions: Array) -> str:
    f = abs(pole) / (2.0 * math.pi)
    z = -pole.real / abs(pole)
    top = np.argsort(-fractions)[:2]
    parts = ", ".join(f"{DOF_LABELS[i]} {100 * fractions[i]:.0f} %" for i in top if fractions[i] >= 0.05)
    return f"Mode {k + 1}: {f:#.4g} Hz, ζ {100 * z:.2g} %\n{parts}"


def _modes_figure(ident: Identification, positions: Array, length: str) -> Figure:
    poles, shapes = ident.model_modes()
    g = ident.center_of_gravity
    table = kinetic_energy_distribution(ident.inertia_per_mass, shapes)
    outline = sensor_outline(positions)
    size = _scene_size(positions, g[None, :])
    fig = _new_figure(13.0, 7.4)
    points = np.vstack([positions, g[None, :]])
    for k in range(poles.shape[0]):
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
        for p, q in zip(points, moved, strict=True):  # the path of every point
            ax.plot([p[0], q[0]], [p[1], q[1]], [p[2], q[2]], color=_MODE_COLOUR, lw=0.7, ls=":")
        _equal_3d(ax, np.vstack([points, moved]), zoom=1.1)
        ax.set_title(_mode_title(k, complex(poles[k]), table[k]), fontsize=10)
        ax.set_xlabel(f"x [{length}]", fontsize=8, labelpad=-2)
        ax.set_ylabel(f"y [{length}]", fontsize=8, labelpad=-2)
        ax.set_zlabel(f"z [{length}]", fontsize=8, labelpad=-2)
        ax.tick_params(labelsize=7, pad=0)
        ax.view_init(elev=22, azim=-60)
    fig.suptitle(
        "Rigid-body modes of the identified model: sensor outline at rest (grey, dashed) and displaced (red), "
        "dotted: path of each sensor; ★ = CG",
        fontsize=11,
    )
    return fig


def _decoupling_tables(ident: Identification) -> tuple[CArray, Array, Array]:
    poles, shapes = ident.model_modes()
    return (
        poles,
        kinetic_energy_distribution(ident.inertia_per_mass, shapes),
        kinetic_energy_distribution_principal(ident.inertia_per_mass, shapes),
    )


def _decoupling_figure(ident: Identification) -> Figure:
    poles, plain, principal = _decoupling_tables(ident)
    rows = [f"{k + 1}: {abs(p) / (2 * math.pi):#.4g} Hz" for k, p in enumerate(poles)]
    fig = _new_figure(11.0, 4.4)
    panels = (
        (plain, DOF_LABELS, "test axes"),
        (principal, ("x", "y", "z", "r1", "r2", "r3"), "rotations about the principal axes"),
    )
    image = None
    for i, (table, columns, label) in enumerate(panels):
        ax = fig.add_subplot(1, 2, i + 1)
        image = ax.imshow(np.clip(table, 0.0, 1.0), cmap="Blues", vmin=0.0, vmax=1.0, aspect="auto")
        for r in range(table.shape[0]):
            for c in range(table.shape[1]):
                v = 100.0 * table[r, c]
                ax.text(
                    c,
                    r,
                    f"{v:.0f}",
                    ha="center",
                    va="center",
                    fontsize=10,
                    color="white" if table[r, c] > 0.55 else "#1a1a1a",
                )
        ax.set_xticks(range(6), columns, fontsize=10)
        ax.set_yticks(range(len(rows)), rows if i == 0 else [""] * len(rows), fontsize=10)
        ax.set_title(f"Kinetic energy per DOF [%], {label}", fontsize=11)
        ax.tick_params(length=0)
    if image is not None:
        fig.colorbar(image, ax=fig.axes, shrink=0.9, label="fraction of the mode's kinetic energy")
    return fig


def _check_stabilisation(stabilisation: Stabilisation) -> list[tuple[int, Array, NDArray[np.bool_]]]:
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


def _stabilisation_figure(ident: Identification, entries: list[tuple[int, Array, NDArray[np.bool_]]]) -> Figure:
    fig = _new_figure(11.0, 5.0)
    ax = fig.add_subplot(1, 1, 1)
    for f in ident.frequency_hz:
        ax.axvline(float(f), color=_CG_COLOUR, lw=0.9, alpha=0.6, zorder=1)
    first = [True, True]
    for order, f, s in entries:
        if np.any(~s):
            ax.scatter(
                f[~s],
                np.full(int(np.sum(~s)), order),
                marker="x",
                s=14,
                color="#9aa7b5",
                label="not stable" if first[0] else None,
                zorder=2,
            )
            first[0] = False
        if np.any(s):
            ax.scatter(
                f[s],
                np.full(int(np.sum(s)), order),
                marker="o",
                s=22,
                color=_SENSOR_COLOUR,
                label="stable" if first[1] else None,
                zorder=3,
            )
            first[1] = False
    ax.plot([], [], color=_CG_COLOUR, lw=0.9, label="modes used")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    ax.grid(True, color="#e3e7ec", lw=0.8)
    ax.legend(loc="upper right", fontsize=9)
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
) -> dict[str, Figure]:
    length, mass = _units(units)
    pos, dirs, ids, m = _as_arrays(positions, directions, sensor_ids, mounts)
    entries = None if stabilisation is None else _check_stabilisation(stabilisation)  # check before drawing
    figures = {
        "layout": _layout_figure(ident, pos, dirs, ids, length, mass, m),
        "modes": _modes_figure(ident, pos, length),
        "decoupling": _decoupling_figure(ident),
    }
    if entries is not None:
        figures["stabilisation"] = _stabilisation_figure(ident, entries)
    return figures


def _png(fig: Figure) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=_DPI, metadata={"Software": None})  # no URL in the file
    return buffer.getvalue()


# --------------------------------------------------------------------------- HTML

_CSS = """
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
caption { caption-side: bottom; text-align: left; color: #4a5663; font-size: 13px; padding-top: 4px; }
figure { margin: 10px 0 20px; }
figure img { max-width: 100%; height: auto; border: 1px solid #e3e7ec; }
figcaption { color: #4a5663; font-size: 13px; margin-top: 4px; }
.warn { background: #fff4e0; border-left: 4px solid #d68910; padding: 6px 12px; margin: 6px 0; }
.flex { display: flex; flex-wrap: wrap; gap: 28px; align-items: flex-start; }
details summary { cursor: pointer; color: #1f5fa8; }
"""


def _table(
    header: Sequence[str], rows: Sequence[Sequence[str]], *, caption: str | None = None, label_cols: int = 1
) -> str:
    head = "".join(
        f'<th class="label">{_esc(h)}</th>' if i < label_cols else f"<th>{_esc(h)}</th>" for i, h in enumerate(header)
    )
    body = "".join(
        "<tr>"
        + "".join(f'<td class="label">{c}</td>' if i < label_cols else f"<td>{c}</td>" for i, c in enumerate(row))
        + "</tr>"
        for row in rows
    )
    cap = f"<caption>{_esc(caption)}</caption>" if caption else ""
    return f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _matrix_html(a: Array, labels: Sequence[str], caption: str | None = None) -> str:
    rows = [[_esc(labels[i]), *(_num(float(v)) for v in a[i])] for i in range(a.shape[0])]
    return _table(["", *labels], rows, caption=caption)


def _figure_html(png: bytes, alt: str, caption: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return (
        f'<figure><img src="data:image/png;base64,{data}" alt="{_esc(alt)}">'
        f"<figcaption>{_esc(caption)}</figcaption></figure>"
    )


def _uncertainty_html(uncertainty: Mapping[str, Any], length: str, mass: str) -> str:
    unit_of = {
        "center_of_gravity": length,
        "inertia_tensor": f"{mass}·{length}²",
        "inertia_per_mass": f"{length}²",
        "principal_moments": f"{mass}·{length}²",
        "principal_moments_per_mass": f"{length}²",
    }
    rows: list[list[str]] = []
    for name, entry in uncertainty.items():
        if not isinstance(entry, Mapping) or "estimate" not in entry:
            continue
        est = np.asarray(_float_array(entry.get("estimate")), dtype=float)
        std = np.asarray(_float_array(entry.get("std")), dtype=float)
        ci = np.asarray(_float_array(entry.get("ci95")), dtype=float)
        if std.shape != est.shape or ci.shape != (*est.shape, 2):
            raise InputError(
                "estimate, std and ci95 (pairs) do not match in shape", source="uncertainty", location=str(name)
            )
        labels = _component_labels(str(name), est.shape)
        unit = unit_of.get(str(name), "")
        if str(name).startswith(("stiffness_diagonal", "damping_diagonal")):
            per_mass = str(name).endswith("_per_mass")
            blocks = _block_units(length, None if per_mass else mass, 2 if str(name).startswith("stiff") else 1)
        first = True
        for index, label in zip(np.ndindex(est.shape), labels, strict=True):
            if est.shape == (3, 3) and index[0] > index[1]:
                continue  # symmetric tensor: the upper triangle says it all
            if str(name).startswith(("stiffness_diagonal", "damping_diagonal")):
                unit = blocks[0] if index[0] < 3 else blocks[2]
            rows.append(
                [
                    _esc(str(name).replace("_", " ")) if first else "",
                    _esc(label),
                    _esc(unit),
                    _num(float(est[index])),
                    _num(float(std[index]), 3),
                    f"{_num(float(ci[index][0]))} … {_num(float(ci[index][1]))}",
                ]
            )
            first = False
    extra = []
    for key in ("method", "segments", "used", "draws", "failed", "implausible", "seed"):
        if key in uncertainty and not isinstance(uncertainty[key], Mapping):
            extra.append(f"{key}: {uncertainty[key]}")
    noise = uncertainty.get("noise")
    if isinstance(noise, Mapping):
        extra.append("noise: " + ", ".join(f"{k} {v}" for k, v in noise.items()))
    caption = "; ".join(extra) if extra else None
    return _table(
        ["quantity", "component", "unit", "estimate", "std", "95 % interval"], rows, caption=caption, label_cols=3
    )


def _float_array(value: Any) -> Any:
    if isinstance(value, list | tuple):
        return [_float_array(v) for v in value]
    return math.nan if value is None else value


def _component_labels(name: str, shape: tuple[int, ...]) -> list[str]:
    if shape == (3,) and name.startswith("center"):
        return ["x", "y", "z"]
    if shape == (3,):
        return ["1", "2", "3"]
    if shape == (6,):
        return list(DOF_LABELS)
    if shape == (3, 3):
        return [f"{a}{b}" for a in "xyz" for b in "xyz"]
    if shape == ():
        return [""]
    return [str(list(i)) for i in np.ndindex(shape)]


def render_report(
    identification: Identification,
    positions: ArrayLike,
    directions: ArrayLike,
    sensor_ids: Sequence[str],
    units: Mapping[str, str],
    *,
    mounts: Sequence[ArrayLike] | None = None,
    stabilisation: Stabilisation | None = None,
    uncertainty: Mapping[str, Any] | None = None,
    title: str = "rigidid report",
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
    uncertainty : mapping, optional
        ``{quantity: {"estimate": [...], "std": [...], "ci95": [[low,
        high], ...]}}`` (the form of
        :func:`rigidid.jsonout.uncertainty_to_dict`: arrays of any
        shape, ``ci95`` with a last axis of 2, None for NaN); other keys
        (``draws``, ``failed``, ``noise`` ...) are shown as a caption.
    title : str
        Heading and ``<title>`` of the document.

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
    pos, dirs, ids, _ = _as_arrays(positions, directions, sensor_ids, mounts)
    uncertainty_table = None if uncertainty is None else _uncertainty_html(uncertainty, length, mass_unit)
    figures = _figures(identification, pos, dirs, ids, units, mounts, stabilisation)
    pngs = {name: _png(fig) for name, fig in figures.items()}
    ident = identification
    diag = ident.diagnostics
    has_mass = ident.mass is not None
    mass_text = f"{_num(ident.mass)} {mass_unit}" if has_mass else "not given (results per unit mass)"
    g = ident.center_of_gravity
    parts: list[str] = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_esc(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_esc(title)}</h1>",
        f'<p class="meta">rigidid {_esc(__version__)} · method {_esc(ident.method)} · units: length {_esc(length)}, '
        f"mass {_esc(mass_unit)}, time s · mass {_esc(mass_text)} · {len(ids)} sensors</p>",
    ]
    for message in diag.warnings:
        parts.append(f'<div class="warn">⚠ {_esc(message)}</div>')

    # mass properties
    parts.append("<h2>Centre of gravity and inertia</h2>")
    parts.append('<div class="flex"><div><h3>Centre of gravity</h3>')
    parts.append(
        _table(
            ["", f"[{length}]"],
            [[a, _num(float(v))] for a, v in zip("xyz", g, strict=True)],
            caption="in the layout's axes",
        )
    )
    inertia = ident.inertia_tensor if has_mass else ident.inertia_per_mass
    inertia_unit = f"{mass_unit}·{length}²" if has_mass else f"{length}² (per unit mass)"
    parts.append("</div><div><h3>Inertia tensor about the CG</h3>")
    assert inertia is not None
    parts.append(
        _matrix_html(
            inertia,
            ["x", "y", "z"],
            caption=f"[{inertia_unit}]; off-diagonal entries are tensor entries (minus the products of inertia)",
        )
    )
    moments = ident.principal_moments if has_mass else ident.principal_moments_per_mass
    assert moments is not None
    axes = ident.principal_axes
    parts.append("</div><div><h3>Principal moments and axes</h3>")
    parts.append(
        _table(
            ["axis", f"moment [{inertia_unit}]", "x", "y", "z"],
            [[str(k + 1), _num(float(moments[k])), *(_num(float(v), 4) for v in axes[:, k])] for k in range(3)],
            caption="ascending moments; unit axis vectors in the layout's axes",
        )
    )
    parts.append("</div></div>")

    # modes
    parts.append("<h2>Modes</h2>")
    mode_rows = [
        [
            str(k + 1),
            _num(float(ident.frequency_hz[k])),
            _num(100 * float(ident.damping_ratio[k]), 4),
            _num(float(diag.model_frequency_hz[k])),
            _num(100 * float(diag.model_damping_ratio[k]), 4),
            f"{float(diag.model_mac[k]):.4f}",
            _residual(float(diag.rigid_fit_residual[k])),
        ]
        for k in range(ident.frequency_hz.shape[0])
    ]
    parts.append(
        _table(
            ["mode", "measured f [Hz]", "measured ζ [%]", "model f [Hz]", "model ζ [%]", "MAC", "rigid-fit residual"],
            mode_rows,
            caption="measured modes used, in order, and the matching modes of the identified model",
        )
    )

    # stiffness and damping
    for name, per_mass, absolute, power in (
        ("Stiffness", ident.stiffness_per_mass, ident.stiffness_matrix, 2),
        ("Damping", ident.damping_per_mass, ident.damping_matrix, 1),
    ):
        matrix = absolute if absolute is not None else per_mass
        blocks = _block_units(length, mass_unit if has_mass else None, power)
        scope = "" if has_mass else " per unit mass"
        parts.append(f"<h2>{name} matrix at the CG{_esc(scope)}</h2>")
        parts.append(
            _matrix_html(
                matrix,
                DOF_LABELS,
                caption=f"units: x-z block [{blocks[0]}], coupling blocks [{blocks[1]}], rx-rz block [{blocks[2]}]",
            )
        )

    # decoupling
    poles, plain, principal = _decoupling_tables(ident)
    parts.append("<h2>Decoupling: kinetic energy distribution</h2>")
    parts.append(
        _figure_html(
            pngs["decoupling"],
            "kinetic energy distribution heat map",
            "Share of each model mode's kinetic energy in each DOF at the CG (cycle-averaged for complex modes); "
            "rows sum to 100 %. Left: test axes (entries can be negative with products of inertia; shown as 0 in "
            "colour). Right: rotations about the principal axes 1, 2, 3.",
        )
    )
    labels = [f"{k + 1} ({abs(p) / (2 * math.pi):#.4g} Hz)" for k, p in enumerate(poles)]
    numbers = [
        [_esc(labels[k]), *(f"{100 * v:.1f}" for v in plain[k]), *(f"{100 * v:.1f}" for v in principal[k])]
        for k in range(len(labels))
    ]
    parts.append("<details><summary>the numbers [%]</summary>")
    parts.append(
        _table(
            ["mode", *DOF_LABELS, *(f"{c}\u2032" for c in PRINCIPAL_DOF_LABELS)],
            numbers,
            caption="primed columns: rotations about the principal axes",
        )
    )
    parts.append("</details>")

    # figures
    parts.append("<h2>Layout</h2>")
    parts.append(
        _figure_html(
            pngs["layout"],
            "sensor layout with CG and principal axes",
            f"Sensors (blue, arrows along the measuring directions; in the projections ⊙ points towards, ⊗ away "
            f"from the viewer), CG (red star) and principal axes 1, 2, 3 from the CG; lengths in {length}."
            + (" Mounts: black triangles." if mounts else ""),
        )
    )
    parts.append(
        _table(
            ["sensor", f"x [{length}]", f"y [{length}]", f"z [{length}]", "direction"],
            [
                [_esc(sid), *(_num(float(v)) for v in p), _esc(_direction_text(d))]
                for sid, p, d in zip(ids, pos, dirs, strict=True)
            ],
        )
    )
    parts.append("<h2>Mode shapes</h2>")
    parts.append(
        _figure_html(
            pngs["modes"],
            "rigid-body mode shapes",
            "Each model mode displaces the sensor points and the CG; the largest sensor displacement is drawn as a "
            "quarter of the layout size. Complex modes are shown at the phase of their largest motion.",
        )
    )
    if "stabilisation" in pngs:
        parts.append("<h2>Stabilisation diagram</h2>")
        parts.append(
            _figure_html(
                pngs["stabilisation"],
                "stabilisation diagram",
                "Poles per model order; vertical lines: the measured modes used.",
            )
        )
    if uncertainty_table is not None:
        parts.append("<h2>Uncertainty</h2>")
        parts.append(uncertainty_table)

    # diagnostics
    parts.append("<h2>Diagnostics</h2>")
    parts.append(
        _table(
            ["quantity", "value"],
            [
                ["layout condition number", _num(diag.layout_condition, 4)],
                ["layout rank", str(diag.layout_rank)],
                ["structure residual |DQ - (DQ)ᵀ| / |DQ|", _residual(diag.structure_residual)],
                ["largest rigid-fit residual", _residual(float(np.max(diag.rigid_fit_residual)))],
                ["smallest model MAC", f"{float(np.min(diag.model_mac)):.4f}"],
                ["warnings", f"{len(diag.warnings)} (listed at the top)" if diag.warnings else "none"],
            ],
        )
    )
    parts.append("</body></html>")
    return "\n".join(parts)


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
) -> list[Path]:
    """Write the report's figures as PNG files.

    Parameters
    ----------
    directory : path-like
        An existing folder.
    identification, positions, directions, sensor_ids, units, mounts, stabilisation
        As :func:`render_report`.

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
    figures = _figures(identification, positions, directions, sensor_ids, units, mounts, stabilisation)
    paths = []
    for name in FIGURE_NAMES:
        if name in figures:
            path = folder / f"{name}.png"
            write_bytes_atomic(path, _png(figures[name]))
            paths.append(path)
    return paths
