"""Is a sensor layout good enough? One small function per check, each returning findings.

Before an impact test: can this layout see all six rigid-body motions at all
(the paper's step (3): a transformation ``T_mo`` of rank 6, eq. (3) of [1]),
how well, and what to change. :func:`check_layout` runs every check;
:mod:`rigidid.core.plan` predicts figures and suggests sensors.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import LayoutFrame, layout_condition, layout_frame, normalise_directions, sensor_matrix
from rigidid.errors import InputError

__all__ = ["AXIS_COS", "Finding", "LayoutReport", "check_layout"]

Array = NDArray[np.float64]
Severity = Literal["error", "warning", "info"]
_SEVERITY_ORDER: dict[str, int] = {"error": 0, "warning": 1, "info": 2}

AXIS_COS = math.cos(math.radians(30.0))
"""A sensor counts for axis x, y or z when its direction is within 30 degrees of it."""

_COND_GOOD = 10.0
_COND_POOR = 100.0
_PARALLEL_COS = math.cos(math.radians(10.0))
_EVERY_LINE_UP_TO = 60
"""Layouts of up to this many sensors are searched for every near-line group; larger ones for the groups
that can warn (a harmless line of four among hundreds of sensors is not worth a line of the report)."""


@dataclass(frozen=True)
class Finding:
    """One observation about a sensor layout.

    Attributes
    ----------
    severity : {"error", "warning", "info"}
        ``"error"``: the identification cannot work; ``"warning"``: it will
        work poorly; ``"info"``: worth knowing.
    message : str
        One or two sentences for the test engineer, with what to do.
    code : str
        Stable identifier of the kind of finding (``"too-few-sensors"``,
        ``"rank"``, ``"condition"``, ``"axis-missing"``, ``"axis-counts"``,
        ``"redundant-pair"``, ``"shared-position"``, ``"collinear"``,
        ``"minimum-sensors"``).
    sensors : tuple of int
        The sensors concerned, numbered from 1 in the layout's order (the
        message names them by their ids when :func:`check_layout` was given
        them).
    """

    severity: Severity
    message: str
    code: str
    sensors: tuple[int, ...] = ()


@dataclass(frozen=True)
class LayoutReport:
    """Result of :func:`check_layout`.

    Attributes
    ----------
    sensors : int
        Number of sensors.
    rank : int
        Rank of the dimensionless transformation ``T_mo`` (6 needed).
    condition : float
        Its condition number (``inf`` below rank 6); about 2-10 is good.
    axis_counts : tuple of int
        Sensors mostly along x, y, z (within 30 degrees) and the oblique rest.
    weakest_motion : str
        The rigid motion the layout sees least, in words.
    findings : tuple of Finding
        Sorted: errors first, then warnings, then information.
    """

    sensors: int
    rank: int
    condition: float
    axis_counts: tuple[int, int, int, int]
    weakest_motion: str
    findings: tuple[Finding, ...]

    @property
    def ok(self) -> bool:
        """True when no finding is an error."""
        return all(f.severity != "error" for f in self.findings)

    @property
    def worst(self) -> str:
        """Most severe finding: ``"error"``, ``"warning"``, ``"info"`` or ``"none"``."""
        for level in ("error", "warning", "info"):
            if any(f.severity == level for f in self.findings):
                return level
        return "none"

    @property
    def severity_key(self) -> tuple[int, int, float]:
        """Sort key, better layouts first: (errors, warnings, condition number).

        Use ``sorted(reports, key=lambda r: r.severity_key)``.
        """
        errors = sum(f.severity == "error" for f in self.findings)
        warns = sum(f.severity == "warning" for f in self.findings)
        return errors, warns, self.condition


def _fmt(x: float) -> str:
    return f"{x:.3g}"


def _vec(v: ArrayLike) -> str:
    a = np.asarray(v, dtype=float)
    return "(" + ", ".join(f"{x:.3g}" if abs(x) >= 5e-4 else "0" for x in a) + ")"


def _names(indices: ArrayLike, names: Sequence[str]) -> str:
    items = [names[int(i)] for i in np.asarray(indices).ravel()]
    if len(items) == 1:
        return f"sensor {items[0]}"
    return "sensors " + ", ".join(items[:-1]) + " and " + items[-1]


def _with_unit(x: float, unit: str) -> str:
    return f"{_fmt(x)} {unit}".rstrip() if unit else f"{_fmt(x)} (layout units)"


def _describe_motion(x: Array, centre: Array, scale: float, unit: str) -> str:
    """A rigid motion ``(t, w)`` of the dimensionless frame in words (a translation or a rotation axis)."""
    t, w = x[:3], x[3:]
    nw = float(np.linalg.norm(w))
    nt = float(np.linalg.norm(t))
    if nw < 0.2 * max(nt, 1e-300):
        return f"a translation along {_vec(t / nt)}"
    axis = w / nw
    point = np.cross(w, t) / nw**2  # closest point of the screw axis to the centroid
    if np.linalg.norm(point) > 5.0:
        return f"a translation along {_vec(t / max(nt, 1e-300))} (with a little rotation)"
    where = centre + scale * point
    return f"a rotation about the axis along {_vec(axis)} through {_vec(where)}" + (f" {unit}" if unit else "")


def _line_groups(
    local: Array, tol: float, pairs: tuple[NDArray[np.intp], NDArray[np.intp]] | None = None
) -> list[tuple[NDArray[np.intp], Array, Array, float]]:
    """Maximal groups of at least 3 points within `tol` of one line: (members, point, direction, worst distance).

    Each line through two points (`pairs`, default every pair) gathers the points within `tol`; a line
    with three or more is refitted through them (SVD) and gathers again. Equal gatherings are refitted
    once, and the subset test is one product of membership matrices.
    """
    p = local.shape[0]
    first, second = np.triu_indices(p, 1) if pairs is None else pairs
    found: list[tuple[NDArray[np.intp], Array, Array, float]] = []
    tried: set[bytes] = set()
    seen: set[bytes] = set()
    for i, j in zip(first.tolist(), second.tolist(), strict=True):
        d = local[j] - local[i]
        length = float(np.linalg.norm(d))
        if length <= 2.0 * tol:
            continue
        inside = _distances(local, local[i], d / length) <= tol
        key = np.packbits(inside).tobytes()
        if np.count_nonzero(inside) < 3 or key in tried:
            continue
        tried.add(key)
        # refit the line through the members and check again
        pts = local[inside]
        c = pts.mean(axis=0)
        u = np.linalg.svd(pts - c)[2][0]
        dist = _distances(local, c, u)
        inside = dist <= tol
        key = np.packbits(inside).tobytes()
        if np.count_nonzero(inside) < 3 or key in seen:
            continue
        seen.add(key)
        found.append((np.flatnonzero(inside), c, u, float(dist[inside].max())))
    if not found:
        return []
    # keep the maximal groups only: a group inside a larger one goes
    member = np.zeros((len(found), p), dtype=np.int64)
    for row, group in enumerate(found):
        member[row, group[0]] = 1
    size = member.sum(axis=1)
    overlap = member @ member.T
    inner = (overlap == size[:, None]) & (size[None, :] > size[:, None])
    return [g for g, lost in zip(found, inner.any(axis=1), strict=True) if not lost]


def _distances(local: Array, point: Array, unit: Array) -> Array:
    """Each point's distance from the line through `point` along the unit vector `unit`."""
    rel = local - point
    return np.asarray(np.linalg.norm(rel - np.outer(rel @ unit, unit), axis=1), dtype=float)


