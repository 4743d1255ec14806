"""Test planning: is a sensor layout good enough, and where to add sensors.

Before an impact test, three questions: can this layout see all six
rigid-body motions at all (the paper's step (3): a transformation ``T_mo`` of
rank 6, eq. (3) of [1]); how precisely will the CG and the inertia come out
for the noise to expect (Monte Carlo on simulated modes of a CAD estimate of
the body, :func:`predict_uncertainty`); and which extra sensor helps most
(:func:`suggest_sensors`).

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from itertools import combinations
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import layout_condition, layout_frame, normalise_directions, sensor_matrix
from rigidid.core.identify import DAMPING_WEIGHT
from rigidid.core.simulate import Body, body_modes
from rigidid.core.uncertainty import (
    DEFAULT_NOISE,
    NoiseLevels,
    Uncertainty,
    _apply_noise,
    _draw_normals,
    _Normals,
    identify_batch,
    propagate,
    uncertainty_to_dict,
)
from rigidid.errors import IllConditionedWarning, InputError

__all__ = [
    "AXIS_COS",
    "Finding",
    "LayoutReport",
    "PredictedFigures",
    "Prediction",
    "SensorPlan",
    "SuggestedSensor",
    "candidate_grid",
    "check_layout",
    "layout_report_to_dict",
    "predict_uncertainty",
    "prediction_to_dict",
    "sensor_plan_to_dict",
    "suggest_sensors",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
Severity = Literal["error", "warning", "info"]
_SEVERITY_ORDER: dict[str, int] = {"error": 0, "warning": 1, "info": 2}

AXIS_COS = math.cos(math.radians(30.0))
"""A sensor counts for axis x, y or z when its direction is within 30 degrees of it."""

_COND_GOOD = 10.0
_COND_POOR = 100.0
_PARALLEL_COS = math.cos(math.radians(10.0))


# --------------------------------------------------------------------------- layout check


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
        The sensors concerned, numbered from 1 in the layout's order.
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


def _names(indices: ArrayLike) -> str:
    items = [str(int(i) + 1) for i in np.asarray(indices).ravel()]
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


def _line_groups(local: Array, tol: float) -> list[tuple[NDArray[np.intp], Array, Array, float]]:
    """Maximal groups of at least 3 points within `tol` of one line: (members, point, direction, worst distance)."""
    p = local.shape[0]
    found: list[tuple[NDArray[np.intp], Array, Array, float]] = []
    seen: set[tuple[int, ...]] = set()
    for i, j in combinations(range(p), 2):
        d = local[j] - local[i]
        length = float(np.linalg.norm(d))
        if length <= 2.0 * tol:
            continue
        u = d / length
        rel = local - local[i]
        dist = np.linalg.norm(rel - np.outer(rel @ u, u), axis=1)
        members = np.flatnonzero(dist <= tol)
        if members.size < 3:
            continue
        # refit the line through the members and check again
        pts = local[members]
        c = pts.mean(axis=0)
        _, _, vt = np.linalg.svd(pts - c)
        u = vt[0]
        rel = local - c
        dist = np.linalg.norm(rel - np.outer(rel @ u, u), axis=1)
        members = np.flatnonzero(dist <= tol)
        key = tuple(int(m) for m in members)
        if members.size < 3 or key in seen:
            continue
        seen.add(key)
        found.append((members, c, u, float(dist[members].max())))
    # keep the maximal groups only
    sets = [set(g[0].tolist()) for g in found]
    return [g for g, s in zip(found, sets, strict=True) if not any(s < other for other in sets)]


def check_layout(
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    unit: str = "",
    line_tolerance: float = 0.1,
    close_tolerance: float = 0.1,
    same_tolerance: float = 0.02,
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
      are not reported.

    Tolerances are relative to the layout's size, so the check does not
    depend on units. Thresholds are rules of thumb, not guarantees; use
    :func:`predict_uncertainty` for figures.
    """
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 3 or pos.shape[0] == 0:
        raise InputError(f"positions must be (sensors, 3), got {pos.shape}")
    if not np.all(np.isfinite(pos)):
        raise InputError("sensor positions must be finite")
    dirs = normalise_directions(directions)
    if dirs.shape != pos.shape:
        raise InputError(f"directions must match positions {pos.shape}, got {dirs.shape}")
    p = pos.shape[0]
    frame = layout_frame(pos)
    local = frame.to_local(pos)
    size = frame.scale
    findings: list[Finding] = []

    # --- count
    if p < 6:
        findings.append(
            Finding(
                "error",
                f"only {p} sensors: the six rigid-body motions need at least six (the paper's step 3); "
                f"add {6 - p} more, pointing along axes the others do not cover",
                "too-few-sensors",
            )
        )
    elif p == 6:
        findings.append(
            Finding(
                "info",
                "six sensors, the minimum: every mode shape fits rigid motion exactly, so noise and flexible "
                "motion cannot be detected; two to six more sensors make the result checkable",
                "minimum-sensors",
            )
        )

    # --- rank, condition, least visible motion
    cond, rank = layout_condition(pos, dirs)
    t = sensor_matrix(local, dirs)
    vt = np.linalg.svd(t)[2]
    weakest = _describe_motion(vt[-1], frame.centre, size, unit)
    if p >= 6 and rank < 6:
        blind = [_describe_motion(v, frame.centre, size, unit) for v in vt[rank:]]
        what = blind[0] if len(blind) == 1 else f"{len(blind)} independent motions, e.g. " + "; ".join(blind)
        findings.append(
            Finding(
                "error",
                f"the layout has rank {rank}, not 6: no sensor sees {what}; "
                "add or re-point sensors so that each such motion moves at least one of them along its axis",
                "rank",
            )
        )
    elif rank == 6 and cond > _COND_POOR:
        findings.append(
            Finding(
                "warning",
                f"the layout is poorly conditioned (condition number {_fmt(cond)}; up to 10 is good): "
                f"measurement noise on {weakest} is amplified about {_fmt(cond)} times; "
                "spread the sensors out and point them along different axes",
                "condition",
            )
        )
    elif rank == 6 and cond > _COND_GOOD:
        findings.append(
            Finding(
                "warning",
                f"the layout is only fairly conditioned (condition number {_fmt(cond)}; up to 10 is good): "
                f"the least visible motion is {weakest}",
                "condition",
            )
        )
    elif rank == 6:
        findings.append(Finding("info", f"the layout is well conditioned (condition number {_fmt(cond)})", "condition"))

    # --- axes
    comp = np.abs(dirs)
    along = comp > AXIS_COS
    counts = along.sum(axis=0)
    oblique = int(p - along.any(axis=1).sum())
    for a, name in enumerate("xyz"):
        if counts[a] > 0:
            continue
        best = int(np.argmax(comp[:, a]))
        if comp[best, a] < 0.05:
            findings.append(
                Finding(
                    "error",
                    f"no sensor has any component along {name}: translation along {name} cannot be seen; "
                    f"point at least one sensor along {name}",
                    "axis-missing",
                )
            )
        else:
            findings.append(
                Finding(
                    "warning",
                    f"no sensor measures along {name} (within 30 degrees; the closest is sensor {best + 1}, "
                    f"{_fmt(comp[best, a])} of its axis along {name}): translation along {name} is seen only "
                    f"indirectly and less precisely; point at least one sensor along {name}",
                    "axis-missing",
                    (best + 1,),
                )
            )
    findings.append(
        Finding(
            "info",
            f"sensors along x: {counts[0]}, y: {counts[1]}, z: {counts[2]}, oblique: {oblique}",
            "axis-counts",
        )
    )

    # --- pairs: redundant and shared positions
    dist = np.linalg.norm(local[:, None] - local[None], axis=2)
    cosang = np.abs(dirs @ dirs.T)
    shared_done: set[int] = set()
    for i, j in combinations(range(p), 2):
        if dist[i, j] <= close_tolerance and cosang[i, j] >= _PARALLEL_COS:
            angle = math.degrees(math.acos(min(1.0, float(cosang[i, j]))))
            findings.append(
                Finding(
                    "warning",
                    f"{_names([i, j])} are {_with_unit(dist[i, j] * size, unit)} apart and measure almost the same "
                    f"direction ({_fmt(angle)} degrees apart): the second adds little; "
                    "point one along another axis or move it elsewhere on the body",
                    "redundant-pair",
                    (i + 1, j + 1),
                )
            )
    for i in range(p):
        if i in shared_done:
            continue
        group = [j for j in range(p) if dist[i, j] <= same_tolerance]
        if len(group) > 1:
            shared_done.update(group)
            findings.append(
                Finding(
                    "info",
                    f"{_names(group)} share one position (a triaxial mount?): fine, but together they see only "
                    "the motion of that one point",
                    "shared-position",
                    tuple(g + 1 for g in group),
                )
            )

    # --- nearly collinear groups
    s_max = float(np.linalg.norm(t, 2)) if t.size else 0.0
    label = np.arange(p)
    for i, j in combinations(range(p), 2):
        if dist[i, j] <= same_tolerance:
            label[label == label[j]] = label[i]
    for members, c, u, worst in _line_groups(local, line_tolerance):
        distinct = np.unique(label[members]).size
        if distinct < 3:
            continue  # fewer than three distinct points: a cluster, reported as shared position
        off = p - members.size
        # how well the whole layout sees a rotation about that line (unit rotation, dimensionless frame)
        x_line = np.concatenate([-np.cross(u, c), u])
        seen = float(np.linalg.norm(t @ x_line) / np.linalg.norm(x_line))
        line_cond = s_max / seen if seen > 0.0 else math.inf
        move = _with_unit(max(0.25, 2.5 * line_tolerance) * size, unit)
        point = frame.centre + size * c
        where = f"(the line along {_vec(u)} through {_vec(point)}{' ' + unit if unit else ''}; "
        where += f"the furthest is {_with_unit(worst * size, unit)} from it)"
        if off == 0:
            text = (
                f"all sensors lie almost on one line {where}: rotation about that line is nearly invisible; "
                f"move at least two of them off the line by at least {move}, on different sides"
            )
            severity: Severity = "warning"
        elif line_cond > _COND_GOOD or (cond > _COND_GOOD and line_cond > 0.5 * cond):
            text = (
                f"{_names(members)} lie almost on one line {where}: rotations about that line are hard to see "
                f"(only the other {off} sensor{'s see' if off > 1 else ' sees'} them); "
                f"move {'one' if off >= 2 else 'two'} of them off the line by at least {move}"
            )
            severity = "warning"
        elif distinct >= 4:
            text = (
                f"{_names(members)} lie almost on one line {where}: they do not see rotation about that line, "
                f"which the other {off} sensors see well enough"
            )
            severity = "info"
        else:
            continue  # three points near a line, harmless: not worth a line of the report
        findings.append(Finding(severity, text, "collinear", tuple(int(m) + 1 for m in members)))

    findings.sort(key=lambda f: _SEVERITY_ORDER[f.severity])
    return LayoutReport(
        sensors=p,
        rank=rank,
        condition=cond,
        axis_counts=(int(counts[0]), int(counts[1]), int(counts[2]), oblique),
        weakest_motion=weakest,
        findings=tuple(findings),
    )


