"""Centre of gravity, inertia, stiffness and damping from rigid-body modes.

The identity behind everything here is eq. (18) of [1],
``M_g G_go Q = K_g G_go``, with ``Q = M_o^-1 K_o`` the stiffness-to-mass matrix
in the coordinates of the origin ``o`` (eq. (17)), and its damping twin
``M_g G_go P = C_g G_go`` with ``P = M_o^-1 C_o``. Multiplying by
``G_og = G_go^-1`` (eq. (14)) on the right gives ``D Q_g = K_g / m`` with
``D = diag(I, J / m)`` and ``Q_g = G_go Q G_og`` the same matrix at the CG.
Symmetry of ``K_g`` is the whole information: ``D Q_g`` must be symmetric.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core import estimator
from rigidid.core.estimator import DAMPING_WEIGHT
from rigidid.core.geometry import layout_condition, normalise_directions, sensor_matrix, transfer_matrix
from rigidid.core.noise import NoiseLevels
from rigidid.core.statespace import mac_matrix, modal_from_poles, state_matrices_paper, state_matrix
from rigidid.errors import (
    IdentificationError,
    IllConditionedWarning,
    InputError,
    Notice,
    PhysicalPlausibilityWarning,
    emit,
)

__all__ = [
    "DAMPING_WEIGHT",
    "METHODS",
    "FitDiagnostics",
    "Identification",
    "identify",
    "inertia_observability",
    "match_modes",
    "model_modes",
    "physical_checks",
    "principal_axes",
    "solve_paper",
    "solve_structured",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
Method = Literal["structured", "paper"]
METHODS: tuple[str, ...] = ("structured", "paper")
UNOBSERVABLE = 1e-6
"""Inertia observability below which the inertia is not determined at all (an error)."""
WEAKLY_OBSERVABLE = 0.03
"""Inertia observability below which the inertia is poorly determined (a warning)."""
MISFIT_DOF = 21
"""Degrees of freedom of the weighted misfit: 30 equations of eq. (18) and its twin, 9 unknowns."""
ILL_CONDITIONED = 1e6
"""Layout condition number above which a warning is issued."""


def _sym(a: Array) -> Array:
    result: Array = 0.5 * (a + a.T)
    return result


def solve_structured(
    stiffness: Array, damping: Array | None = None, damping_weight: float = 0.0
) -> tuple[Array, Array]:
    """CG and inertia per mass from the whole of eq. (18) of [1], solved together.

    Parameters
    ----------
    stiffness : ndarray, shape (6, 6)
        ``Q = M_o^-1 K_o`` in the coordinates of the origin (dimensionless
        frame advised: lengths and times scaled to order one).
    damping : ndarray, shape (6, 6), optional
        ``P = M_o^-1 C_o``, used when `damping_weight` is positive.
    damping_weight : float
        Weight of the damping twin of eq. (18) against the stiffness equations.

    Returns
    -------
    cg : ndarray, shape (3,)
        Centre of gravity in the origin's frame (length).
    inertia_per_mass : ndarray, shape (3, 3)
        Symmetric ``J / m`` (length^2).

    Notes
    -----
    A batch of one of :func:`rigidid.core.estimator.solve_cg`, which says how.
    """
    q = np.asarray(stiffness, dtype=float)[None]
    p = None if damping is None else np.asarray(damping, dtype=float)[None]
    g, j, _ = estimator.solve_cg(q, p, damping_weight)
    return g[0], j[0]


def inertia_observability(stiffness: Array, cg: Array) -> float:
    """How well eq. (18) of [1] determines the inertia: 0 (not at all) to 1.

    Parameters
    ----------
    stiffness : ndarray, shape (6, 6)
        ``Q = M_o^-1 K_o`` in the dimensionless frame.
    cg : ndarray, shape (3,)
        The CG in that frame.

    Returns
    -------
    float
        Ratio of the smallest to the largest singular value of the linear map
        from ``J / m`` to the antisymmetric part of ``D Q_g``. Zero when the
        supports do not couple rotations to translations (for example mounts
        symmetric about the CG): then any inertia fits the modes, each with its
        own stiffness. Typical test rigs give 0.1-0.3; measurement noise of
        relative size e raises an unobservable case to about e.

    Notes
    -----
    Only the stiffness equations are used: damping is too uncertain to carry
    the inertia (:func:`rigidid.core.estimator.observability_batch`).
    """
    q = np.asarray(stiffness, dtype=float)[None]
    return float(estimator.observability_batch(q, np.asarray(cg, dtype=float)[None])[0])


def solve_paper(stiffness: Array) -> tuple[Array, Array]:
    """CG and inertia per mass by the paper's sequential route, eqs. (36)-(39) of [1].

    Parameters
    ----------
    stiffness : ndarray, shape (6, 6)
        ``Q = M_o^-1 K_o`` in the origin's coordinates.

    Returns
    -------
    cg : ndarray, shape (3,)
        From eq. (36).
    inertia_per_mass : ndarray, shape (3, 3)
        ``J / m = (K12 / m)^T Q21^-1`` (eq. (39)), symmetrised as in the paper.

    Raises
    ------
    IdentificationError
        If eq. (36) or ``Q21`` is singular (for example identical mounts at one
        height, where ``K21`` is singular in exact arithmetic).

    Warns
    -----
    IllConditionedWarning
        If either is ill-conditioned (condition above 1e6).

    Notes
    -----
    Fragile: 0.1 % noise on mode shapes can move the CG by a large fraction of
    the body. Kept for comparison with the paper; eq. (40) is applied in its
    corrected form ``K22 / m = (J / m) Q22 - (K21 / m) H_go`` by the caller
    (:func:`identify` forms ``sym(D Q_g)``, which is the same matrix).
    """
    notices: list[Notice] = []
    try:
        return _solve_paper(np.asarray(stiffness, dtype=float), notices)
    finally:
        emit(notices)


def _solve_paper(q: Array, notices: list[Notice]) -> tuple[Array, Array]:
    a36, b36 = (x[0] for x in estimator.eq36_system(q[None]))
    q21 = q[3:, :3]
    for name, mat in (("eq. (36)", a36), ("Q21", q21)):
        c = np.linalg.cond(mat)
        if not np.isfinite(c) or c > 1e12:
            raise IdentificationError(
                f"paper method: {name} is singular (condition {c:.3g}); use the structured method"
            )
        if c > ILL_CONDITIONED:
            message = f"paper method: {name} is ill-conditioned (condition {c:.3g})"
            notices.append(Notice(IllConditionedWarning, message))
    g = np.asarray(np.linalg.solve(a36, b36), dtype=np.float64)
    k12 = estimator.at_cg(q[None], g[None])[0, :3, 3:]
    j = np.asarray(np.linalg.solve(q21.T, k12).T, dtype=np.float64)
    return g, _sym(j)


def principal_axes(inertia: ArrayLike) -> tuple[Array, Array]:
    """Principal moments (ascending) and axes of a symmetric inertia tensor.

    Parameters
    ----------
    inertia : array_like, shape (3, 3)
        Inertia tensor (or inertia per mass).

    Returns
    -------
    moments : ndarray, shape (3,)
        Eigenvalues, ascending.
    axes : ndarray, shape (3, 3)
        Column ``i`` is the unit axis of ``moments[i]``; the first two columns
        have their largest component positive, the third completes a
        right-handed frame.

    Examples
    --------
    >>> moments, axes = principal_axes([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 5.0]])
    >>> moments.round(12).tolist()
    [1.0, 3.0, 5.0]
    >>> (axes[:, 0] * np.sqrt(2) + 0.0).round(12).tolist()
    [1.0, -1.0, 0.0]
    """
    w, v = np.linalg.eigh(_sym(np.asarray(inertia, dtype=float)))
    for i in range(2):
        if v[np.argmax(np.abs(v[:, i])), i] < 0:
            v[:, i] = -v[:, i]
    v[:, 2] = np.cross(v[:, 0], v[:, 1])
    return w, v


@dataclass(frozen=True)
class FitDiagnostics:
    """How well-posed the identification was and how well the result fits.

    Attributes
    ----------
    layout_condition : float
        Condition number of the dimensionless sensor transformation.
    layout_rank : int
        Its rank (6 needed).
    rigid_fit_residual : ndarray, shape (6,)
        Per mode used, ``|psi - T T^+ psi| / |psi|`` (0 with six sensors).
    structure_residual : float
        ``|D Q_g - (D Q_g)^T| / |D Q_g|`` at the solution: 0 for data an exact
        rigid body explains.
    inertia_observability : float
        See :func:`inertia_observability`.
    model_frequency_hz, model_damping_ratio : ndarray, shape (6,)
        Modes of the identified model, matched to the measured modes.
    model_mac : ndarray, shape (6,)
        MAC between each measured shape and the identified model's shape.
    warnings : tuple of str
        The physical-plausibility and conditioning warnings raised.
    misfit : float or None
        With noise levels given: the weighted cost ``|L r|^2`` of eq. (18) and
        its damping twin in noise units at the noise-weighted fit, chi-square with `misfit_dof` degrees
        of freedom when the rigid-body model and the levels are right (None
        without levels).
    misfit_dof : int
        Its degrees of freedom (21: 30 equations, 9 unknowns), 0 without levels.
    residual_weights : ndarray, shape (30, 30), or None
        The whitening ``L`` of the reported estimate
        (:func:`rigidid.core.linearised.residual_weights`); None when the
        estimate has fixed weights (no levels, or a misfit per degree of
        freedom above :data:`~rigidid.core.linearised.ACCEPTABLE_MISFIT`).
    """

    layout_condition: float
    layout_rank: int
    rigid_fit_residual: Array
    structure_residual: float
    inertia_observability: float
    model_frequency_hz: Array
    model_damping_ratio: Array
    model_mac: Array
    warnings: tuple[str, ...] = field(default=())
    misfit: float | None = None
    misfit_dof: int = 0
    residual_weights: Array | None = field(default=None, repr=False)


@dataclass(frozen=True)
class Identification:
    """Identified rigid-body properties, at the CG, in the layout's units.

    Attributes
    ----------
    center_of_gravity : ndarray, shape (3,)
        CG in the layout's axes (length).
    inertia_per_mass : ndarray, shape (3, 3)
        Inertia tensor about the CG divided by mass (length^2).
    stiffness_per_mass : ndarray, shape (6, 6)
        Support stiffness at the CG over mass, DOF order x, y, z, rx, ry, rz
        (1/s^2, length/s^2, length^2/s^2 blocks).
    damping_per_mass : ndarray, shape (6, 6)
        Viscous damping at the CG over mass (1/s, length/s, length^2/s).
    mass : float or None
        The mass, when known.
    frequency_hz, damping_ratio : ndarray, shape (6,)
        Measured modes used, in the order given.
    mode_shapes_cg : ndarray of complex, shape (6, 6)
        Column ``k``: the rigid-body motion ``(x, y, z, rx, ry, rz)`` of the
        CG (length, rad) that best explains measured mode ``k``, scaled to
        unit Euclidean norm.
    method : str
        ``"structured"`` or ``"paper"``.
    diagnostics : FitDiagnostics
    """

    center_of_gravity: Array
    inertia_per_mass: Array
    stiffness_per_mass: Array
    damping_per_mass: Array
    mass: float | None
    frequency_hz: Array
    damping_ratio: Array
    mode_shapes_cg: CArray
    method: str
    diagnostics: FitDiagnostics

    def _absolute(self, per_mass: Array) -> Array | None:
        return None if self.mass is None else self.mass * per_mass

    @property
    def inertia_tensor(self) -> Array | None:
        """Inertia tensor about the CG (mass length^2), or None without mass."""
        return self._absolute(self.inertia_per_mass)

    @property
    def stiffness_matrix(self) -> Array | None:
        """Support stiffness at the CG (mass/s^2 ...), or None without mass."""
        return self._absolute(self.stiffness_per_mass)

    @property
    def damping_matrix(self) -> Array | None:
        """Support damping at the CG (mass/s ...), or None without mass."""
        return self._absolute(self.damping_per_mass)

    @property
    def principal_moments_per_mass(self) -> Array:
        """Principal moments of inertia per mass, ascending (length^2)."""
        return principal_axes(self.inertia_per_mass)[0]

    @property
    def principal_moments(self) -> Array | None:
        """Principal moments of inertia, ascending, or None without mass."""
        return self._absolute(self.principal_moments_per_mass)

    @property
    def principal_axes(self) -> Array:
        """Unit principal axes, column ``i`` for moment ``i``."""
        return principal_axes(self.inertia_per_mass)[1]

    def model_modes(self) -> tuple[CArray, CArray]:
        """Modes of the identified model, eq. (1) of [1] with the identified matrices.

        Returns
        -------
        poles : ndarray of complex, shape (6,)
            One pole per pair, ``Im > 0`` (rad/s), ascending frequency.
        shapes : ndarray of complex, shape (6, 6)
            Column ``k``: motion of the CG ``(x, y, z, rx, ry, rz)`` in mode
            ``k`` (length and rad), scaled to unit Euclidean norm.
        """
        poles, shapes = model_modes(self.inertia_per_mass, self.stiffness_per_mass, self.damping_per_mass)
        order = np.argsort(np.abs(poles))
        shapes = shapes[:, order]
        return poles[order], shapes / np.linalg.norm(shapes, axis=0)


def physical_checks(inertia_per_mass: Array, stiffness: Array, damping: Array) -> list[str]:
    """Physically impossible features of an identified body, in words.

    Parameters
    ----------
    inertia_per_mass : ndarray, shape (3, 3)
        ``J / m`` (or ``J``).
    stiffness, damping : ndarray, shape (6, 6)
        ``K`` and ``C`` at the CG (or per mass).

    Returns
    -------
    list of str
        Empty for a plausible body; else: an inertia that is not positive
        definite, principal moments that break the triangle inequality
        (``I_3 <= I_1 + I_2`` holds for every real body), a stiffness or damping
        matrix that is not positive semi-definite.

    Examples
    --------
    >>> physical_checks(np.diag([1.0, 1.0, 3.0]), np.eye(6), np.eye(6))
    ['principal moments break the triangle inequality (largest exceeds the sum of the other two)']
    """
    found = []
    j, k, c = (np.asarray(x, dtype=float) for x in (inertia_per_mass, stiffness, damping))
    moments = np.linalg.eigvalsh(_sym(j))
    if moments[0] <= 0.0:
        found.append(
            f"inertia tensor is not positive definite (principal moments per mass {moments.round(6).tolist()})"
        )
    elif moments[2] > (moments[0] + moments[1]) * (1.0 + 1e-9):
        found.append("principal moments break the triangle inequality (largest exceeds the sum of the other two)")
    for name, mat in (("stiffness", k), ("damping", c)):
        ev = np.linalg.eigvalsh(_sym(mat))
        if ev[0] < -1e-9 * max(abs(ev[-1]), 1e-300):
            share = 100.0 * ev[0] / max(abs(ev[-1]), 1e-300)
            found.append(
                f"{name} matrix is not positive semi-definite (smallest eigenvalue {share:.2g} % of the largest)"
            )
    return found


def model_modes(j: Array, k: Array, c: Array) -> tuple[CArray, CArray]:
    """Poles (``Im > 0``) and CG motions of the model ``diag(I, j)``, ``k``, ``c`` (eq. (1) of [1])."""
    d = np.eye(6)
    d[3:, 3:] = j
    mu, vec = np.linalg.eig(state_matrix(d, k, c))
    upper = np.argsort(-mu.imag)[:6]
    return mu[upper], vec[6:, upper]


def match_modes(measured: CArray, model_poles: CArray, model_shapes: CArray) -> tuple[CArray, Array]:
    """Pair each measured mode with the model mode of best MAC; return model poles and MACs."""
    mac = mac_matrix(measured, model_shapes)
    chosen = np.argmax(mac, axis=1)
    return model_poles[chosen], mac[np.arange(mac.shape[0]), chosen]


def identify(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    *,
    mass: float | None = None,
    method: Method = "structured",
    damping_weight: float = DAMPING_WEIGHT,
    warn: bool = True,
    noise: NoiseLevels | None = None,
) -> Identification:
    """Identify CG, inertia, stiffness and damping from six rigid-body modes.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor locations in the test's axes (length), ``p >= 6``.
    directions : array_like, shape (p, 3)
        Measuring axes (normalised here).
    poles : array_like of complex, shape (6,)
        One pole of each rigid-body mode (rad/s).
    shapes : array_like of complex, shape (p, 6)
        Mode shapes as each sensor reads them along its own direction; any
        scaling per mode.
    mass : float, optional
        Mass of the body; without it only per-mass results are meaningful.
    method : {"structured", "paper"}
        ``"structured"``: exact state matrix (eq. (19)) and the whole of
        eq. (18) solved together (:func:`solve_structured`). ``"paper"``:
        eqs. (25)-(26) and the sequential eqs. (36)-(40), eq. (40) corrected.
    damping_weight : float
        With ``"structured"``, weight of the damping twin of eq. (18) in the
        CG and inertia fit, in the dimensionless frame (0: stiffness only).
        The default was chosen on ``benchmarks/noise_accuracy.py``; results
        there change by under 0.1 % of span between 0 and 0.3.
    warn : bool
        Issue the conditioning and plausibility findings as warnings (they are
        in ``diagnostics.warnings`` either way). They are issued once the
        result or the error is known, so none is lost when an error follows.

    Returns
    -------
    Identification

    Raises
    ------
    InputError
        Shapes that do not match the layout, or a mass that is not positive.
    IdentificationError
        A layout of rank below 6, or modes that do not determine a rigid body.

    Notes
    -----
    Shapes with more than six sensors are projected on rigid-body motion by
    least squares (eq. (30) of [1] in spirit). The computation runs in a frame
    centred on the sensors, with lengths divided by their RMS radius and times
    by the mean natural frequency, so results are invariant to origin and
    units. Physically impossible results raise
    :class:`~rigidid.errors.PhysicalPlausibilityWarning` and are listed in the
    diagnostics. The structured method is a batch of one of
    :func:`rigidid.core.estimator.estimate`, the kernel every route shares.

    Examples
    --------
    Simulate a body on four mounts, read it with eight sensors, identify it:

    >>> from rigidid.core.simulate import Body, Mount, body_modes
    >>> mounts = [Mount.from_values(p, (8e4, 9e4, 2e5), (40.0, 50.0, 90.0))
    ...           for p in ([0.3, 0.2, -0.3], [-0.3, 0.2, 0.2], [0.3, -0.25, 0.1], [-0.3, -0.2, -0.2])]
    >>> body = Body(mass=60.0, center_of_gravity=np.array([0.02, -0.01, 0.1]),
    ...             inertia_tensor=np.array([[2.0, 0.1, 0.0], [0.1, 3.0, 0.2], [0.0, 0.2, 4.0]]), mounts=mounts)
    >>> pos = np.array([[x, y, z] for x in (0.4, -0.4) for y in (0.3, -0.3) for z in (0.2, -0.2)])
    >>> dirs = np.eye(3)[[0, 1, 2, 0, 1, 2, 0, 1]]
    >>> modes = body_modes(body, pos, dirs)
    >>> result = identify(pos, dirs, modes.poles, modes.shapes, mass=60.0)
    >>> result.center_of_gravity.round(9).tolist()
    [0.02, -0.01, 0.1]
    >>> np.diag(result.inertia_tensor).round(6).tolist()
    [2.0, 3.0, 4.0]
    """
    notices: list[Notice] = []
    try:
        return _identify(positions, directions, poles, shapes, mass, method, damping_weight, notices, noise)
    finally:
        if warn:
            emit(notices)


def _checked(
    positions: ArrayLike, directions: ArrayLike, poles: ArrayLike, shapes: ArrayLike, mass: float | None, method: str
) -> tuple[Array, Array, CArray, CArray]:
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    lam = np.asarray(poles, dtype=complex).ravel()
    psi = np.asarray(shapes, dtype=complex)
    if psi.ndim != 2 or psi.shape != (pos.shape[0], lam.shape[0]) or dirs.shape != pos.shape:
        raise InputError(
            f"shapes must be (sensors, modes) = ({pos.shape[0]}, {lam.shape[0]}), got {psi.shape}; "
            f"directions {dirs.shape}"
        )
    if lam.shape[0] != 6:
        raise InputError(f"exactly six rigid-body modes are needed, got {lam.shape[0]}")
    if np.any(lam.imag <= 0.0) or np.any(lam.real > 0.0):
        raise InputError("poles must be stable with positive imaginary part")
    if not np.all(np.isfinite(psi)) or not np.all(np.isfinite(pos)):
        raise InputError("positions and shapes must be finite")
    if mass is not None and not (np.isfinite(mass) and mass > 0.0):
        raise InputError(f"mass must be positive, got {mass}")
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    return pos, dirs, lam, psi


def _identify(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    mass: float | None,
    method: str,
    damping_weight: float,
    notices: list[Notice],
    noise: NoiseLevels | None = None,
) -> Identification:
    pos, dirs, lam, psi = _checked(positions, directions, poles, shapes, mass, method)
    cond, rank = layout_condition(pos, dirs)
    if rank < 6:
        raise IdentificationError(f"the sensor layout has rank {rank}; rigid-body motion needs rank 6")
    if cond > ILL_CONDITIONED:
        notices.append(Notice(IllConditionedWarning, f"sensor layout is ill-conditioned (condition {cond:.3g})"))
    prep = estimator.prepare(pos[None], dirs[None], lam[None], psi[None])
    if not prep.ok[0]:
        raise IdentificationError(estimator.STATUS_MESSAGES[int(prep.status[0])])
    weighted = None
    if method == "paper":
        q, p = state_matrices_paper(lam / prep.omega[0], prep.coordinates[0])
        g, j = _solve_paper(q, notices)
    else:
        q, p = prep.stiffness[0], prep.damping[0]
        g_b, j_b, _ = estimator.solve_cg(prep.stiffness, prep.damping, damping_weight)
        weighted = None if noise is None else _weighted(pos, dirs, lam, psi, noise, prep, g_b, j_b)
        if weighted is not None and weighted[3] is not None:
            g_b, j_b = weighted[0], weighted[1]
        g, j = g_b[0], j_b[0]
    omega, phi = float(prep.omega[0]), prep.coordinates[0]
    observability = _checked_observability(q, g, notices)
    dq = estimator.at_cg(q[None], g[None], j[None])[0]
    dp = estimator.at_cg(p[None], g[None], j[None])[0]
    structure = float(np.linalg.norm(dq - dq.T)) / max(float(np.linalg.norm(dq)), 1e-300)
    k, c = _sym(dq), _sym(dp)
    notices.extend(Notice(PhysicalPlausibilityWarning, message) for message in physical_checks(j, k, c))

    centre, length = prep.centre[0], float(prep.scale[0])
    model_poles, model_phi = model_modes(j, k, c)
    model_psi = sensor_matrix((pos - centre) / length, dirs, g) @ model_phi
    matched, mac = match_modes(psi, model_poles, model_psi)
    model_f, model_z = modal_from_poles(matched * omega)
    f, z = modal_from_poles(lam)

    dof = np.array([1.0, 1.0, 1.0, length, length, length])
    shapes_cg = (transfer_matrix(g) @ phi) * np.array([length, length, length, 1.0, 1.0, 1.0])[:, None]
    return Identification(
        center_of_gravity=centre + length * g,
        inertia_per_mass=length**2 * j,
        stiffness_per_mass=omega**2 * k * np.outer(dof, dof),
        damping_per_mass=omega * c * np.outer(dof, dof),
        mass=None if mass is None else float(mass),
        frequency_hz=f,
        damping_ratio=z,
        mode_shapes_cg=shapes_cg / np.linalg.norm(shapes_cg, axis=0),
        method=method,
        diagnostics=FitDiagnostics(
            layout_condition=cond,
            layout_rank=rank,
            rigid_fit_residual=prep.fit_residual[0],
            structure_residual=structure,
            inertia_observability=observability,
            model_frequency_hz=model_f,
            model_damping_ratio=model_z,
            model_mac=mac,
            warnings=tuple(n.message for n in notices),
            misfit=None if weighted is None else float(weighted[2][0]),
            misfit_dof=0 if weighted is None else MISFIT_DOF,
            residual_weights=None if weighted is None else weighted[3],
        ),
    )


def _checked_observability(q: Array, g: Array, notices: list[Notice]) -> float:
    """The inertia observability of ``M^-1 K`` about `g`: refused when none, a notice when weak."""
    observability = inertia_observability(q, g)
    if observability < UNOBSERVABLE:
        raise IdentificationError(
            "the inertia is not observable: the supports do not couple rotations to translations "
            "(e.g. mounts symmetric about the CG), so inertia and stiffness cannot be separated "
            f"(inertia observability {observability:.1e})"
        )
    if observability < WEAKLY_OBSERVABLE:
        notices.append(
            Notice(
                IllConditionedWarning,
                f"the inertia is poorly determined (inertia observability {observability:.2g}, typically "
                "0.1-0.3): the supports couple rotations to translations only weakly",
            )
        )
    return observability


def _weighted(
    pos: Array, dirs: Array, lam: CArray, psi: CArray, noise: NoiseLevels, prep: estimator.Prepared, g: Array, j: Array
) -> tuple[Array, Array, Array, Array | None] | None:
    """The noise-weighted solution from the unweighted one: CG, ``J / m``, misfit (batches of one) and ``L``.

    When the weighted misfit per degree of freedom exceeds
    :data:`~rigidid.core.linearised.ACCEPTABLE_MISFIT`, the unweighted CG and
    ``J / m`` come back with the misfit and no ``L``.
    """
    from rigidid.core.linearised import ACCEPTABLE_MISFIT, residual_weights

    params = np.array([j[0, 0, 0], j[0, 1, 1], j[0, 2, 2], j[0, 0, 1], j[0, 0, 2], j[0, 1, 2]])
    white = residual_weights(pos, dirs, lam, psi, noise, g[0], params)
    if white is None:
        return None
    g_w, j_w, cost = estimator.solve_cg(prep.stiffness, prep.damping, weights=white)
    if not (np.all(np.isfinite(g_w)) and np.all(np.isfinite(j_w))):
        return None
    if cost[0] > ACCEPTABLE_MISFIT * MISFIT_DOF:
        # the noise levels do not explain the misfit: their weights are not trusted
        return g, j, cost, None
    return g_w, j_w, cost, white