def _hidden_lines(
    lay: _Layout, pairs: tuple[NDArray[np.intp], NDArray[np.intp]], tol: float, floor: float
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """The pairs whose line's rotation the whole layout sees more than `floor` times worse than its best motion.

    ``|T x|^2 = x^T (T^T T) x`` for the unit rotation ``x`` about each line (eq. (3) of [1]), so every
    pair costs a 6 x 6 form, not a pass over the sensors; pairs closer than ``2 tol`` have no line.
    """
    t, local = lay.transformation, lay.local
    first, second = pairs
    d = local[second] - local[first]
    length = np.linalg.norm(d, axis=1)
    keep = length > 2.0 * tol
    first, second = first[keep], second[keep]
    u = d[keep] / length[keep, None]
    x = np.concatenate([-np.cross(u, local[first]), u], axis=1)
    seen = np.sqrt(np.maximum(np.einsum("mi,ij,mj->m", x, t.T @ t, x), 0.0) / np.einsum("mi,mi->m", x, x))
    s_max = float(np.linalg.norm(t, 2)) if t.size else 0.0
    hidden = seen * floor < s_max
    return first[hidden], second[hidden]


@dataclass(frozen=True)
class _Layout:
    """What the checks share: the layout in its dimensionless frame and the message settings."""

    directions: Array
    frame: LayoutFrame
    local: Array
    transformation: Array
    condition: float
    rank: int
    names: Sequence[str]
    unit: str

    @property
    def count(self) -> int:
        return int(self.directions.shape[0])

    def length(self, x: float) -> str:
        return _with_unit(x * self.frame.scale, self.unit)

    def motion(self, x: Array) -> str:
        return _describe_motion(x, self.frame.centre, self.frame.scale, self.unit)


def _check_count(lay: _Layout) -> list[Finding]:
    """At least six sensors; exactly six is worth a word."""
    p = lay.count
    if p < 6:
        return [
            Finding(
                "error",
                f"only {p} sensors: the six rigid-body motions need at least six (the paper's step 3); "
                f"add {6 - p} more, pointing along axes the others do not cover",
                "too-few-sensors",
            )
        ]
    if p == 6:
        return [
            Finding(
                "info",
                "six sensors, the minimum: every mode shape fits rigid motion exactly, so noise and flexible "
                "motion cannot be detected; two to six more sensors make the result checkable",
                "minimum-sensors",
            )
        ]
    return []


def _check_rank_and_condition(lay: _Layout, weakest: str) -> list[Finding]:
    """Rank 6 of ``T_mo``, else the motions no sensor sees; the condition number and the least visible motion."""
    cond, rank = lay.condition, lay.rank
    if lay.count >= 6 and rank < 6:
        vt = np.linalg.svd(lay.transformation)[2]
        blind = [lay.motion(v) for v in vt[rank:]]
        what = blind[0] if len(blind) == 1 else f"{len(blind)} independent motions, e.g. " + "; ".join(blind)
        return [
            Finding(
                "error",
                f"the layout has rank {rank}, not 6: no sensor sees {what}; "
                "add or re-point sensors so that each such motion moves at least one of them along its axis",
                "rank",
            )
        ]
    if rank < 6:
        return []
    if cond > _COND_POOR:
        text = (
            f"the layout is poorly conditioned (condition number {_fmt(cond)}; up to 10 is good): "
            f"measurement noise on {weakest} is amplified about {_fmt(cond)} times; "
            "spread the sensors out and point them along different axes"
        )
        return [Finding("warning", text, "condition")]
    if cond > _COND_GOOD:
        text = (
            f"the layout is only fairly conditioned (condition number {_fmt(cond)}; up to 10 is good): "
            f"the least visible motion is {weakest}"
        )
        return [Finding("warning", text, "condition")]
    return [Finding("info", f"the layout is well conditioned (condition number {_fmt(cond)})", "condition")]


def _axis_counts(directions: Array) -> tuple[int, int, int, int]:
    along = np.abs(directions) > AXIS_COS
    counts = along.sum(axis=0)
    return int(counts[0]), int(counts[1]), int(counts[2]), int(directions.shape[0] - along.any(axis=1).sum())


def _check_axes(lay: _Layout) -> list[Finding]:
    """At least one sensor within 30 degrees of each axis."""
    comp = np.abs(lay.directions)
    counts = _axis_counts(lay.directions)
    found = []
    for a, name in enumerate("xyz"):
        if counts[a] > 0:
            continue
        best = int(np.argmax(comp[:, a]))
        if comp[best, a] < 0.05:
            text = (
                f"no sensor has any component along {name}: translation along {name} cannot be seen; "
                f"point at least one sensor along {name}"
            )
            found.append(Finding("error", text, "axis-missing"))
        else:
            text = (
                f"no sensor measures along {name} (within 30 degrees; the closest is {_names([best], lay.names)}, "
                f"{_fmt(comp[best, a])} of its axis along {name}): translation along {name} is seen only "
                f"indirectly and less precisely; point at least one sensor along {name}"
            )
            found.append(Finding("warning", text, "axis-missing", (best + 1,)))
    x, y, z, oblique = counts
    found.append(Finding("info", f"sensors along x: {x}, y: {y}, z: {z}, oblique: {oblique}", "axis-counts"))
    return found


def _check_pairs(lay: _Layout, close_tolerance: float, same_tolerance: float) -> list[Finding]:
    """Redundant pairs (close together, parallel or anti-parallel) and shared positions (triaxial mounts)."""
    p = lay.count
    dist = _pair_distances(lay.local)
    cosang = np.abs(lay.directions @ lay.directions.T)
    found = []
    close = np.triu((dist <= close_tolerance) & (cosang >= _PARALLEL_COS), 1)
    for i, j in np.argwhere(close).tolist():
        angle = math.degrees(math.acos(min(1.0, float(cosang[i, j]))))
        text = (
            f"{_names([i, j], lay.names)} are {lay.length(dist[i, j])} apart and measure almost the same "
            f"direction ({_fmt(angle)} degrees apart): the second adds little; "
            "point one along another axis or move it elsewhere on the body"
        )
        found.append(Finding("warning", text, "redundant-pair", (i + 1, j + 1)))
    shared_done = np.zeros(p, dtype=bool)
    for i in range(p):
        if shared_done[i]:
            continue
        group = np.flatnonzero(dist[i] <= same_tolerance)
        if group.size > 1:
            shared_done[group] = True
            text = (
                f"{_names(group, lay.names)} share one position (a triaxial mount?): fine, but together they see "
                "only the motion of that one point"
            )
            found.append(Finding("info", text, "shared-position", tuple(int(g) + 1 for g in group)))
    return found


def _pair_distances(local: Array) -> Array:
    """The distance between every two points, shape (p, p), without a (p, p, 3) intermediate."""
    sq = np.einsum("ij,ij->i", local, local)
    gram = local @ local.T
    dist: Array = np.sqrt(np.maximum(sq[:, None] + sq[None, :] - 2.0 * gram, 0.0))
    return dist


def _check_collinear(lay: _Layout, line_tolerance: float, same_tolerance: float) -> list[Finding]:
    """Groups of three or more sensors almost on one line, judged by how well the rest see rotation about it."""
    p, t, local, cond = lay.count, lay.transformation, lay.local, lay.condition
    dist = _pair_distances(local)
    s_max = float(np.linalg.norm(t, 2)) if t.size else 0.0
    label = np.arange(p)
    for i, j in np.argwhere(np.triu(dist <= same_tolerance, 1)).tolist():
        label[label == label[j]] = label[i]
    pairs = np.triu_indices(p, 1)
    if p > _EVERY_LINE_UP_TO:  # only lines that can warn: about 0.5 p^2 lines of 6 x 6 forms, not p^3
        warns_above = _COND_GOOD if cond <= _COND_GOOD else min(_COND_GOOD, 0.5 * cond)
        pairs = _hidden_lines(lay, pairs, line_tolerance, 0.5 * warns_above)
    found = []
    for members, c, u, worst in _line_groups(local, line_tolerance, pairs):
        distinct = np.unique(label[members]).size
        if distinct < 3:
            continue  # fewer than three distinct points: a cluster, reported as shared position
        off = p - members.size
        # how well the whole layout sees a rotation about that line (unit rotation, dimensionless frame)
        x_line = np.concatenate([-np.cross(u, c), u])
        seen = float(np.linalg.norm(t @ x_line) / np.linalg.norm(x_line))
        line_cond = s_max / seen if seen > 0.0 else math.inf
        move = lay.length(max(0.25, 2.5 * line_tolerance))
        point = lay.frame.centre + lay.frame.scale * c
        where = f"(the line along {_vec(u)} through {_vec(point)}{' ' + lay.unit if lay.unit else ''}; "
        where += f"the furthest is {lay.length(worst)} from it)"
        group = _names(members, lay.names)
        if off == 0:
            text = (
                f"all sensors lie almost on one line {where}: rotation about that line is nearly invisible; "
                f"move at least two of them off the line by at least {move}, on different sides"
            )
            severity: Severity = "warning"
        elif line_cond > _COND_GOOD or (cond > _COND_GOOD and line_cond > 0.5 * cond):
            text = (
                f"{group} lie almost on one line {where}: rotations about that line are hard to see "
                f"(only the other {off} sensor{'s see' if off > 1 else ' sees'} them); "
                f"move {'one' if off >= 2 else 'two'} of them off the line by at least {move}"
            )
            severity = "warning"
        elif distinct >= 4 and p <= _EVERY_LINE_UP_TO:
            text = (
                f"{group} lie almost on one line {where}: they do not see rotation about that line, "
                f"which the other {off} sensors see well enough"
            )
            severity = "info"
        else:
            continue  # three points near a line, harmless: not worth a line of the report
        found.append(Finding(severity, text, "collinear", tuple(int(m) + 1 for m in members)))
    return found


def check_layout(
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    unit: str = "",
    line_tolerance: float = 0.1,
    close_tolerance: float = 0.1,
    same_tolerance: float = 0.02,
    names: Sequence[str] | None = None,
) -> LayoutReport:
    """Check a sensor layout before a test.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Planned sensor locations (length).
    directions : array_like, shape (p, 3)
        Planned measuring axes (any length; normalised here).
    unit : str
        Length unit for the messages (``"mm"``, ``"in"``...); empty for none.
    line_tolerance : float
        Sensors within this distance of one line, as a fraction of the
        layout's RMS radius about its centroid, count as "almost on one line".
    close_tolerance : float
        Two sensors this close (same fraction) with directions within 10
        degrees of each other (or of opposite) count as redundant.
    same_tolerance : float
        Two sensors this close (same fraction) share one position.
    names : sequence of str, optional
        Sensor ids for the messages (quoted there: ``sensor 'A+x'``); default
        the numbers 1, 2... in the layout's order.

    Returns
    -------
    LayoutReport

    Raises
    ------
    InputError
        For arrays of the wrong shape, non-finite positions or a zero direction.

    Notes
    -----
    Checks, each reported as a :class:`Finding`:

    * at least six sensors (error below, info at exactly six: every shape then
      fits rigid motion exactly and noise or flexible motion go unseen);
    * rank 6 of ``T_mo`` (eq. (3) of [1], the paper's step (3)); otherwise the
      motion no sensor sees is described;
    * condition number of the dimensionless ``T_mo``
      (:func:`rigidid.core.geometry.layout_condition`): up to 10 good, 10-100
      a warning (noise on the least visible motion amplified that much), above
      100 a stronger warning; the least visible motion (smallest singular
      vector) is described;
    * per axis, the sensors whose direction is within 30 degrees of x, y or z
      (``|n_axis| > cos 30``); an axis without one is a warning (the paper's
      layouts have at least one per axis);
    * redundant pairs (close together, parallel or anti-parallel) and shared
      positions (triaxial mounts: info);
    * groups of three or more sensors almost on one line (within
      `line_tolerance`): rotation about that line is seen only by the other
      sensors. A warning when all sensors are on the line, or when the
      rotation about the line is seen more than 10 times worse than the best
      seen motion (``s_max / |T x_line| > 10`` with ``x_line`` the unit
      rotation about the line, the condition number restricted to that
      motion), or when the layout is not well conditioned (condition above
      10) mostly because of it (``s_max / |T x_line|`` above half the
      condition number); info
      for harmless groups of four or more distinct positions; harmless triples
      are not reported. Above 60 sensors only the lines that can warn are
      searched (the rotation about the line through two sensors seen more
      than half the warning threshold worse: ``x^T T^T T x`` per pair), and
      harmless groups are not reported: the search then grows as ``p^2``,
      not ``p^3`` (1,006 sensors: under a second).

    Tolerances are relative to the layout's size, so the check does not
    depend on units. Thresholds are rules of thumb, not guarantees; use
    :func:`rigidid.core.plan.predict_uncertainty` for figures.

    Examples
    --------
    Six sensors all along z on a flat plate see no in-plane motion:

    >>> pos = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 0, 0], [0, 2, 0]]
    >>> report = check_layout(pos, [[0, 0, 1]] * 6)
    >>> report.ok, report.rank, [f.code for f in report.findings if f.severity == "error"]
    (False, 3, ['rank', 'axis-missing', 'axis-missing'])
    """
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 3 or pos.shape[0] == 0:
        raise InputError(f"positions must be (sensors, 3), got {pos.shape}")
    if not np.all(np.isfinite(pos)):
        raise InputError("sensor positions must be finite")
    dirs = normalise_directions(directions)
    if dirs.shape != pos.shape:
        raise InputError(f"directions must match positions {pos.shape}, got {dirs.shape}")
    labels = [str(i + 1) for i in range(pos.shape[0])] if names is None else [repr(str(n)) for n in names]
    if len(labels) != pos.shape[0]:
        raise InputError(f"names must match positions ({pos.shape[0]}), got {len(labels)}")
    frame = layout_frame(pos)
    local = frame.to_local(pos)
    cond, rank = layout_condition(pos, dirs)
    lay = _Layout(dirs, frame, local, sensor_matrix(local, dirs), cond, rank, labels, unit)
    weakest = lay.motion(np.linalg.svd(lay.transformation)[2][-1])
    findings = [
        *_check_count(lay),
        *_check_rank_and_condition(lay, weakest),
        *_check_axes(lay),
        *_check_pairs(lay, close_tolerance, same_tolerance),
        *_check_collinear(lay, line_tolerance, same_tolerance),
    ]
    findings.sort(key=lambda f: _SEVERITY_ORDER[f.severity])
    return LayoutReport(
        sensors=pos.shape[0],
        rank=rank,
        condition=cond,
        axis_counts=_axis_counts(dirs),
        weakest_motion=weakest,
        findings=tuple(findings),
    )
