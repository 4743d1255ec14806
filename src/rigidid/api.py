"""The Python API: what the command line does, as functions a notebook can call.

>>> import rigidid
>>> layout = rigidid.load_layout("samples/paper-1994/layout.json")  # doctest: +SKIP
>>> modes = rigidid.load_modes("samples/paper-1994/modes.csv", layout)  # doctest: +SKIP
>>> result = rigidid.identify(layout, modes)  # doctest: +SKIP
>>> result.identification.center_of_gravity  # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from rigidid import files
from rigidid.core.identify import Identification, Method
from rigidid.core.identify import identify as identify_core
from rigidid.core.selection import rigid_fit_residuals
from rigidid.core.simulate import Body, Mount, add_noise, body_modes
from rigidid.core.statespace import modal_from_poles, poles_from_modal
from rigidid.errors import InputError
from rigidid.files import ModeTable
from rigidid.models import BodyFile, LayoutFile

__all__ = ["IdentifyResult", "body_from_file", "identify", "load_layout", "load_modes", "simulate"]

PathLike = str | os.PathLike[str]
Selection = Literal["all", "given", "automatic"]


@dataclass(frozen=True)
class IdentifyResult:
    """An identification with the context needed to report it.

    Attributes
    ----------
    identification : Identification
        The numbers (CG, inertia, stiffness, damping, diagnostics).
    units : dict
        ``{"length": ..., "mass": ...}`` of the layout.
    sensor_ids : tuple of str
    positions, directions : ndarray, shape (p, 3)
        The layout (directions as unit vectors).
    modes_used : tuple of int
        Mode labels used, in the order of the identification's modes.
    selection : {"all", "given", "automatic"}
        How the six modes were chosen.
    candidate_residuals : dict or None
        Rigid-body fit residual of every mode given, when chosen automatically.
    """

    identification: Identification
    units: dict[str, str]
    sensor_ids: tuple[str, ...]
    positions: NDArray[np.float64]
    directions: NDArray[np.float64]
    modes_used: tuple[int, ...]
    selection: Selection
    candidate_residuals: dict[int, float] | None = None


def load_layout(path: PathLike) -> LayoutFile:
    """Read and validate ``layout.json`` (see :func:`rigidid.files.load_layout`)."""
    return files.load_layout(path)


def load_modes(path: PathLike, layout: LayoutFile) -> ModeTable:
    """Read and validate ``modes.csv`` against a layout (see :func:`rigidid.files.load_modes`)."""
    return files.load_modes(path, [s.id for s in layout.sensors])


def _choose_modes(
    modes: ModeTable, transformation: NDArray[np.float64], wanted: Sequence[int] | None, source: str | None
) -> tuple[tuple[int, ...], Selection, dict[int, float] | None]:
    if wanted is not None:
        labels = tuple(int(m) for m in wanted)
        unknown = [m for m in labels if m not in modes.labels]
        if unknown:
            raise InputError(
                f"mode {unknown[0]} is not in the modes file (it has {list(modes.labels)})", source="--modes"
            )
        if len(labels) != 6 or len(set(labels)) != 6:
            raise InputError(f"give six different mode labels, got {list(labels)}", source="--modes")
        return labels, "given", None
    n = len(modes.labels)
    if n < 6:
        raise InputError(f"{n} modes given; the six rigid-body modes are needed", source=source)
    if n == 6:
        return modes.labels, "all", None
    if transformation.shape[0] <= 6:
        raise InputError(
            f"{n} modes given and only {transformation.shape[0]} sensors: with six sensors every shape fits "
            "rigid-body motion, so the rigid modes cannot be chosen; pass --modes",
            source=source,
        )
    residual = rigid_fit_residuals(transformation, modes.shapes)
    order = np.sort(np.argsort(residual, kind="stable")[:6])
    chosen = tuple(modes.labels[i] for i in order)
    return chosen, "automatic", {label: float(r) for label, r in zip(modes.labels, residual, strict=True)}


def identify(
    layout: LayoutFile | PathLike,
    modes: ModeTable | PathLike,
    *,
    mass: float | None = None,
    modes_used: Sequence[int] | None = None,
    method: Method = "structured",
) -> IdentifyResult:
    """Identify CG, inertia, stiffness and damping from a layout and its modes.

    Parameters
    ----------
    layout : LayoutFile or path-like
        The sensors (and optionally the mass).
    modes : ModeTable or path-like
        Modal parameters; with more than six modes the six rigid-body modes
        are chosen (see `modes_used`).
    mass : float, optional
        Mass of the body; overrides the layout's ``mass``.
    modes_used : sequence of int, optional
        The six mode labels to use. Without it exactly six modes are used as
        given, or, with more than six modes and more than six sensors, the six
        whose shapes fit rigid-body motion best.
    method : {"structured", "paper"}
        See :func:`rigidid.core.identify.identify`.

    Returns
    -------
    IdentifyResult

    Raises
    ------
    InputError
        Bad files or arguments.
    IdentificationError
        Data that determine no rigid body.
    """
    from rigidid.core.geometry import layout_frame, sensor_matrix

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    source = None if isinstance(modes, ModeTable) else str(modes)
    table = modes if isinstance(modes, ModeTable) else load_modes(modes, lay)
    ids, positions, directions = files.layout_arrays(lay)
    if table.sensor_ids != ids:
        raise InputError("the modes' sensors do not match the layout's sensors", source=source)
    frame = layout_frame(positions)
    t = sensor_matrix(frame.to_local(positions), directions)
    labels, selection, residuals = _choose_modes(table, t, modes_used, source)
    used = table.subset(labels)
    result = identify_core(
        positions,
        directions,
        poles_from_modal(used.frequency_hz, used.damping_ratio),
        used.shapes,
        mass=mass if mass is not None else lay.mass,
        method=method,
    )
    return IdentifyResult(
        identification=result,
        units={"length": lay.units.length, "mass": lay.units.mass},
        sensor_ids=ids,
        positions=positions,
        directions=directions,
        modes_used=labels,
        selection=selection,
        candidate_residuals=residuals,
    )


def body_from_file(body: BodyFile) -> Body:
    """The core :class:`~rigidid.core.simulate.Body` of a validated ``body.json``."""
    return Body(
        mass=body.mass,
        center_of_gravity=np.array(body.center_of_gravity, dtype=float),
        inertia_tensor=np.array(body.inertia_tensor, dtype=float),
        mounts=tuple(Mount.from_values(m.position, m.stiffness, m.damping) for m in body.mounts),
    )


def simulate(
    body: BodyFile | PathLike,
    layout: LayoutFile | PathLike,
    *,
    frequency_noise: float = 0.0,
    damping_noise: float = 0.0,
    shape_noise: float = 0.0,
    seed: int | None = None,
) -> ModeTable:
    """The six rigid-body modes of a body on its mounts, as the layout's sensors read them.

    Parameters
    ----------
    body : BodyFile or path-like
        Mass, CG, inertia tensor and mounts (``body.json``).
    layout : LayoutFile or path-like
        The sensors.
    frequency_noise, damping_noise : float
        Relative standard deviation of Gaussian noise on each natural
        frequency and damping ratio (0.001 = 0.1 %).
    shape_noise : float
        Complex Gaussian noise on the shape values, relative to each mode's
        RMS value.
    seed : int, optional
        Seed of the noise.

    Returns
    -------
    ModeTable
        Modes labelled 1-6 in ascending frequency, shapes scaled to a largest
        value of 1.

    Raises
    ------
    InputError
        Bad files, or units of the body and layout that differ.
    """
    lay = layout if isinstance(layout, LayoutFile) else files.load_layout(layout, require_rank=False)
    spec = body if isinstance(body, BodyFile) else files.load_body(body)
    if spec.units != lay.units:
        raise InputError(
            f"body units ({spec.units.length}, {spec.units.mass}) differ from layout units "
            f"({lay.units.length}, {lay.units.mass})",
            source=None if isinstance(body, BodyFile) else str(body),
            location="units",
        )
    ids, positions, directions = files.layout_arrays(lay)
    modes = body_modes(body_from_file(spec), positions, directions)
    if frequency_noise or damping_noise or shape_noise:
        modes = add_noise(modes, frequency=frequency_noise, damping=damping_noise, shape=shape_noise, seed=seed)
    f, z = modal_from_poles(modes.poles)
    return ModeTable(tuple(range(1, 7)), f, z, ids, modes.shapes)
