"""The mass line: mass, CG and inertia from accelerance FRFs between rigid and elastic modes.

Far above the rigid-body modes and below the first elastic mode, the
accelerance of a rigid body is its inverse mass matrix seen through the
sensors and references, ``H(w) ~ T M^-1 T_f^T`` (the mass line). With mounts
that are not negligible the next terms of the expansion in ``1/w`` are kept:

``H(w) = T [M^-1 + M^-1 K M^-1 / w^2 + i M^-1 C M^-1 / w + ...] T_f^T``.

Rigid coordinates ``Y(w) = T^+ H(w)`` (least squares over the sensors) then
satisfy, for every frequency of the band,

``M Y(w) = T_f^T + E / w^2 + i G / w + F w^2``

which is **linear** in the ten inertial parameters (``m``, ``m c``, the
inertia about the origin) and in the free correction matrices ``E`` (mount
stiffness), ``G`` (mount damping) and ``F`` (upper residual of elastic modes
above the band), all 6 x q. Fitting ``M`` rather than ``M^-1`` lets fewer
than six references determine the body: ``M^-1`` has 21 free entries but only
its product with the ``q`` reference columns is measured; ``M`` has ten
parameters and ``q >= 2`` references in general position determine them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.chisquare import chi2_quantile
from rigidid.core.frfmodes import PEAK_SHORTFALL_Z, PeakShortfall, peak_split, residue_limit, scaled_frame
from rigidid.core.frfstats import BodyIntervals, body_intervals, misfit_units
from rigidid.core.geometry import sensor_matrix, skew
from rigidid.core.rigidfrf import RigidFrfFit, mass_matrix_from_parameters
from rigidid.errors import FrfPeakBiasWarning, IdentificationError, InputError, Notice

__all__ = ["MIN_BAND_RATIO", "MassLine", "auto_band", "mass_from_residues", "mass_line", "peak_notice"]

Array = NDArray[np.float64]

MIN_LINES = 10
"""Fewest frequency lines in the band (the fit has up to six terms per rigid coordinate)."""

MIN_BAND_RATIO = 2.0
"""Narrowest band (upper over lower frequency) the mass line accepts: over narrower bands the
constant and its correction terms cannot be told apart (benchmarks/frf_accuracy.py, on mounts:
bands of ratio 1.3-1.6 gave mass errors of 18-99 %, ratio 1.8-2.2 about 1 %)."""


@dataclass(frozen=True)
class MassLine:
    """What the mass line gives.

    Attributes
    ----------
    mass : float
        Mass (1 / accelerance unit, i.e. force / (length / s^2)).
    center_of_gravity : ndarray, shape (3,)
        CG in the layout coordinates (length).
    inertia_tensor : ndarray, shape (3, 3)
        Inertia tensor about the CG (mass length^2), off-diagonals minus the
        products of inertia.
    band : tuple of float
        The frequency band used (Hz).
    band_source : str
        ``"given"`` or ``"automatic"``.
    frequencies_used : int
        Number of frequency lines in the band.
    residual : float
        RMS relative misfit of the model to the rigid coordinates in the band.
    corrections : tuple of str
        The correction terms fitted (``"stiffness"``, ``"damping"``, ``"upper_residual"``).
    supports : str
        How the mounts were modelled: ``"first_order"`` (the ``1/w^2``, ``i/w`` terms),
        ``"exact"`` (:func:`rigidid.core.rigidfrf.rigid_frf_fit`) or ``"none"``.
    supports_reason : str
        Why (one sentence; empty from :func:`mass_from_residues`).
    intervals : rigidid.core.frfstats.BodyIntervals or None
        Linearised 95 % intervals of mass, CG and inertia (None where not available).
    misfit_noise_units : float or None
        The fit's RMS misfit over the noise seen in its third differences along frequency
        (:func:`rigidid.core.frfstats.misfit_units`): about 1 when the model explains the FRFs.
    misfit_where : str
        Where the misfit is largest (e.g. ``"response 3, reference 1"``), for messages.
    peak_shortfall : rigidid.core.frfmodes.PeakShortfall or None
        How far the FRFs fall short of the fit at the resonance peaks (residues only).
    support_matrices : (ndarray, ndarray) or None
        With `supports` ``"exact"``: the fitted stiffness and damping ``(K, C)``, each
        (6, 6) about the CG (DOF x, y, z, rx, ry, rz; force / length, force s / length,
        rotations in rad; angular frequency), as far as the band determines them.
    """

    mass: float
    center_of_gravity: Array
    inertia_tensor: Array
    band: tuple[float, float]
    band_source: str
    frequencies_used: int
    residual: float
    corrections: tuple[str, ...]
    supports: str = "first_order"
    supports_reason: str = ""
    intervals: BodyIntervals | None = None
    misfit_noise_units: float | None = None
    misfit_where: str = ""
    peak_shortfall: PeakShortfall | None = None
    support_matrices: tuple[Array, Array] | None = None


def peak_notice(result: MassLine, route: str) -> Notice | None:
    """A :class:`~rigidid.errors.FrfPeakBiasWarning` when the FRFs fall short of the fit at the peaks.

    Parameters
    ----------
    result : MassLine
        An FRF route's answer.
    route : str
        Its name (for the message).

    Returns
    -------
    Notice or None
        When ``|z|`` of :attr:`MassLine.peak_shortfall` exceeds
        :data:`rigidid.core.frfmodes.PEAK_SHORTFALL_Z`.
    """
    short = result.peak_shortfall
    if short is None or not abs(short.z) > PEAK_SHORTFALL_Z:
        return None
    how = "fall short of" if short.fraction > 0.0 else "exceed"
    return Notice(
        FrfPeakBiasWarning,
        f"the FRFs {how} the {route} fit at the resonance peaks by {100 * abs(short.fraction):.2g} % of the "
        f"summed power's shape ({abs(short.z):.3g} standard errors, strongest at {short.frequency:.4g} Hz), "
        "beyond their noise: the bias of an H1 estimate there (leakage, low coherence); the answer may be off "
        "beyond its interval: finer line spacing, more averages, or an H2/Hv estimate",
    )


def auto_band(frequencies: ArrayLike, frf: ArrayLike) -> tuple[float, float]:
    """Choose the mass-line band from the FRF magnitude sum.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Frequencies (Hz), ascending.
    frf : array_like, shape (p, q, f)
        Accelerance FRFs.

    Returns
    -------
    low, high : float
        ``3 x`` the highest rigid-body peak and ``0.5 x`` the first elastic peak
        (Hz); ``high`` is the last frequency when no elastic peak is seen.

    Raises
    ------
    IdentificationError
        If the peaks cannot be split into rigid and elastic ones with room for
        a band between them (give the band instead).

    Notes
    -----
    Peaks of ``sum |H|^2`` over all FRFs are split into rigid-body and elastic
    ones by :func:`rigidid.core.frfmodes.peak_split`; their ratio must exceed 6
    for the band to exist. A single cluster of peaks is taken as the rigid-body
    modes.
    """
    return _auto_band(np.asarray(frequencies, dtype=float), np.asarray(frf))[0]


def _auto_band(f: Array, h: NDArray[np.complex128]) -> tuple[tuple[float, float], float | None]:
    """:func:`auto_band` and the first elastic peak (Hz, None if none is seen)."""
    fp, split = peak_split(f, h)
    if fp.size == 0:
        raise IdentificationError("no resonance peak in the FRFs: give the band")
    if split is not None:
        low, high = 3.0 * fp[split], 0.5 * fp[split + 1]
        elastic: float | None = float(fp[split + 1])
    else:
        low, high = 3.0 * fp[-1], float(f[-1])
        elastic = None
    if not high > low or np.count_nonzero((f >= low) & (f <= high)) < MIN_LINES:
        if elastic is None:
            raise IdentificationError(
                f"no room for a mass-line band: the FRFs end at {f[-1]:.4g} Hz, {f[-1] / fp[-1]:.2g}x the highest "
                f"peak ({fp[-1]:.4g} Hz), and the mass line needs lines from 3x it up (a band of a factor "
                f"{MIN_BAND_RATIO:g}): measure further up, or give the band"
            )
        raise IdentificationError(
            f"no room for a mass-line band between the rigid-body peaks (up to {fp[split]:.4g} Hz) and the first "
            f"elastic one at {elastic:.4g} Hz: the mass line needs lines from 3x the one to half the other; "
            "give the band"
        )
    return (float(low), float(high)), elastic


def _body_from_inverse_mass(y0: Array, tf: Array, origin: Array, span: float) -> tuple[float, Array, Array]:
    """Mass, CG and inertia about the CG from ``y0 = M^-1 T_f^T`` (scaled frame): ``M y0 = T_f^T``, linear."""
    q = tf.shape[0]
    a_mat = np.stack([(mass_matrix_from_parameters(e) @ y0).reshape(-1) for e in np.eye(10)], axis=1)
    b_vec = tf.T.reshape(-1)
    norms = np.linalg.norm(a_mat, axis=0)
    norms[norms == 0.0] = 1.0
    sol, _, rank10, svals = np.linalg.lstsq(a_mat / norms, b_vec, rcond=None)
    if rank10 < 10 or svals[-1] < 1e-4 * svals[0]:
        raise IdentificationError(
            f"the {q} reference(s) do not determine the mass, CG and inertia from the mass line "
            "(at least 3 references at different points and in different directions are needed)"
        )
    theta = sol / norms
    m = float(theta[0])
    if not m > 0.0:
        hint = (
            ": the FRFs have the opposite sign convention (accelerance is acceleration per force, its mass line "
            "positive); negate them or the reference directions"
            if m < 0.0
            else ""
        )
        raise IdentificationError(f"the mass line gives a mass of {m:.4g}, not positive{hint}")
    return _body_from_parameters(theta, origin, span)


def mass_line(
    frequencies: ArrayLike,
    frf: ArrayLike,
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
    stiffness: bool = True,
    damping: bool = True,
    upper_residual: bool = True,
    elastic_frequency: float | None = None,
    supports: str = "auto",
) -> MassLine:
    """Mass, CG and inertia from accelerance FRFs by the mass line.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Frequencies (Hz), ascending, positive.
    frf : array_like of complex, shape (p, q, f)
        Accelerance: sensor ``i`` per unit force at reference ``j``.
    positions, directions : array_like, shape (p, 3)
        Sensor locations (length) and unit measuring axes, ``p >= 6`` of rank 6.
    reference_positions, reference_directions : array_like, shape (q, 3)
        Force points and unit directions, ``q >= 2``.
    band : (float, float), optional
        Band (Hz). Default: :func:`auto_band`.
    stiffness, damping, upper_residual : bool
        Fit the mount-stiffness term (``1/w^2``), the mount-damping term
        (``i/w``) and an upper residual of elastic modes above the band.
    elastic_frequency : float, optional
        The first elastic mode (Hz), above the band. The upper residual is then
        that mode's own term ``x / (1 - x)``, ``x = (w / w_e)^2``, plus ``w^2``;
        without it, ``w^2`` and ``w^4``. Found with the band when the band is
        automatic.
    supports : {"auto", "exact", "first_order"}
        How the mounts enter: ``"first_order"`` the ``1/w^2`` and ``i/w`` terms
        above; ``"exact"`` the rigid-body model ``K X + i w C X - w^2 M X = -w^2
        T_f^T`` fitted line by line (:func:`rigidid.core.rigidfrf.rigid_frf_fit`);
        ``"auto"`` the exact fit when `stiffness` is on (see Notes).

    Returns
    -------
    MassLine

    Raises
    ------
    InputError
        If shapes disagree or the band holds too few lines.
    IdentificationError
        If the sensors do not see six rigid-body motions, the references do
        not determine the ten inertial parameters, or the band spans less than
        :data:`MIN_BAND_RATIO`.

    Notes
    -----
    One linear least-squares problem (real and imaginary parts stacked,
    columns scaled to unit norm); rigid coordinates about the sensor
    centroid, in a frame scaled by the sensor span, so that the problem is
    well conditioned whatever the units. The fit is exact for a rigid body
    on massless mounts to first order in ``(w_rigid / w)^2`` with the
    stiffness term, and to first order in ``(w / w_elastic)^2`` with the
    upper residual. With `supports` ``"exact"`` (or ``"auto"`` choosing it) the
    mounts are modelled exactly (:mod:`rigidid.core.rigidfrf`) over at most
    :data:`EXACT_LINES` evenly spaced lines of the band; ``"auto"`` takes that fit
    wherever it is determined unless it misfits the band by more than
    :data:`AUTO_LACK_OF_FIT` times the first-order fit (misfits in noise units,
    the noise estimated from the third differences of the first-order misfit
    along frequency, where a smooth lack of fit vanishes); ``residual`` is then
    the exact fit's. Where the supports' first-order terms do not stand out of the
    noise (:func:`_supports_seen`, :data:`SUPPORTS_SEEN`: free-free bodies) ``"auto"``
    takes the first-order fit, linear, its upper residual always fitted. The first-order
    (and the uncorrected) answer is the fit weighted by each line's noise level, the level
    estimated from the misfit (:func:`_level_weighted`, issue 21): where the noise varies
    along the band the unweighted fit let the noisy lines in at full weight. The fit's
    residual and misfit in noise units stay the unweighted fit's.
    """
    f = np.asarray(frequencies, dtype=float).reshape(-1)
    h = np.asarray(frf, dtype=complex)
    pos, dirs = np.asarray(positions, dtype=float), np.asarray(directions, dtype=float)
    rpos, rdirs = np.asarray(reference_positions, dtype=float), np.asarray(reference_directions, dtype=float)
    p, q = pos.shape[0], rpos.shape[0]
    if h.shape != (p, q, f.size):
        raise InputError(f"frf must have shape (sensors, references, frequencies) = {(p, q, f.size)}, got {h.shape}")
    band_source = "given"
    if band is None:
        band, found = _auto_band(f, h)
        band_source = "automatic"
        if elastic_frequency is None:
            elastic_frequency = found
    lo, hi = float(band[0]), float(band[1])
    sel = _band_lines(f, lo, hi)
    n_f = int(np.count_nonzero(sel))
    # scaled frame: origin at the sensor centroid, lengths in units of the span
    origin, span, t = scaled_frame(pos, dirs)
    # in scaled coordinates rotations are per unit span: force columns T_f^T unchanged in form
    tf = sensor_matrix((rpos - origin) / span, rdirs)
    w = 2.0 * np.pi * f[sel]
    y = np.linalg.lstsq(t, h[:, :, sel].reshape(p, q * n_f), rcond=None)[0].reshape(6 * q, n_f)
    # per rigid coordinate and reference: constant (the mass line) plus correction terms
    extra = tuple(
        name for name, on in (("stiffness", stiffness), ("damping", damping), ("upper_residual", upper_residual)) if on
    )
    design = _correction_design(w, extra, elastic_frequency)
    target = np.concatenate([y.real, y.imag], axis=1).T  # (2 n_f, 6 q)
    coef, _, rank, _ = np.linalg.lstsq(design, target, rcond=None)
    if rank < design.shape[1]:
        raise InputError(f"band {lo:g}-{hi:g} Hz is too narrow to separate the mass line from its corrections")
    fitted = design @ coef
    residual = float(np.sqrt(np.mean((fitted - target) ** 2)) / np.sqrt(np.mean(target**2)))
    y0 = coef[0].reshape(6, q)  # M^-1 T_f^T (scaled rigid coordinates per unit force)
    support_model, why = _support_model(supports, stiffness)
    fit: RigidFrfFit | None = None
    noise = _noise_residual(fitted - target, target, design.shape[1])
    if support_model == "auto" and (unseen := _unseen_supports(design, coef, fitted - target, 1 + int(damping))):
        support_model, why = "first_order", unseen
    if support_model in ("exact", "auto"):
        fit = _exact_fit(w, y.reshape(6, q, n_f), (tf, t), design, (stiffness, damping), support_model == "exact")
        if support_model == "auto":
            support_model, why = _auto_supports(fit, residual, noise)
    units, where = _first_order_misfit(fitted - target, design.shape[1], q)
    supports_kc = None
    if support_model == "exact" and fit is not None:
        m, cg, inertia = _body_from_parameters(fit.parameters, origin, span)
        units, where, intervals = _exact_verdict(fit, origin, span)
        residual = fit.residual
        supports_kc = _supports_at_cg(fit, cg - origin, span)
    else:
        x_w, coef_w, e_w = _level_weighted(design, target, fitted - target)
        y0 = coef_w[0].reshape(6, q)
        m, cg, inertia = _body_from_inverse_mass(y0, tf, origin, span)
        intervals = _first_order_intervals(x_w, e_w, y0, tf, origin, span)
    return MassLine(
        mass=m, center_of_gravity=cg, inertia_tensor=inertia, band=(lo, hi), band_source=band_source,
        frequencies_used=n_f, residual=residual, corrections=extra, supports=support_model, supports_reason=why,
        intervals=intervals, misfit_noise_units=units, misfit_where=where, support_matrices=supports_kc,
    )  # fmt: skip


def _band_lines(f: Array, lo: float, hi: float) -> NDArray[np.bool_]:
    """The lines of the mass-line band `lo`-`hi` Hz, refused when it is too narrow or holds too few lines."""
    if hi < MIN_BAND_RATIO * lo:
        raise IdentificationError(
            f"the mass-line band {lo:.4g}-{hi:.4g} Hz spans less than a factor {MIN_BAND_RATIO:g}: the rigid-body "
            "modes are too close to the elastic ones to separate the mass line from the mounts (use the modal route)"
        )
    sel: NDArray[np.bool_] = (f >= lo) & (f <= hi)
    n_f = int(np.count_nonzero(sel))
    if n_f < MIN_LINES:
        raise InputError(f"band {lo:g}-{hi:g} Hz holds {n_f} frequency lines, need at least {MIN_LINES}")
    return sel


def _exact_fit(
    w: Array,
    y: NDArray[np.complex128],
    frames: tuple[Array, Array],
    design: Array,
    terms: tuple[bool, bool],
    required: bool,
) -> RigidFrfFit | None:
    """The exact support fit (:func:`rigidid.core.rigidfrf.rigid_frf_fit`) on every k-th line of the band.

    `y` (6, q, lines) are the rigid coordinates per unit force, `frames` the force columns ``T_f`` and
    the sensor matrix ``T`` (scaled frame); the upper-residual columns of the mass line's `design` go
    with it; `terms`: (stiffness, damping). None when the fit fails and was not `required`.
    """
    from rigidid.core.rigidfrf import rigid_frf_fit

    tf, t = frames
    stiffness, damping = terms
    n_f = w.size
    upper = design[:n_f, 1 + int(stiffness) + int(damping) :]  # the upper-residual columns (real)
    every = -(-n_f // EXACT_LINES)  # every k-th line: the exact fit's cost grows with lines x references^2
    args = (w[::every], y[:, :, ::every], tf.T)
    try:
        plain = rigid_frf_fit(*args, damping=damping, sensor_gram=t.T @ t)
    except IdentificationError:
        plain = None
    if not upper.shape[1]:
        if plain is None and required:
            return rigid_frf_fit(*args, damping=damping, sensor_gram=t.T @ t)
        return plain
    try:
        full = rigid_frf_fit(*args, damping=damping, residual_basis=upper[::every], sensor_gram=t.T @ t)
    except IdentificationError:
        if plain is None and required:
            raise
        return plain
    return full if plain is None or _residual_needed(plain, full, upper.shape[1]) else plain


UPPER_RESIDUAL_Z = 3.090232306167813
"""The exact support fit keeps the upper residual when the misfit it removes exceeds the noise's share at
the false-alarm rate of this normal quantile, 0.1 % (:func:`upper_residual_f`, :func:`chi2_quantile`; on
femtools' soft-mount cases, 21 lines 6-15 Hz and no elastic mode, its 72 free coefficients took the mass
from 0.3 % to 2 % off at 1 % noise, and negative at 3 %). The test before issue 21's last stop,
``F > 1 + 3 sqrt(2 / k)`` with ``k = 6 q`` coefficients per residual function, took the noise of the
``6 q`` columns as independent and equal: on mounted bodies (benchmarks/frf_coverage.py, 200 draws, no
residual in the simulator) ``F`` had mean 1.08 but standard deviation 0.36 against the 0.24 it assumed,
and kept the residual on 7 % of the draws (nominal 0.1-0.5 %); with the effective degrees of freedom
(``nu`` 11-30, predicted SD 0.35) the same 200 draws keep it once (0.5 %)."""


UPPER_RESIDUAL_CHEAP = 5.0
"""The exact support fit also keeps the upper residual whenever it lowers the misfit at all and widens
the mass's standard error by less than this factor (the residual is then cheap: nearly orthogonal to the
inertial parameters). On free-free bodies measured below an elastic mode (benchmarks/frf_coverage.py,
free, 200 draws) the widening was 2.5 (median; 95 % below 5.4) and the F test alone dropped a residual
the data need in 16 % of the draws, leaving 10 answers beyond 4 of their own SE without a warning (RMS z
of the mass 1.41); with this rule 1 (widening 5.06), RMS z 1.01. On mounted bodies (5.5-9.9), near-band
supports and femtools' cases (9.6-17), where the F test's choice was right, nothing changes."""


def upper_residual_f(plain_rows: Array, full_rows: Array, n_basis: int) -> tuple[float, float]:
    """The upper residual's F statistic and its effective numerator degrees of freedom.

    Parameters
    ----------
    plain_rows, full_rows : ndarray, shape (12 q, n)
        The exact fit's weighted misfit without and with the residual
        (:attr:`rigidid.core.rigidfrf.RigidFrfFit.misfit_rows`: real parts then imaginary, per rigid
        coordinate and reference, along the lines).
    n_basis : int
        The residual's functions (real, fitted per column).

    Returns
    -------
    f_stat : float
        ``F = (c_0 - c_1) / (b tr S)``, ``c`` the sums of squares of the misfits, ``b`` = `n_basis`,
        ``S`` the ``6 q x 6 q`` covariance of the real rows of the misfit with the residual (over its
        ``n - b`` degrees of freedom per row).
    dof : float
        ``nu = b (tr S)^2 / tr(S^2)``.

    Notes
    -----
    Under noise alone (no residual in the data) ``c_0 - c_1`` is the noise projected on the residual's
    ``b x 6 q`` coefficients (eq. (1) of [1] in the frequency domain, output error, linearised), the same
    ``b`` functions along the lines for every column: ``e^T (S kron P) e``, ``P`` a rank-``b`` projector,
    a sum of ``b`` copies of ``sum_i lambda_i chi2_1`` over the eigenvalues of ``S``. Its mean is
    ``b tr S`` and its variance ``2 b tr(S^2)``; Satterthwaite's match of both moments gives
    ``nu F ~ chi2(nu)``. The columns' noise is correlated through the sensors and unequal (on mounted
    bodies of benchmarks/frf_coverage.py ``nu`` was 11-27 for ``b 6 q = 36`` coefficients), so the
    old ``k = b 6 q`` overstated the statistic's degrees of freedom; with ``nu`` its standard deviation
    was 0.35 predicted against 0.36 measured over 200 draws. Few lines (``n - b < 6 q``, femtools'
    cases) make ``S`` rank deficient and ``nu`` smaller: the test only grows more reluctant to keep the
    residual.

    References
    ----------
    .. [1] "Determination of rigid body characteristics from time domain modal test
       data", Journal of Sound and Vibration, 1994.
    """
    c0, c1 = float(np.sum(plain_rows**2)), float(np.sum(full_rows**2))
    half = full_rows.shape[0] // 2
    real = full_rows[:half]
    cov = real @ real.T / max(real.shape[1] - n_basis, 1)
    t1 = float(np.trace(cov))
    t2 = float(np.sum(cov * cov))
    tiny = np.finfo(float).tiny
    return (c0 - c1) / max(n_basis * t1, tiny), n_basis * t1**2 / max(t2, tiny)


def _residual_needed(plain: RigidFrfFit, full: RigidFrfFit, n_basis: int) -> bool:
    """Whether the exact fit keeps the upper residual: the F test asks for it, or it is cheap.

    Cheap: see :data:`UPPER_RESIDUAL_CHEAP`; parameter 0 of the fits is the mass. The F test: ``nu F``
    beyond the 0.1 % upper quantile of ``chi2(nu)`` (:func:`upper_residual_f`, :data:`UPPER_RESIDUAL_Z`).
    """
    if plain.misfit_rows is None or full.misfit_rows is None:
        return full.residual < plain.residual
    c0, c1 = float(np.sum(plain.misfit_rows**2)), float(np.sum(full.misfit_rows**2))
    if c1 < c0 and plain.covariance is not None and full.covariance is not None:
        widening = np.sqrt(full.covariance[0, 0] / max(plain.covariance[0, 0], np.finfo(float).tiny))
        if widening < UPPER_RESIDUAL_CHEAP:
            return True
    f_stat, dof = upper_residual_f(plain.misfit_rows, full.misfit_rows, n_basis)
    return bool(f_stat * dof > chi2_quantile(dof, UPPER_RESIDUAL_Z))


def _exact_verdict(fit: RigidFrfFit, origin: Array, span: float) -> tuple[float, str, BodyIntervals | None]:
    """The exact support fit's misfit in noise units, where it is worst, and its intervals.

    The misfit is the output-error fit's weighted misfit (:func:`~rigidid.core.frfstats.misfit_units`,
    its third differences along frequency give the noise); the intervals map the covariance of its ten
    inertial parameters to mass, CG and inertia (delta method).
    """
    if fit.misfit_rows is None or fit.covariance is None:
        return 1.0, "", None
    rows = fit.misfit_rows
    q = rows.shape[0] // 12
    units, per_row = misfit_units(rows, 1)  # 52 parameters over 12 q rows: about one per row
    per_col = np.sqrt(0.5 * (per_row[: 6 * q] ** 2 + per_row[6 * q :] ** 2)).reshape(6, q)
    i, j = np.unravel_index(int(np.argmax(per_col)), per_col.shape)
    names = ("x", "y", "z", "rx", "ry", "rz")
    where = f"rigid coordinate {names[i]} at the sensors, reference {j + 1} ({per_col[i, j]:.3g} noise units)"
    intervals = body_intervals(
        lambda theta: _body_from_parameters(theta, origin, span),
        fit.parameters,
        fit.covariance,
        "linearised: sandwich covariance of the output-error rigid-body fit, clustered per line and reference",
    )
    return units, where, intervals


def _correction_design(w: Array, extra: tuple[str, ...], elastic_frequency: float | None) -> Array:
    """Design matrix (real rows, then imaginary) of the mass line: a constant plus the `extra` corrections.

    Stiffness ``1/u^2``, damping ``i/u``, and the upper residual (``x/(1-x)`` and ``u^2`` below an elastic
    mode at `elastic_frequency`, else ``u^2`` and ``u^4``), with ``u`` the frequency over the band's centre.
    """
    u = w / float(np.sqrt(w[0] * w[-1]))
    cols_re = [np.ones_like(u)]
    cols_im = [np.zeros_like(u)]
    for name in extra:
        if name == "stiffness":
            cols_re.append(1.0 / u**2)
            cols_im.append(np.zeros_like(u))
        elif name == "damping":
            cols_re.append(np.zeros_like(u))
            cols_im.append(1.0 / u)
        elif elastic_frequency is not None:
            x = (w / (2.0 * np.pi * elastic_frequency)) ** 2
            cols_re.extend([x / (1.0 - x), u**2])
            cols_im.extend([np.zeros_like(u), np.zeros_like(u)])
        else:
            cols_re.extend([u**2, u**4])
            cols_im.extend([np.zeros_like(u), np.zeros_like(u)])
    design: Array = np.concatenate([np.stack(cols_re, axis=1), np.stack(cols_im, axis=1)])
    return design


def _first_order_misfit(misfit: Array, n_params: int, q: int) -> tuple[float, str]:
    """The first-order fit's misfit in noise units (:func:`~rigidid.core.frfstats.misfit_units`), where worst."""
    n_f = misfit.shape[0] // 2
    rows = np.concatenate([misfit[:n_f].T, misfit[n_f:].T])  # (12 q, f): real parts, then imaginary parts
    units, per_row = misfit_units(rows, max(n_params // 2, 1))
    per_col = np.sqrt(0.5 * (per_row[: 6 * q] ** 2 + per_row[6 * q :] ** 2)).reshape(6, q)
    i, j = np.unravel_index(int(np.argmax(per_col)), per_col.shape)
    names = ("x", "y", "z", "rx", "ry", "rz")
    return units, f"rigid coordinate {names[i]}, reference {j + 1} ({per_col[i, j]:.3g} noise units)"


NOISE_WINDOW = 0.0625
"""Half-width, as a share of the band's lines, of the window over which :func:`_first_order_intervals`
averages the misfit's outer products to estimate each line's noise covariance (an eighth of the band). Wider
windows steady the standard errors further where the noise is even along the band, but at the band's ends the
window is one-sided, and that is where the constant's weights sit: with the noise 25x higher at the band's low
end than at its top, free-free coverage was 0.895 with 1/8, 0.911 with 1/16, 0.921 with 1/32 (0.910 with each
row alone); with even noise 0.945, 0.943, 0.942 over 1000 draws (0.939 each row alone, 0.945 the true noise's)."""


def _first_order_intervals(
    design: Array, misfit: Array, y0: Array, tf: Array, origin: Array, span: float
) -> BodyIntervals:
    """Linearised intervals of the first-order mass line: sandwich covariance of its constants ``y0``.

    `design` and `misfit` are the weighted fit's (:func:`_level_weighted`: rows divided by their noise level's
    square root), so ``a`` below weighs the whitened rows and ``S_l`` is the whitened noise, about ``Sigma``.
    The constants are ``a^T Y`` (``a`` the design pseudo-inverse's first row), so their covariance is
    ``V = sum_l a_l^2 S_l`` over the data rows ``l``, ``S_l`` the noise covariance of row ``l``'s ``6 q``
    columns (correlated through the sensors, so all of them together), estimated by :func:`_line_noise`.
    A per-row sandwich (``S_l = e_l e_l^T`` alone) is unbiased but noisy: the weights ``a_l^2`` sit on
    the band's ends (``1 / w^2`` and ``w^4`` largest there), about 45 rows of 121 carry them, so the
    standard error varied by 11 % between draws and ``z`` followed a Student ``t`` of about 45 degrees of
    freedom (95 % coverage 0.944 with ``1.96``; free-free draws of benchmarks/frf_coverage.py, issue 21).
    A single ``S`` pooled over the band is steadier but wrong where the noise varies along it (noise
    rising 25x over the band: coverage 0.971, RMS ``z`` 0.90). The delta method's linearisation holds: the
    map from ``y0`` to mass, CG and inertia left a second-order part of 0.02-0.06 SE RMS (0.6 at most) over
    200 draws, and with the true noise's covariance (benchmarks/frf_free_oracle.py) the SEs are the same.
    """
    a = np.linalg.pinv(design)[0]  # the constant of every column is a^T (its column of the target)
    cov = _line_noise(design, misfit, a)
    return body_intervals(
        lambda y: _body_from_inverse_mass(y, tf, origin, span),
        y0,
        cov,
        "linearised: the mass line weighted by each line's noise level, sandwich covariance of its constants, the "
        "noise averaged over neighbouring lines",
    )


def _line_noise(design: Array, misfit: Array, a: Array) -> Array:
    """``sum_l a_l^2 S_l`` (:func:`_first_order_intervals`) with each line's noise ``S_l`` averaged over its neighbours.

    Each row's misfit is divided by ``1 - h_l``, ``h_l`` its leverage (HC3; HC2's ``sqrt(1 - h_l)`` makes
    ``e_l e_l^T / (1 - h_l)`` unbiased for ``S_l`` only where the noise is even: where it is not, the fit
    spreads the noisy lines' noise into the quiet lines' misfit and takes it from the noisy, high-leverage
    end lines', where the constant's weights sit). The misfit's level ``r_l`` along the band
    (:func:`_line_level`) is divided out before the window's mean and put back after it, ``S_l = r_l x`` the mean
    of ``e_k e_k^T / r_k``: the window then averages a noise of even level, also where it is one-sided (at the
    band's ends the mean of a steep level was 20 % low). With the noise 25x higher at the band's low end
    (benchmarks/frf_coverage.py ``free_slope_low``, ``supports="first_order"``, 1000 draws) the pooled coverage
    was 0.904 (RMS ``z`` 1.176) with HC2 and no level, 0.920 with the level, 0.928 (1.078) with both; 0.940,
    0.942 with the noise 25x higher at the top; 0.943 (1.028), 0.943, 0.947 (1.013) with even noise. ``S_l``
    is the mean of these over the lines within :data:`NOISE_WINDOW` of the band's lines of
    line ``l``, real and imaginary parts together (FRF noise is circular: both parts carry half of the
    complex covariance, the same matrix; the rows are stacked real parts of the lines, then imaginary).
    Unbiased wherever the noise is constant over a window, and it varies smoothly along frequency (it
    follows the force spectrum and the response); the estimate then rests on several times more rows than
    a per-row sandwich. ``sum_l a_l^2 S_l = sum_k b_k e_k e_k^T / r_k`` with ``b_k`` the window sum of
    ``a_l^2 r_l / (2 n_l)`` (``n_l`` lines in line ``l``'s window), one pass.
    """
    n_f = design.shape[0] // 2
    level = _line_level(design, misfit)
    e = misfit / (1.0 - _leverage(design))[:, None] / np.sqrt(level)[:, None]
    count = _window_sum(np.ones(n_f), NOISE_WINDOW)  # lines in each line's window
    share = _window_sum((a[:n_f] ** 2 + a[n_f:] ** 2) * level[:n_f] / (2.0 * count), NOISE_WINDOW)  # b_k
    cov: Array = (e[:n_f] * share[:, None]).T @ e[:n_f] + (e[n_f:] * share[:, None]).T @ e[n_f:]
    return cov


def _support_model(supports: str, stiffness: bool) -> tuple[str, str]:
    """The mount model :func:`mass_line` uses, and why."""
    if supports not in ("auto", "exact", "first_order"):
        raise InputError(f"supports must be 'auto', 'exact' or 'first_order', got {supports!r}")
    if not stiffness:
        return "none", "no stiffness correction asked for: the mounts are neglected"
    if supports == "first_order":
        return "first_order", "first-order mount correction asked for"
    if supports == "exact":
        return "exact", "exact rigid-body fit of M, K and C asked for"
    return "auto", ""


EXACT_LINES = 300
"""At most this many lines (every k-th of the band) go into the exact rigid-body fit of
:func:`mass_line` (with six references and 2000 lines it took 17 s; 300 lines suffice for noise-free
data, and on noisy data the exact fit is only taken when the first-order one misfits)."""

AUTO_LACK_OF_FIT = 1.1
"""``supports="auto"`` takes the exact rigid-body fit unless its misfit exceeds the first-order
fit's by this factor (in RMS). Before issue 21 it was the other way round (the first-order
correction unless its own misfit exceeded the noise by this factor), as the exact fit was then an
equation-error fit, biased on noisy FRFs (median mass error 36 % on mounts at 1 % noise). By output
error it is unbiased, and the first-order correction is not: on bodies on mounts measured from 1.5x
their highest support mode (benchmarks/frf_coverage.py, mounted) its inertia came out 10-20 of its
own standard errors off while its misfit was 1.00-1.05 noise units, so a misfit test cannot guard it."""


def _noise_residual(misfit: Array, target: Array, n_params: int) -> float:
    """The relative misfit the first-order fit would have if it were adequate (noise alone).

    The noise is estimated from the third differences along frequency of the fit's own
    misfit (``misfit``: ``(2 f, 6 q)``, real parts of the lines then imaginary parts): white
    noise of variance ``s^2`` gives ``20 s^2``, while a misfit the model leaves because it
    is wrong varies smoothly with frequency and almost vanishes in the differences. Scaled
    to :func:`mass_line`'s relative RMS residual with the fit's degrees of freedom. The
    mean of the squares, as the residual is an RMS over lines of different noise.
    """
    n_f = misfit.shape[0] // 2
    if n_f < 4:
        return 0.0
    d3 = np.concatenate([np.diff(misfit[:n_f], n=3, axis=0), np.diff(misfit[n_f:], n=3, axis=0)])
    var = float(np.mean(d3**2)) / 20.0  # per real value
    dof = max(1.0 - n_params / misfit.shape[0], 0.0)
    return float(np.sqrt(var * dof) / np.sqrt(np.mean(target**2)))


SUPPORTS_SEEN = 5.0
"""``supports="auto"`` takes the first-order mass line when its support terms (``E / w^2``, ``i G / w``) are
within this many standard deviations of what noise alone gives (:func:`_supports_seen`), else the exact
rigid-body fit (issue 21). Where the supports are not seen, ``K`` and ``C`` are unidentified: the exact fit's
output-error cost is flat along them (only ``M^-1 K M^-1 T_f^T`` is seen to first order, and not even that
above the noise), the fit is strongly nonlinear in them and its linearised standard errors are not the spread
(free-free bodies of benchmarks/frf_coverage.py, one body and 60 noise draws: the spread 1.33 times the mean
SE, RMS z 1.26, the SE itself varying by 52 % between draws, one draw's 140 times the others'); and it needs
the choice of the upper residual, which it cannot make reliably there (:func:`_residual_needed`: draw 194, 4.7
SE off). The first-order fit is linear (its SE was the spread within 0.86-1.14 on six free-free bodies x 100
draws), always fits the upper residual, and the terms it leaves out are the support terms times their own
relative size: below the noise when the first-order ones are. Measured ``F``: free-free bodies (supports 0.1
Hz under a 30-150 Hz band) mean 1.03, SD 0.26 (theory 0.24), largest 2.05 over 1000 draws (before the Hotelling
factor of :func:`_supports_seen`: mean 1.11, and 2 draws above the threshold); mounted bodies from 1.5x their
highest support mode 2000-2400; the threshold for 36 coefficients is 2.18."""


def _supports_seen(design: Array, coef: Array, misfit: Array, n_terms: int) -> float | None:
    """Whether the first-order fit's support terms stand out of the noise; None where they do not.

    Returns :func:`_supports_f`'s ``F`` when it is below ``1 +`` :data:`SUPPORTS_SEEN` ``sqrt(2 / p)`` (``p`` the
    number of support coefficients: the standard deviation of ``F`` under noise alone), else None; None also with
    fewer rows than ``2 p + k`` (femtools' 21 lines and 6 references: the exact fit is taken, as before).
    """
    f_stat = _supports_f(design, coef, misfit, n_terms)
    if f_stat is None:
        return None
    return f_stat if f_stat < 1.0 + SUPPORTS_SEEN * np.sqrt(2.0 / (n_terms * misfit.shape[1])) else None


LEVEL_WINDOW = 0.125
"""Half-width, as a share of the band's lines, of the window of :func:`_line_level`'s straight line (in ``log``
level): twice :data:`NOISE_WINDOW`, as a straight line follows a log-linear level over any window and the
wider one steadies it. Under noise alone ``F`` averaged 1.050 with 1/16, 1.035 with 1/8, 1.031 with 1/4 (60
lines, even noise, 200 draws); 0.99-1.00 with the noise falling 25x along 121 lines, and on free-free bodies
(benchmarks/frf_coverage.py, 40 draws) 1.10, 1.09, 1.01 (``free_slope_low``, ``free_slope_high``, ``free``)
whatever the width."""

LEVEL_PASSES = 3
"""Passes of :func:`_supports_f`'s level estimate, each from the misfit of the fit weighted by the last."""


def _supports_f(design: Array, coef: Array, misfit: Array, n_terms: int) -> float | None:
    """The Hotelling ``F`` of the first-order fit's support terms, each line whitened by its own noise level.

    The terms are rows ``1 .. n_terms`` of the coefficients (``p = n_terms x 6 q`` of them, ``b``). The noise of
    a line's ``6 q`` columns is modelled ``S_l = s_l^2 Sigma``: a shape ``Sigma`` common to the band (the columns
    correlated through the sensors) times a level ``s_l^2`` that varies along it, estimated over windows of
    neighbouring lines as the intervals' :func:`_line_noise` estimates ``S_l`` (:func:`_line_level`). Each data
    row is divided by ``s_l`` and the fit is redone on the whitened rows (design ``X_w``, data ``Y_w``: weighted
    least squares), whose noise is then ``Sigma`` on every row. The level is estimated again from the weighted
    fit's misfit, :data:`LEVEL_PASSES` times: the unweighted fit spreads the noisy lines' noise into the quiet
    lines' misfit (through the constant and the end-weighted terms), which flattens the level (at the noisy end
    0.38 of the true one after one pass, relative to the band's middle; ``F`` averaged 1.31 and 0.72 on
    ``free_slope_low`` and ``free_slope_high``, 1.10 and 1.09 after three, 1.17 and 1.07 with the true level).
    Its support coefficients ``b = A Y_w`` (``A`` rows
    ``1 .. n_terms`` of ``X_w``'s pseudo-inverse) have covariance ``V = (A A^T) kron Sigma``; ``Sigma`` is
    estimated by ``S = E_w^T E_w / nu`` from the whitened misfit, ``nu = N - k`` degrees of freedom over the
    ``N`` real rows. Under pure noise ``b`` is independent of ``S`` (the misfit is orthogonal to the fit) and
    ``S`` is a Wishart matrix of ``nu`` degrees of freedom in ``d = 6 q`` dimensions, ``E[S^-1] = nu / (nu - d -
    1) Sigma^-1``: ``F = (nu - d - 1) / nu x b^T V^-1 b / p`` (a Hotelling statistic) has mean 1 and standard
    deviation about ``sqrt(2 / p)``. The level ``s_l^2`` rests on the window's ``d`` x (its rows) squared
    whitened values (several hundred), so its own error (a few %) is left out: it raised the mean of ``F`` by
    0.035 on 60 lines (:data:`LEVEL_WINDOW`).

    Why the level: one ``S`` over the band (as before) reads lines noisier than the band's average as support
    terms (``1 / w^2`` weighs the lowest lines): with the noise 25x higher at the band's low end than at its top,
    ``F`` averaged 4.8 and 39 of 40 free-free draws went to the exact fit, whose standard errors are not its
    spread there (see :data:`SUPPORTS_SEEN`; benchmarks/frf_coverage.py ``free_slope_low``, issue 21); with the
    noise 25x higher at the top ``F`` averaged 0.37, a test that could not see supports. Why not each line's full
    ``S_l``: the ``18 x 18`` covariance of 3 references from the window's 18-34 rows is singular at the band's
    ends, where the stiffness term's weights sit (the row sandwich inflated ``F`` to 2-3.7 on free-free bodies).
    (Without the Hotelling factor, about 0.92 for 121 lines and 3 references, the null mean was 1.11.)

    Measured over 200 free-free draws (benchmarks/frf_coverage.py's bodies; threshold 2.18): ``free`` mean 1.01,
    SD 0.26, largest 1.94 (0.99, 0.25, 1.82 before); ``free_slope_low`` 1.08, 0.27, 1 draw above (4.79 and 199
    above before); ``free_slope_high`` 1.13, 0.34, 2 above (0.36 before). Those above are signal, not the
    test: the suspension's damping term (``2 zeta w_s / w``, about 1e-4 of the mass line) shows where the band's
    low end is quiet; with the mounts' damping or stiffness zeroed in the simulation the same draws give 0.7-1.7.
    Mounted bodies (20 draws): 1400-2800 (1600-3800 before).
    """
    n_rows, k = design.shape
    cols = slice(1, 1 + n_terms)
    nu, d = n_rows - k, misfit.shape[1]
    p = n_terms * d
    if n_rows < 2 * p + k:
        return None
    x_w, coef_w, e_w = _level_weighted(design, design @ coef - misfit, misfit)  # misfit: fitted minus data
    b = coef_w[cols].reshape(-1)
    a = np.linalg.pinv(x_w)[cols]  # (n_terms, N)
    noise = e_w.T @ e_w / nu  # (6 q, 6 q): Sigma, the columns correlated through the sensors
    v = np.kron(a @ a.T, noise)
    return float((nu - d - 1) / nu * float(b @ np.linalg.lstsq(v, b, rcond=None)[0]) / p)


def _level_weighted(design: Array, target: Array, misfit: Array) -> tuple[Array, Array, Array]:
    """The fit weighted by each line's noise level (feasible generalised least squares), the level from the misfit.

    Parameters
    ----------
    design : ndarray, shape (N, k)
        The mass line's design (real rows, then imaginary: :func:`_correction_design`).
    target : ndarray, shape (N, 6 q)
        Its data (rigid coordinates per unit force, real parts then imaginary).
    misfit : ndarray, shape (N, 6 q)
        The unweighted fit's misfit (either sign).

    Returns
    -------
    x_w : ndarray, shape (N, k)
        The design with each row divided by ``s_l``, the level's square root (:func:`_line_level`).
    coef_w : ndarray, shape (k, 6 q)
        The weighted fit's coefficients: ``min sum_l |y_l - x_l c|^2 / s_l^2``.
    e_w : ndarray, shape (N, 6 q)
        Its whitened misfit, data minus fit: about ``Sigma`` on every row when the level model holds.

    Notes
    -----
    Why weight: the noise of line ``l``'s ``6 q`` columns is ``S_l = s_l^2 Sigma`` (:func:`_supports_f`), every
    column with the same design ``X``, so the noise of all columns together is ``Sigma kron diag(s^2)``. For
    that covariance and a design common to the columns, generalised least squares (Aitken's best linear unbiased
    estimate) is each column's least squares with weights ``1 / s_l^2``: the coefficients' covariance is
    ``(X^T W X)^-1 kron Sigma``, no larger than the unweighted fit's ``(X^+ diag(s^2) X^+T) kron Sigma``, and
    equal to it only where the level is even. On free-free bodies whose noise is 25x higher at one end of the
    band (benchmarks/frf_free_weighted.py, 200 draws per regime) the mass line's constants weighted so had 0.33-
    0.47 times the unweighted fit's RMS error in mass, CG and inertia, within 2 % of the fit weighted by the true
    level; with even noise 0.99-1.01 times. The unweighted fit's intervals had also been 8 % narrow there
    (coverage 0.92): its end lines, where the constant's weights sit, are the noisy ones, and their noise was
    read from one-sided windows; weighted, the whitened noise is even and those windows read it right. Coverage
    of the 95 % intervals pooled over mass, CG and inertia diagonal on draws not looked at while building this
    (benchmarks/frf_coverage.py, seeds 2000 up): 0.951 (400 draws, RMS ``z`` 0.985) with the noise 25x higher
    at the low end, 0.956 (0.963) at the top, 0.950 (0.996, 1000 draws) with even noise; each figure 0.927-0.965.

    The level is estimated :data:`LEVEL_PASSES` times, each from the misfit of the fit weighted by the last
    (see :func:`_supports_f`, which tests the support terms of this fit). The level rests on several hundred
    squared whitened values per line (a window of lines x ``6 q`` columns), so its error is a few % and the
    weights' cost in efficiency is of second order in it.
    """
    level, e_w = np.ones(design.shape[0]), misfit
    x_w: Array = design
    coef_w: Array = np.zeros((design.shape[1], target.shape[1]))
    for _ in range(LEVEL_PASSES):
        level = level * _line_level(x_w, e_w)
        x_w, y_w = design / np.sqrt(level)[:, None], target / np.sqrt(level)[:, None]
        coef_w = np.asarray(np.linalg.lstsq(x_w, y_w, rcond=None)[0], dtype=float)
        e_w = y_w - x_w @ coef_w
    return x_w, coef_w, e_w


def _line_level(design: Array, misfit: Array) -> Array:
    """Each data row's noise level ``s_l^2`` (:func:`_supports_f`), up to a common factor, from its neighbours.

    Each row's misfit ``e_l``, leverage-corrected as in :func:`_line_noise`, gives ``r_l = e_l^T S_0^-1 e_l``
    (``S_0`` the band's pooled covariance), which scatters about ``s_l^2`` times a constant. The level of line
    ``l`` is ``exp`` of a straight line fitted to ``log r`` (real and imaginary rows together) over the lines
    within :data:`LEVEL_WINDOW` of the band's lines of ``l``, evaluated at ``l``: exact for a noise whose level
    is log-linear in frequency over a window, also at the band's ends, where
    the window is one-sided and where the stiffness term's weights sit (a window's mean there was 20 % below the
    end line's level with the noise 25x higher at the low end, and ``F`` averaged 1.5). The mean of ``log
    chi^2`` is the same on every line, so its offset is a common factor, which cancels in ``F``. Returned per row
    (real rows, then imaginary).
    """
    n_f = design.shape[0] // 2
    e = misfit / np.sqrt(1.0 - _leverage(design))[:, None]
    pooled = e.T @ e / e.shape[0]
    r = np.sum(e * np.linalg.lstsq(pooled, e.T, rcond=None)[0].T, axis=1)
    g = np.log(np.maximum(r[:n_f] + r[n_f:], np.finfo(float).tiny))  # per line
    k = np.arange(n_f, dtype=float)
    s0, sk, skk, sy, sky = (_window_sum(v, LEVEL_WINDOW) for v in (np.ones(n_f), k, k * k, g, k * g))
    s1, s2, sxy = sk - k * s0, skk - 2.0 * k * sk + k * k * s0, sky - k * sy  # sums of (j - l), (j - l)^2, ...
    level = np.exp((s2 * sy - s1 * sxy) / (s0 * s2 - s1 * s1))
    return np.concatenate([level, level])


def _window_sum(values: Array, half_width: float) -> Array:
    """Each line's sum of `values` over the lines within `half_width` (a share of the band's lines, at least
    one line) on each side of it; one-sided at the band's ends."""
    box = np.ones(2 * max(1, round(half_width * values.size)) + 1)
    out: Array = np.convolve(values, box, mode="same")
    return out


def _leverage(design: Array) -> Array:
    """The diagonal of the hat matrix per data row, at most 0.99."""
    q_design = np.linalg.qr(design)[0]
    lev: Array = np.minimum(np.sum(q_design**2, axis=1), 0.99)
    return lev


def _unseen_supports(design: Array, coef: Array, misfit: Array, n_terms: int) -> str:
    """Why ``supports="auto"`` takes the first-order fit (:func:`_supports_seen`); empty where the supports are seen."""
    f_stat = _supports_seen(design, coef, misfit, n_terms)
    if f_stat is None:
        return ""
    return (
        f"the supports are not seen in the band (their first-order terms {f_stat:.3g} times the noise's share, "
        f"below {1.0 + SUPPORTS_SEEN * np.sqrt(2.0 / coef[1 : 1 + n_terms].size):.3g}): the first-order mass line, "
        "linear in the FRFs, its upper residual always fitted"
    )


def _auto_supports(
    fit: RigidFrfFit | None, first_order_residual: float, noise_residual: float = 0.0
) -> tuple[str, str]:
    """Choose the mount model: the exact fit where it is determined and fits as well (see :data:`AUTO_LACK_OF_FIT`)."""
    tiny = np.finfo(float).tiny
    units = first_order_residual / max(noise_residual, tiny)
    if fit is None:
        return "first_order", "the exact rigid-body fit is not determined by these lines: first-order mount correction"
    exact_units = fit.residual / max(noise_residual, tiny)
    if fit.residual > AUTO_LACK_OF_FIT * first_order_residual:
        return "first_order", (
            f"the exact rigid-body fit of M, K and C misfits the band by {exact_units:.3g} times the noise, the "
            f"first-order mount correction by {units:.3g}: first-order mount correction"
        )
    return "exact", (
        f"the exact rigid-body fit of M, K and C misfits the band by {exact_units:.3g} times the noise "
        f"({fit.residual:.2g}), the first-order mount correction by {units:.3g} ({first_order_residual:.2g}): "
        "the exact fit holds whatever the supports, the first-order one leaves a bias even where its misfit "
        "hides in the noise"
    )


def _body_from_parameters(theta: Array, origin: Array, span: float) -> tuple[float, Array, Array]:
    """Mass, CG and inertia about the CG from the ten parameters of ``M`` in the scaled frame."""
    m = float(theta[0])
    c_scaled = theta[1:4] / m
    j_o = mass_matrix_from_parameters(theta)[3:, 3:]
    inertia = span**2 * (j_o + m * skew(c_scaled) @ skew(c_scaled))
    return m, origin + span * c_scaled, 0.5 * (inertia + inertia.T)


def _supports_at_cg(fit: RigidFrfFit, cg_offset: Array, span: float) -> tuple[Array, Array]:
    """The exact fit's ``K`` and ``C`` about the CG in layout lengths, from the scaled frame.

    The scaled coordinates are ``(x_o, span theta)`` at the sensor centroid ``o``, so ``K_o = S K_s S``
    with ``S = diag(1, 1, 1, span, span, span)``; about the CG ``x_o = x_cg - [o - cg]x theta``, so
    ``K_cg = A^T K_o A`` with ``A = [[I, [cg - o]x], [0, I]]`` (eq. (2) of [1]; the same for ``C``).
    """
    s = np.diag([1.0, 1.0, 1.0, span, span, span])
    a = np.eye(6)
    a[:3, 3:] = skew(cg_offset)
    k, c = (a.T @ s @ mat @ s @ a for mat in (fit.stiffness, fit.damping))
    return 0.5 * (k + k.T), 0.5 * (c + c.T)


RESIDUES_BAND_RATIO = 1.2
"""The residues route's band must reach this factor above the highest rigid-body mode (its resonance
and the fall beyond it). It was 2 before issue 21; on the regime matrix's bands ending at 1.5x and 2x
the highest mode (benchmarks/frf_regimes.py top1.5x, top2x) the residues are as accurate as with a
band to 4x."""


def mass_from_residues(
    frequencies: ArrayLike,
    frf: ArrayLike,
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
    poles: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
    weighting: str = "noise",
) -> MassLine:
    """Mass, CG and inertia from scaled rigid-body modes: residues fitted with known poles.

    Parameters
    ----------
    frequencies, frf, positions, directions, reference_positions, reference_directions
        As :func:`mass_line`.
    poles : array_like of complex, shape (6,)
        The six rigid-body poles (rad/s, ``Im > 0``), e.g. from ``modes.csv``.
    band : (float, float), optional
        Band (Hz) of the fit: it must hold the rigid-body modes and lie below the
        first elastic mode. Default: from the lowest line to half the first
        elastic peak (:func:`auto_band`), or the last line.
    weighting : {"noise", "relative", "none"}
        ``"noise"`` (default): every value weighted by the inverse of its noise level,
        found from the misfit of its neighbouring lines
        (:func:`rigidid.core.frfmodes.residue_limit`); ``"relative"`` by ``1 / |H|`` (right
        only for noise proportional to the FRF: with a noise floor it weights the
        anti-resonances by their noise, benchmarks/frf_regimes.py); ``"none"``: unweighted.

    Returns
    -------
    MassLine
        ``band_source`` as for :func:`mass_line`; ``corrections`` is
        ``("residues", "upper_residual")``.

    Notes
    -----
    The receptance is ``sum_k R_k / (i w - l_k) + conj``; the residues ``R_k``
    (``p x q``, complex, the scaled shapes times their participations) are fitted
    by linear least squares to the accelerance ``-w^2 x receptance`` with an
    upper residual (``w^2``, ``w^4``), every value weighted by its noise level
    found from the misfit (``1 / |H|`` was the default before issue 21: right for
    noise proportional to the FRF, but with a noise floor it weighted the
    anti-resonances by their noise, mass off by up to 13 % at exit 0), the poles
    refined on the weighted FRFs (:func:`rigidid.core.frfmodes.residue_limit`).
    The intervals (``intervals``) are linearised: the limit's variance from the
    misfit, plus the poles' propagated. The high-frequency limit of the model,
    ``sum_k 2 Re(l_k R_k) = T M^-1 T_f^T``, then gives the body as the mass
    line does, but from every line of the band including the resonances.
    """
    f = np.asarray(frequencies, dtype=float).reshape(-1)
    h = np.asarray(frf, dtype=complex)
    pos = np.asarray(positions, dtype=float)
    dirs = np.asarray(directions, dtype=float)
    rpos = np.asarray(reference_positions, dtype=float)
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    p, q = pos.shape[0], rpos.shape[0]
    if h.shape != (p, q, f.size):
        raise InputError(f"frf must have shape (sensors, references, frequencies) = {(p, q, f.size)}, got {h.shape}")
    if lam.size != 6 or np.any(lam.imag <= 0.0):
        raise InputError("poles must be the six rigid-body poles with positive imaginary parts")
    band_source = "given"
    if band is None:
        band_source = "automatic"
        try:
            _, elastic = _auto_band(f, h)
        except IdentificationError:
            elastic = None
        band = (float(f[0]), 0.5 * elastic if elastic is not None else float(f[-1]))
    lo, hi = float(band[0]), float(band[1])
    sel = (f >= lo) & (f <= hi)
    n_f = int(np.count_nonzero(sel))
    if n_f < 3 * MIN_LINES:
        raise InputError(f"band {lo:g}-{hi:g} Hz holds {n_f} frequency lines, need at least {3 * MIN_LINES}")
    top = float(np.abs(lam).max()) / (2.0 * np.pi)
    if hi < RESIDUES_BAND_RATIO * top:
        raise IdentificationError(
            f"the band ends at {hi:.4g} Hz, {hi / top:.2g}x the highest rigid-body mode ({top:.4g} Hz): the residues "
            f"need it to reach {RESIDUES_BAND_RATIO:g}x, past that mode's resonance"
        )
    origin, span, t = scaled_frame(pos, dirs)
    tf = sensor_matrix((rpos - origin) / span, np.asarray(reference_directions, dtype=float))
    fit = residue_limit(f, h, lam, band=(lo, hi), upper=2, weighting=weighting)
    t_pinv = np.linalg.pinv(t)  # (6, p)
    y0 = t_pinv @ fit.limit  # M^-1 T_f^T in the scaled frame
    m, cg, inertia = _body_from_inverse_mass(y0, tf, origin, span)
    # y0[:, j] = T^+ limit[:, j]: independent columns, cov T^+ diag(var_j) T^+^T
    cov = np.zeros((6, q, 6, q))
    for j in range(q):
        cov[:, j, :, j] = (t_pinv * fit.variance[:, j]) @ t_pinv.T
    if fit.limit_jacobian.shape[2]:  # the poles' uncertainty, correlated across the FRFs
        gy = np.einsum("is,sjn->ijn", t_pinv, fit.limit_jacobian).reshape(6 * q, -1)
        cov = cov + (gy @ fit.pole_covariance @ gy.T).reshape(6, q, 6, q)
    intervals = body_intervals(
        lambda y: _body_from_inverse_mass(y, tf, origin, span),
        y0,
        cov.reshape(6 * q, 6 * q),
        "linearised: variance of the residues' high-frequency limit from the weighted misfit, poles refined and their "
        "variance propagated",
    )
    return MassLine(
        mass=m,
        center_of_gravity=cg,
        inertia_tensor=inertia,
        band=(lo, hi),
        band_source=band_source,
        frequencies_used=n_f,
        residual=fit.residual,
        corrections=("residues", "upper_residual"),
        intervals=intervals,
        misfit_noise_units=fit.misfit_units,
        misfit_where=f"response {fit.worst[0] + 1}, reference {fit.worst[1] + 1} ({fit.worst_units:.3g} noise units)",
        peak_shortfall=fit.peak_shortfall,
    )