def _none_if_inf(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def layout_report_to_dict(report: LayoutReport) -> dict[str, Any]:
    """JSON-ready form of a :class:`LayoutReport`.

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


# --------------------------------------------------------------------------- predicted uncertainty


def _body_length(body: Body) -> float:
    """Characteristic length ``sqrt(trace(J) / (3 m))``: the RMS radius of gyration."""
    return float(np.sqrt(np.trace(body.inertia_tensor) / (3.0 * body.mass)))


def _score(cg_std: Array, moments_rel_std: Array, length: float) -> Array:
    """``|std(CG)| / L + |std(I_k) / I_k|`` along the last axis (NaN/inf propagate)."""
    result: Array = np.linalg.norm(cg_std, axis=-1) / length + np.linalg.norm(moments_rel_std, axis=-1)
    return result


@dataclass(frozen=True)
class PredictedFigures:
    """Predicted precision of a layout for a body.

    Attributes
    ----------
    score : float
        ``|std(CG)|_2 / L + |std(I_k) / I_k|_2``, with ``L = sqrt(trace(J) / (3 m))``
        the body's RMS radius of gyration and ``I_k`` its principal moments:
        the relative error to expect on the CG plus that on the principal
        moments (dimensionless; smaller is better; ``inf`` when the layout
        cannot identify the body).
    center_of_gravity_std : ndarray, shape (3,)
        Standard deviation of each CG coordinate (length).
    principal_moments_std : ndarray, shape (3,)
        Standard deviation of each principal moment, ascending moments (mass length^2).
    principal_moments_rel_std : ndarray, shape (3,)
        The same relative to the moments.
    condition : float
        Condition number of the layout.
    failed : int
        Monte Carlo draws that could not be identified.
    """

    score: float
    center_of_gravity_std: Array
    principal_moments_std: Array
    principal_moments_rel_std: Array
    condition: float
    failed: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (lists and floats; infinite and NaN values as None)."""
        return {
            "score": _none_if_inf(self.score),
            "center_of_gravity_std": [_none_if_inf(v) for v in self.center_of_gravity_std.tolist()],
            "principal_moments_std": [_none_if_inf(v) for v in self.principal_moments_std.tolist()],
            "principal_moments_rel_std": [_none_if_inf(v) for v in self.principal_moments_rel_std.tolist()],
            "condition": _none_if_inf(self.condition),
            "failed": self.failed,
        }


@dataclass(frozen=True)
class Prediction:
    """Result of :func:`predict_uncertainty`.

    Attributes
    ----------
    figures : PredictedFigures
        The summary (standard deviations and score).
    inertia_std : ndarray, shape (3, 3)
        Standard deviation of each inertia tensor entry (mass length^2).
    uncertainty : Uncertainty
        The whole Monte Carlo result; its estimates are the identification of
        the exact simulated modes (the body itself, to rounding).
    """

    figures: PredictedFigures
    inertia_std: Array
    uncertainty: Uncertainty

    @property
    def center_of_gravity_std(self) -> Array:
        """Standard deviation of the CG coordinates (length)."""
        return self.figures.center_of_gravity_std

    @property
    def principal_moments_std(self) -> Array:
        """Standard deviation of the principal moments (mass length^2)."""
        return self.figures.principal_moments_std

    @property
    def score(self) -> float:
        """See :attr:`PredictedFigures.score`."""
        return self.figures.score


def _check_body(body: Body) -> None:
    if not isinstance(body, Body):
        raise InputError("the body must be a rigidid.core.simulate.Body")


def predict_uncertainty(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    noise: NoiseLevels = DEFAULT_NOISE,
    draws: int = 1000,
    seed: int | None = 0,
    damping_weight: float = DAMPING_WEIGHT,
) -> Prediction:
    """Predicted standard deviation of the CG and inertia for a planned test.

    Parameters
    ----------
    body : Body
        Estimate of the body (mass, CG, inertia, mounts), from CAD for example.
    positions : array_like, shape (p, 3)
        Planned sensor locations (length), ``p >= 6``.
    directions : array_like, shape (p, 3)
        Planned measuring axes.
    noise : NoiseLevels
        Measurement noise to expect.
    draws : int
        Monte Carlo draws.
    seed : int, optional
        Seed (fixed by default so that repeated plans agree).
    damping_weight : float
        As in :func:`~rigidid.core.identify.identify`.

    Returns
    -------
    Prediction

    Raises
    ------
    InputError
        Invalid body or arrays.
    IdentificationError
        If the layout cannot identify the body (rank below 6).

    Notes
    -----
    The exact modes of the body as the layout would read them
    (:func:`~rigidid.core.simulate.body_modes`) are perturbed by `noise` and
    identified again (:func:`~rigidid.core.uncertainty.propagate`). The figures
    hold for this body and these mounts: a CAD estimate that is far off (or
    mounts that couple the modes differently) changes them.
    """
    _check_body(body)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    modes = body_modes(body, pos, dirs)
    result = propagate(
        pos, dirs, modes.poles, modes.shapes, mass=body.mass, noise=noise, draws=draws, seed=seed,
        damping_weight=damping_weight,
    )  # fmt: skip
    moments = np.linalg.eigvalsh(body.inertia_tensor)
    cg_std = result.center_of_gravity.std
    mom_std = result.principal_moments.std
    rel = mom_std / moments
    figures = PredictedFigures(
        score=float(_score(cg_std, rel, _body_length(body))),
        center_of_gravity_std=cg_std,
        principal_moments_std=mom_std,
        principal_moments_rel_std=rel,
        condition=layout_condition(pos, dirs)[0],
        failed=result.failed,
    )
    return Prediction(figures, result.inertia.std, result)


def prediction_to_dict(prediction: Prediction) -> dict[str, Any]:
    """JSON-ready form of a :class:`Prediction`: the figures, ``inertia_std`` and the full uncertainty."""
    out = prediction.figures.to_dict()
    out["inertia_std"] = [[_none_if_inf(v) for v in row] for row in prediction.inertia_std.tolist()]
    out["uncertainty"] = uncertainty_to_dict(prediction.uncertainty)
    return out


# --------------------------------------------------------------------------- sensor suggestions


def candidate_grid(positions: ArrayLike, per_axis: int = 3, margin: float = 0.0) -> Array:
    """Candidate sensor positions on a regular grid over the sensors' bounding box.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Existing sensor locations (length).
    per_axis : int
        Grid points along each axis (at least 1); an axis along which the
        sensors do not extend gets one point.
    margin : float
        Enlarge the box by this fraction of its extent on each side.

    Returns
    -------
    ndarray, shape (k, 3)
        Grid points, ``k <= per_axis ** 3``.

    Notes
    -----
    The grid knows nothing of the body's surface: points inside the body or
    in the air are candidates too. Pass real mounting points to
    :func:`suggest_sensors` when you have them.
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    if pos.shape[0] == 0 or per_axis < 1:
        raise InputError("candidate_grid needs at least one position and one point per axis")
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    ext = hi - lo
    lo, hi = lo - margin * ext, hi + margin * ext
    tiny = 1e-9 * max(float(ext.max()), 1e-300)
    axes = [np.linspace(lo[a], hi[a], per_axis) if ext[a] > tiny else np.array([lo[a]]) for a in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    result: Array = grid
    return result


@dataclass(frozen=True)
class SuggestedSensor:
    """One step of :func:`suggest_sensors`.

    Attributes
    ----------
    step : int
        1 for the first sensor added, 2 for the next...
    candidate : int
        Index into the candidate list (positions x directions, see
        :attr:`SensorPlan.candidate_positions`).
    position : ndarray, shape (3,)
        Where to put it (length).
    direction : ndarray, shape (3,)
        Its measuring axis (unit).
    figures : PredictedFigures
        Predicted precision of the layout with this sensor and those before it.
    ranking : tuple of (int, float)
        Every candidate tried at this step and its score, best first.
    """

    step: int
    candidate: int
    position: Array
    direction: Array
    figures: PredictedFigures
    ranking: tuple[tuple[int, float], ...]


@dataclass(frozen=True)
class SensorPlan:
    """Result of :func:`suggest_sensors`.

    Attributes
    ----------
    baseline : PredictedFigures
        The layout as given.
    steps : tuple of SuggestedSensor
        The sensors to add, in order.
    candidate_positions, candidate_directions : ndarray, shape (c, 3)
        The candidates tried (positions repeated for the three axes when no
        directions were given).
    noise : NoiseLevels
        Noise assumed.
    draws : int
        Monte Carlo draws per candidate.
    """

    baseline: PredictedFigures
    steps: tuple[SuggestedSensor, ...]
    candidate_positions: Array
    candidate_directions: Array
    noise: NoiseLevels
    draws: int


def _figures_batch(
    body: Body,
    layouts_pos: Array,
    layouts_dir: Array,
    shapes: CArray,
    poles: CArray,
    normals: _Normals,
    noise: NoiseLevels,
    damping_weight: float,
) -> list[PredictedFigures]:
    """Predicted figures of several layouts of the same size at once (common random numbers)."""
    n_lay, p = layouts_pos.shape[:2]
    draws = normals.mass.shape[0]
    data = _apply_noise(normals, noise, layouts_pos, layouts_dir, poles, shapes, body.mass)
    batch = identify_batch(
        data.positions.reshape(-1, p, 3),
        data.directions.reshape(-1, p, 3),
        data.poles.reshape(-1, 6),
        data.shapes.reshape(-1, p, 6),
        damping_weight=damping_weight,
    )
    assert data.mass is not None
    mass = data.mass.reshape(n_lay, draws)
    ok = batch.ok.reshape(n_lay, draws)
    cg = batch.center_of_gravity.reshape(n_lay, draws, 3)
    moments = batch.principal_moments_per_mass.reshape(n_lay, draws, 3) * mass[..., None]
    truth = np.linalg.eigvalsh(body.inertia_tensor)
    length = _body_length(body)
    out = []
    for k in range(n_lay):
        good = ok[k]
        n_ok = int(good.sum())
        cond = layout_condition(layouts_pos[k], layouts_dir[k])[0]
        if n_ok < max(2, int(0.95 * draws)):
            inf3 = np.full(3, np.inf)
            out.append(PredictedFigures(math.inf, inf3, inf3.copy(), inf3.copy(), cond, draws - n_ok))
            continue
        cg_std = cg[k, good].std(axis=0, ddof=1)
        m_std = moments[k, good].std(axis=0, ddof=1)
        rel = m_std / truth
        out.append(PredictedFigures(float(_score(cg_std, rel, length)), cg_std, m_std, rel, cond, draws - n_ok))
    return out


def suggest_sensors(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    candidates: ArrayLike | None = None,
    candidate_directions: ArrayLike | None = None,
    *,
    add: int = 1,
    noise: NoiseLevels = DEFAULT_NOISE,
    draws: int = 300,
    seed: int | None = 0,
    damping_weight: float = DAMPING_WEIGHT,
) -> SensorPlan:
    """Greedy choice of sensors to add, each the one that most reduces the predicted uncertainty.

    Parameters
    ----------
    body : Body
        Estimate of the body and its mounts.
    positions : array_like, shape (p, 3)
        Current sensor locations (length); fewer than six is allowed.
    directions : array_like, shape (p, 3)
        Current measuring axes.
    candidates : array_like, shape (k, 3), optional
        Possible new sensor locations; default :func:`candidate_grid` of the
        current positions (27 points).
    candidate_directions : array_like, shape (k, 3), optional
        Measuring axis of each candidate. Without it every candidate position
        is tried along x, y and z.
    add : int
        Number of sensors to add.
    noise : NoiseLevels
        Noise to expect.
    draws : int
        Monte Carlo draws per candidate and step.
    seed : int, optional
        Seed; every candidate is judged on the same random numbers (common
        random numbers), so comparisons are much less noisy than the figures.
    damping_weight : float
        As in :func:`~rigidid.core.identify.identify`.

    Returns
    -------
    SensorPlan

    Raises
    ------
    InputError
        Invalid body, arrays, or ``add`` larger than the number of candidates.

    Warns
    -----
    IllConditionedWarning
        When no candidate gives a usable layout at some step (it is then
        chosen by condition number).

    Notes
    -----
    The criterion is :attr:`PredictedFigures.score`. Each step evaluates every
    remaining candidate with the Monte Carlo of
    :func:`~rigidid.core.uncertainty.identify_batch` (``k * draws``
    identifications per step, a few seconds for 80 candidates and 300 draws).
    While the layout cannot identify the body (rank below 6) the candidate
    that gives the best-conditioned layout is taken. Greedy choice is not
    globally optimal; it is a good start for an engineer's judgement.
    """
    _check_body(body)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions) if pos.shape[0] else np.zeros((0, 3))
    if dirs.shape != pos.shape:
        raise InputError(f"directions must match positions {pos.shape}, got {dirs.shape}")
    cand = candidate_grid(pos) if candidates is None else np.asarray(candidates, dtype=float).reshape(-1, 3)
    if candidate_directions is None:
        c_pos = np.repeat(cand, 3, axis=0)
        c_dir = np.tile(np.eye(3), (cand.shape[0], 1))
    else:
        c_dir = normalise_directions(candidate_directions)
        if c_dir.shape != cand.shape:
            raise InputError(f"candidate directions must match candidates {cand.shape}, got {c_dir.shape}")
        c_pos = cand
    if not (1 <= add <= c_pos.shape[0]):
        raise InputError(f"can add between 1 and {c_pos.shape[0]} sensors (the candidates), asked for {add}")
    if not (isinstance(draws, int) and draws >= 2):
        raise InputError(f"draws must be an integer of at least 2, got {draws!r}")
    p = pos.shape[0]
    everything = body_modes(body, np.vstack([pos, c_pos]), np.vstack([dirs, c_dir]))
    base_shapes, cand_shapes = everything.shapes[:p], everything.shapes[p:]
    normals_all = _draw_normals(np.random.default_rng(seed), draws, p + add)

    def figures_of(chosen: list[int], extra: NDArray[np.intp]) -> list[PredictedFigures]:
        n_extra = len(chosen) + (1 if extra.size else 0)
        size = p + n_extra
        if size < 6:
            return [
                PredictedFigures(math.inf, np.full(3, np.inf), np.full(3, np.inf), np.full(3, np.inf), math.inf, draws)
                for _ in range(max(extra.size, 1))
            ]
        n_lay = max(extra.size, 1)
        lay_pos = np.empty((n_lay, size, 3))
        lay_dir = np.empty((n_lay, size, 3))
        lay_shp = np.empty((n_lay, size, 6), dtype=complex)
        lay_pos[:, :p], lay_dir[:, :p], lay_shp[:, :p] = pos, dirs, base_shapes
        for slot, c in enumerate(chosen):
            lay_pos[:, p + slot], lay_dir[:, p + slot], lay_shp[:, p + slot] = c_pos[c], c_dir[c], cand_shapes[c]
        if extra.size:
            lay_pos[:, -1], lay_dir[:, -1], lay_shp[:, -1] = c_pos[extra], c_dir[extra], cand_shapes[extra]
        normals = normals_all.sensors(np.arange(size))
        return _figures_batch(body, lay_pos, lay_dir, lay_shp, everything.poles, normals, noise, damping_weight)

    baseline = figures_of([], np.zeros(0, dtype=np.intp))[0]
    chosen: list[int] = []
    steps: list[SuggestedSensor] = []
    for step in range(1, add + 1):
        remaining = np.array([c for c in range(c_pos.shape[0]) if c not in chosen], dtype=np.intp)
        figs = figures_of(chosen, remaining)
        scores = np.array([f.score for f in figs])
        if np.all(~np.isfinite(scores)):
            # cannot identify yet: take the best-conditioned (rank first) layout
            ranks, ratios = [], []
            for c in remaining:
                lay_p = np.vstack([pos, c_pos[chosen], c_pos[c]])
                lay_d = np.vstack([dirs, c_dir[chosen], c_dir[c]])
                s = np.linalg.svd(sensor_matrix(layout_frame(lay_p).to_local(lay_p), lay_d), compute_uv=False)
                r = int(np.sum(s > 1e3 * max(lay_p.shape[0], 6) * np.finfo(float).eps * s[0]))
                ranks.append(r)
                ratios.append(s[r - 1] / s[0] if r else 0.0)
            # most independent motions first, then the best conditioned
            order = np.lexsort((-np.array(ratios), -np.array(ranks)))
            if p + step >= 6:
                warnings.warn(
                    f"step {step}: no candidate gives a layout that identifies the body; chose by conditioning",
                    IllConditionedWarning,
                    stacklevel=2,
                )
        else:
            order = np.argsort(scores, kind="stable")
        best = int(order[0])
        c_best = int(remaining[best])
        chosen.append(c_best)
        ranking = tuple((int(remaining[i]), float(scores[i])) for i in order)
        steps.append(SuggestedSensor(step, c_best, c_pos[c_best].copy(), c_dir[c_best].copy(), figs[best], ranking))
    return SensorPlan(baseline, tuple(steps), c_pos, c_dir, noise, draws)


def sensor_plan_to_dict(plan: SensorPlan, *, ranking: int = 5) -> dict[str, Any]:
    """JSON-ready form of a :class:`SensorPlan`.

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
        "baseline": plan.baseline.to_dict(),
        "steps": [
            {
                "step": s.step,
                "candidate": s.candidate,
                "position": s.position.tolist(),
                "direction": s.direction.tolist(),
                "figures": s.figures.to_dict(),
                "ranking": [entry(c, v) for c, v in s.ranking[:ranking]],
            }
            for s in plan.steps
        ],
        "noise": plan.noise.as_dict(),
        "draws": plan.draws,
    }
