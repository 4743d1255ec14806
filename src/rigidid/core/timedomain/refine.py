"""Output-error (maximum-likelihood) refinement of the rigid body on the impact records.

The body's physical parameters (CG, J/m, K/m, C/m) are fitted directly to the
free decays of every impact: the 12x12 state matrix of eq. (19) of [1] gives
the poles and the acceleration shapes at the sensors; each impact's complex
modal amplitudes and channel offsets enter linearly and are solved inside the
residual (variable projection); every channel is weighted by its noise level;
the Jacobian is analytic (eigenvalue and eigenvector derivatives). The
Cramér-Rao bound of every parameter follows from the same Jacobian.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import layout_frame, normalise_directions, sensor_matrix
from rigidid.core.linalg import pseudo_inverse, svd
from rigidid.core.optimize import levenberg_marquardt
from rigidid.core.statespace import modal_from_poles
from rigidid.core.timedomain.acceptance import MisfitTest, budgeted_misfit_test, misfit_test
from rigidid.core.timedomain.chain import ChainModel, ChannelChain
from rigidid.core.timedomain.coupling import CouplingScore, coupling_score, modal_gram
from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH, decimate, fir_taps
from rigidid.core.timedomain.pretrigger import PRE_HELD, band_noise
from rigidid.core.timedomain.sensor_test import TESTED_OUTPUTS, SensorTest, body_change_test, noise_inflation
from rigidid.errors import InputError

__all__ = [
    "MAX_ROWS",
    "N_PARAMETERS",
    "PreparedDecays",
    "RecordBound",
    "Refinement",
    "SensorCorrection",
    "SensorTerms",
    "columns_of",
    "cut_decays",
    "delay_step",
    "fit_factor",
    "good_fit",
    "prepare_decays",
    "pretrigger_sigma",
    "record_bound",
    "refine_body",
    "refine_prepared",
    "sensor_terms",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

N_PARAMETERS = 51
"""CG (3), Cholesky factors of J/m (6), K/m (21) and C/m (21)."""

MAX_ROWS = 150_000
"""Largest number of residuals (samples x channels over all impacts) fitted; longer
records are cut (the end of a decay holds the least signal)."""

_TRIL3 = np.tril_indices(3)
_TRIL6 = np.tril_indices(6)
_MIN_PRETRIGGER = 32  # samples of pre-trigger needed to take the noise level from it
_Z95 = 1.959963984540054
_GOOD_COST = 2.0  # normalised cost 2 cost / n_residuals above this: a bad fit (about 1 at a good one)
_DECREMENT = 0.05  # converged: Gauss-Newton decrement below this many residual variances
_STALL = 1e-4  # converged at a bound of J, K, C > 0: a step lowers the cost by less (in variances)
_STALL_DECREMENT = 4.0  # ... while the Gauss-Newton step, out of reach, is below 2 standard errors
_GOLUB_PEREYRA = False  # the full variable-projection Jacobian (measured: benchmarks/refine_diagnose.py)
_PILOT = 30  # residual evaluations of the pilot fit whose residual gives the noise levels when hum is found
_DELAY_SKIP = 2  # samples (at the fit's rate) dropped from each decay when the delays are fitted
_GEODESIC_H = 0.1  # step fraction of the central difference for the second directional derivative


@dataclass(frozen=True)
class Refinement:
    """The body fitted to the records, its Cramér-Rao bound and how the fit went.

    Attributes
    ----------
    center_of_gravity : ndarray, shape (3,)
        CG in the layout's axes (length).
    inertia_per_mass : ndarray, shape (3, 3)
        Inertia tensor about the CG over mass (length^2).
    stiffness_per_mass, damping_per_mass : ndarray, shape (6, 6)
        Support stiffness and damping at the CG over mass, DOF order x, y, z,
        rx, ry, rz.
    poles : ndarray of complex, shape (6,)
        Poles of the fitted model (rad/s), ascending frequency.
    std : dict of str to ndarray
        Standard errors at the estimate (the Cramér-Rao bound made robust: sandwich
        covariance of :mod:`rigidid.core.timedomain.intervals`), same keys and shapes as the
        values: ``"center_of_gravity"``, ``"inertia_per_mass"``,
        ``"stiffness_per_mass"``, ``"damping_per_mass"``, ``"frequency_hz"``,
        ``"damping_ratio"``.
    normalised_cost : float
        ``2 cost / n_residuals`` in noise-weighted units: about 1 at a good fit
        when the noise levels come from the pre-trigger.
    noise_from : str
        ``"pretrigger"`` or ``"residual"``: where the channel noise levels came from.
    residuals : int
        Number of residuals fitted.
    evaluations : int
        Residual evaluations of the optimiser.
    converged : bool
        Whether the optimiser met its convergence test (Gauss-Newton decrement below
        0.05 residual variances or below the rounding floor of the data, or the cost
        stalled at the boundary of positive definite J, K, C with the decrement below 4)
        rather than stopping at its evaluation budget; False when the start was only
        evaluated.
    misfit : MisfitTest or None
        The acceptance test of the residual against the pre-trigger.
    delays, delays_std : ndarray, shape (p,), or None
        With ``estimate_delays``: each channel's delay (s) beyond the stated chain's,
        relative to the reference channel (0 there), and its standard error.
    delay_score : ndarray, shape (2, p), or None
        Without ``estimate_delays``, when the fit was not accepted (with the sensors corrected, always, the
        sensors freed with the delays; kept when the correction is dropped, :func:`_plain_kept`): the one Gauss-Newton
        step's delay of each channel (s) and its z score (delay over standard error), the
        test for an unmodelled skew (:func:`delay_step`).
    hum : tuple of (float, float, float)
        Mains hum found in the start's residual and modelled (nuisance sinusoids per channel and
        impact): frequency (Hz), z score and RMS amplitude in noise standard deviations
        (:func:`rigidid.core.timedomain.hum.find_hum`).
        The acceptance test (:mod:`rigidid.core.timedomain.acceptance`).
    sensor_std : dict or None
        With stated sensor tolerances: per type-B source (:data:`rigidid.core.sensor_budget.SOURCES`),
        the refit's own std of each physical value (keys as `std`) from the sensors' errors.
    sensor_correction : SensorCorrection or None
        With ``estimate_sensors``: the sensors' errors estimated with the body (which the
        body's values and ``sensor_std`` then account for).
    sensor_test : SensorTest or None
        With stated sensor tolerances: the score test of the sensors as stated at the plain
        refit's minimum (:func:`rigidid.core.timedomain.sensor_test.body_change_test`), and whether
        the sensors were then estimated.
    coupling : CouplingScore or None
        The score test for an AC coupling the chain does not state, at the plain refit's minimum, or, when that
        one does not flag and the sensors were corrected, at the last later pass's (the sensors' misfit out of its
        residual) when that one does (:mod:`rigidid.core.timedomain.coupling`; None with a stated high-pass);
        ``modelled`` when this refit models the corner it found (by default when the test flags it).
    """

    center_of_gravity: Array
    inertia_per_mass: Array
    stiffness_per_mass: Array
    damping_per_mass: Array
    poles: CArray
    std: dict[str, Array]
    normalised_cost: float
    noise_from: str
    residuals: int
    evaluations: int
    converged: bool = False
    misfit: MisfitTest | None = None
    delays: Array | None = None
    delays_std: Array | None = None
    delay_score: Array | None = None
    hum: tuple[tuple[float, float, float], ...] = ()
    sensor_std: dict[str, dict[str, Array]] | None = None
    sensor_correction: SensorCorrection | None = None
    sensor_test: SensorTest | None = None
    coupling: CouplingScore | None = None

    @property
    def frequency_hz(self) -> Array:
        """Undamped natural frequencies of the fitted model (Hz)."""
        return modal_from_poles(self.poles)[0]

    @property
    def damping_ratio(self) -> Array:
        """Damping ratios of the fitted model."""
        return modal_from_poles(self.poles)[1]


# --- parameterisation ---------------------------------------------------------------------


@dataclass(frozen=True)
class _Frame:
    centre: Array
    scale: float
    omega: float  # time scale (rad/s)

    def to_theta(self, g: Array, jm: Array, km: Array, cm: Array) -> Array:
        e = np.diag([1.0, 1.0, 1.0, 1.0 / self.scale, 1.0 / self.scale, 1.0 / self.scale])
        gl = (g - self.centre) / self.scale
        jl = jm / self.scale**2
        kl = e @ km @ e / self.omega**2
        cl = e @ cm @ e / self.omega
        return np.concatenate([gl, _chol(jl)[_TRIL3], _chol(kl)[_TRIL6], _chol(cl)[_TRIL6]])

    def physical(self, theta: Array) -> tuple[Array, Array, Array, Array]:
        gl, jl, kl, cl = _local(theta)
        s = self.scale
        ei = np.diag([1.0, 1.0, 1.0, s, s, s])
        return gl * s + self.centre, jl * s**2, ei @ kl @ ei * self.omega**2, ei @ cl @ ei * self.omega


def _chol(a: Array) -> Array:
    """Lower Cholesky factor of the symmetric `a`, its eigenvalues made at least 1e-3 of the largest.

    A negative eigenvalue (a structured estimate of C is often slightly indefinite: a weakly
    damped direction estimated below zero) is reflected to its magnitude rather than set
    near zero: a factor with a near-zero diagonal sits at the fold of ``L L^T``, where the
    cost's derivative along that direction vanishes and the fit stalled (``benchmarks/
    refine_diagnose.py``: 4 of 6 seeds at 5 % noise).
    """
    a = 0.5 * (a + a.T)
    w, v = np.linalg.eigh(a)
    floor = 1e-3 * max(float(np.max(np.abs(w))), 1e-300)
    result: Array = np.linalg.cholesky((v * np.maximum(np.abs(w), floor)) @ v.T)
    return result


def _lower(values: Array, n: int) -> Array:
    out = np.zeros((n, n))
    out[np.tril_indices(n)] = values
    return out


def _local(theta: Array) -> tuple[Array, Array, Array, Array]:
    lj, lk, lc = _lower(theta[3:9], 3), _lower(theta[9:30], 6), _lower(theta[30:51], 6)
    return theta[:3], lj @ lj.T, lk @ lk.T, lc @ lc.T


def _state(jl: Array, kl: Array, cl: Array) -> tuple[Array, Array]:
    """State matrix A (12x12) of eq. (19) and M^-1 (6x6), per mass, local units."""
    minv = np.zeros((6, 6))
    minv[:3, :3] = np.eye(3)
    minv[3:, 3:] = np.linalg.solve(jl, np.eye(3))
    a = np.zeros((12, 12))
    a[:6, :6] = -minv @ cl
    a[:6, 6:] = -minv @ kl
    a[6:, :6] = np.eye(6)
    return a, minv


def _dstate(theta: Array, minv: Array, a: Array) -> list[Array]:
    """dA/dtheta_j for j = 3..50 (the 48 parameters A depends on)."""
    lj, lk, lc = _lower(theta[3:9], 3), _lower(theta[9:30], 6), _lower(theta[30:51], 6)
    out: list[Array] = []
    top = a[:6, :]  # [-M^-1 C, -M^-1 K]
    for i, j in zip(*_TRIL3, strict=True):
        e = np.zeros((3, 3))
        e[i, j] = 1.0
        dj = e @ lj.T + lj @ e.T
        dm = np.zeros((6, 6))
        dm[3:, 3:] = dj
        da = np.zeros((12, 12))
        da[:6, :] = -minv @ dm @ top  # d(M^-1) X = -M^-1 dM M^-1 X
        out.append(da)
    for block, lower in ((6, lk), (0, lc)):
        for i, j in zip(*_TRIL6, strict=True):
            e = np.zeros((6, 6))
            e[i, j] = 1.0
            dx = e @ lower.T + lower @ e.T
            da = np.zeros((12, 12))
            da[:6, block : block + 6] = -minv @ dx
            out.append(da)
    return out


# --- the model at the sensors -----------------------------------------------------------


def _modes(theta: Array, pos: Array, dirs: Array, with_derivatives: bool) -> tuple[CArray, CArray, CArray, CArray]:
    """Poles (6,), shapes (p, 6), and their derivatives (51, 6), (51, p, 6)."""
    gl, jl, kl, cl = _local(theta)
    a, minv = _state(jl, kl, cl)
    lam, vec = np.linalg.eig(a)
    keep = np.flatnonzero(lam.imag > 0.0)
    if keep.size != 6:
        raise np.linalg.LinAlgError("the model has not six underdamped modes")
    keep = keep[np.argsort(np.abs(lam[keep]))]
    t_g = sensor_matrix(pos, dirs, gl)
    lam_k = lam[keep]
    accel = vec[:6, keep] * lam_k  # acceleration of the CG in each mode
    phi = t_g @ accel
    if not with_derivatives:
        return lam_k, phi, np.zeros((0, 6), complex), np.zeros((0, *phi.shape), complex)
    left = np.linalg.solve(vec, np.eye(12))
    dlam = np.zeros((N_PARAMETERS, 6), complex)
    dphi = np.zeros((N_PARAMETERS, pos.shape[0], 6), complex)
    # CG: only the sensor matrix moves: d/dg_j of (r - g) x n = -(e_j x n)
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1.0
        dt = np.hstack([np.zeros_like(dirs), -np.cross(np.broadcast_to(e, dirs.shape), dirs)])
        dphi[j] = dt @ accel
    gap = lam[None, :] - lam[:, None]  # gap[i, k] = lam_k - lam_i
    np.fill_diagonal(gap, 1.0)
    for j, da in enumerate(_dstate(theta, minv, a), start=3):
        f = left @ da @ vec
        dl = np.diag(f)[keep]
        coef = f[:, keep] / gap[:, keep]
        coef[keep, np.arange(6)] = 0.0
        dv = vec @ coef  # (12, 6)
        dlam[j] = dl
        dphi[j] = t_g @ (dv[:6] * lam_k + vec[:6, keep] * dl)
    return lam_k, phi, dlam, dphi


# --- the acquisition chain -------------------------------------------------------------


@dataclass(frozen=True)
class _Link:
    """The chain in the refit's model: ``phi_ck H_c(s_k)``, and the fitted delays' parameters.

    ``free`` lists the channels whose delays are ``theta[N_PARAMETERS:]`` (local time units,
    seconds times `omega`); the other channels' delays are the stated ones only.
    """

    chain: ChainModel
    omega: float
    free: tuple[int, ...] = ()
    hum: tuple[float, ...] = ()

    def apply(
        self, theta: Array, lam: CArray, phi: CArray, dlam: CArray, dphi: CArray
    ) -> tuple[CArray, CArray, CArray]:
        """Shapes through the chain and their derivatives (delay rows appended when delays are fitted).

        ``d(phi H)/dtheta = dphi H + phi H'(s) omega dlam``; a delay ``tau_c`` multiplies channel c by
        ``e^{-s tau_c}``, so ``d(phi_ck H_ck)/d(omega tau_c) = -lambda_k phi_ck H_ck`` (local units).
        """
        h, dh = self.transfer(theta, lam, phi.shape[0])
        out = phi * h
        if dphi.shape[0] == 0:
            return out, dlam, dphi
        d = dphi * h[None] + phi[None] * dh[None] * self.omega * dlam[:, None, :]
        dd = np.zeros((len(self.free), *phi.shape), complex)
        for i, c in enumerate(self.free):
            dd[i, c] = -lam * out[c]
        return out, np.vstack([dlam, np.zeros((len(self.free), lam.size), complex)]), np.concatenate([d, dd])

    def transfer(self, theta: Array, lam: CArray, p: int) -> tuple[CArray, CArray]:
        """Each channel's chain ``H_c(s_k)`` (p, 6) with the fitted delays, and its derivative in ``s``."""
        extra = np.zeros(p)
        extra[list(self.free)] = theta[N_PARAMETERS:] / self.omega
        h: CArray
        dh: CArray
        h, dh = self.chain.transfer(lam * self.omega, extra)
        return h, dh

    def extra_columns(self) -> int:
        """Linear unknowns per impact the chain adds (the AC coupling's transients, per channel) and the hum."""
        hum = 2 * len(self.hum) * len(self.chain.channels)
        return hum + int(sum(int(np.sum(mask)) for _, _, mask in self.chain.highpass_modes()))

    def nuisance(self, t: Array) -> Array | None:
        """Nuisance columns (n, p, m): the AC coupling's transients and the hum's sinusoids (None: none)."""
        parts = [x for x in (self.chain.nuisance(t, self.omega),) if x is not None]
        if self.hum:
            from rigidid.core.timedomain.hum import hum_columns

            parts.append(hum_columns(t, self.omega, self.hum, len(self.chain.channels)))
        return np.concatenate(parts, axis=2) if parts else None


# --- data preparation -------------------------------------------------------------------


@dataclass(frozen=True)
class PreparedDecays:
    """What the refit fits: the decays at the fit's rate and each channel's noise level.

    Attributes
    ----------
    decays : list of ndarray, shape (n_i, p)
        Per impact, the free decay from its start, decimated by the fit's
        factor (:func:`fit_factor`) and cut to :data:`MAX_ROWS` values in all.
    sigma : ndarray, shape (p,)
        Noise level of each channel at the fit's rate (ones when unknown).
    dt : float
        Sample interval of `decays` (s).
    noise_from : {"pretrigger", "residual"}
        Where `sigma` comes from ("residual": the refit measures it).
    drift : bool
        Whether the model has a linear drift per channel and impact beside the
        offset (records whose DC offset and drift were taken out,
        :mod:`rigidid.core.timedomain.trend`).
    pre_counts : tuple of int
        Pre-trigger samples of each record (raw rate; empty when unknown).
    pre_m2 : ndarray, shape (records, p), or None
        Their squared deviations from the record's pre-trigger mean, per channel
        (for the acceptance test, :mod:`rigidid.core.timedomain.acceptance`).
    pre_held : tuple of ndarray, shape (k_i, p), or None
        Each pre-trigger's first rows (raw rate, at most
        :data:`~rigidid.core.timedomain.pretrigger.PRE_HELD`): its noise in the fit's band is measured on
        them once the hum is known (:func:`_with_hum`), which sets `sigma`, `pre_variance` and `pre_dof`.
    pre_variance : ndarray, shape (records, p), or None
        Each record's pre-trigger variance per channel in the fit's band (None: not measured; the
        acceptance test then takes `pre_m2` as white noise).
    pre_dof : tuple of float
        Its degrees of freedom per record (:class:`~rigidid.core.timedomain.pretrigger.BandNoise`).
    """

    decays: list[Array]  # (n_i, p)
    sigma: Array  # (p,) noise level of each channel in the decays fitted
    dt: float
    noise_from: str
    drift: bool = False
    pre_counts: tuple[int, ...] = ()
    pre_m2: Array | None = None
    pre_held: tuple[Array, ...] | None = None
    pre_variance: Array | None = None
    pre_dof: tuple[float, ...] = ()


_Data = PreparedDecays


def columns_of(data: PreparedDecays, channels: Sequence[int]) -> PreparedDecays:
    """`data` with only the given channels (e.g. the clipped ones left out).

    Parameters
    ----------
    data : PreparedDecays
    channels : sequence of int
        Columns kept, in order.

    Returns
    -------
    PreparedDecays
    """
    cols = list(channels)
    m2 = None if data.pre_m2 is None else data.pre_m2[:, cols]
    held = None if data.pre_held is None else tuple(x[:, cols] for x in data.pre_held)
    variance = None if data.pre_variance is None else data.pre_variance[:, cols]
    return replace(data, decays=[d[:, cols] for d in data.decays], sigma=data.sigma[cols], pre_m2=m2, pre_held=held,
                   pre_variance=variance)  # fmt: skip


def pretrigger_sigma(counts: Sequence[int], squares: Sequence[Array], n_records: int, factor: int) -> tuple[Array, str]:
    """Each channel's noise level at the fit's rate from the pre-trigger statistics.

    Parameters
    ----------
    counts : sequence of int
        Pre-trigger samples of each record.
    squares : sequence of ndarray, shape (p,)
        Per record, the sum of squared deviations from its own mean, per channel.
    n_records : int
        Number of records (at least :data:`_MIN_PRETRIGGER` samples each, on average, are needed).
    factor : int
        The fit's decimation: white noise's variance after its filter is
        ``sum h^2`` of :func:`~rigidid.core.timedomain.preprocess.fir_taps`.

    Returns
    -------
    sigma : ndarray, shape (p,)
    noise_from : {"pretrigger", "residual"}
        "residual" (and ones) when the pre-trigger is too short or silent.
    """
    p = squares[0].shape[0] if len(squares) else 0
    if sum(counts) >= _MIN_PRETRIGGER * n_records:
        used = [(n, m2) for n, m2 in zip(counts, squares, strict=True) if n > 1]
        s = np.sqrt(sum(m2 for _, m2 in used) / sum(n for n, _ in used))
        if factor > 1:
            s = s * math.sqrt(float(np.sum(fir_taps(factor) ** 2)))
        if np.all(s > 0.0):
            return s, "pretrigger"
    return np.ones(p), "residual"


def cut_decays(decays: list[Array], p: int) -> list[Array]:
    """`decays` cut to :data:`MAX_ROWS` values in all (the same rows of each); too short ones refused.

    Raises
    ------
    InputError
        A decay shorter than ``4 FIR_HALF_LENGTH`` samples.
    """
    total = sum(d.shape[0] for d in decays) * p
    if total > MAX_ROWS:
        keep = MAX_ROWS // (p * len(decays))
        decays = [d[:keep] for d in decays]
    if min(d.shape[0] for d in decays) < 4 * FIR_HALF_LENGTH:
        raise InputError("records too short for the refinement")
    return decays


def prepare_decays(
    records: Sequence[Array],
    dt: float,
    starts: Sequence[int],
    onsets: Sequence[int],
    factor: int,
) -> PreparedDecays:
    """The refit's data from whole records (:func:`refine_body`'s first step).

    Parameters
    ----------
    records : sequence of ndarray, shape (n_i, p)
        The records, samples by sensors.
    dt : float
        Sample interval (s).
    starts, onsets : sequence of int
        Per record, the first sample of the free decay and of the impact.
    factor : int
        The modal estimate's decimation: the fit's is the smallest up to it
        whose decays fit :data:`MAX_ROWS` (:func:`fit_factor`).
    Returns
    -------
    PreparedDecays

    Notes
    -----
    The pre-trigger is ``r[:onset - 2]``; its level per channel is first the
    RMS about each record's mean, scaled by the fit filter's noise gain
    (:func:`pretrigger_sigma`, white noise); its first
    :data:`~rigidid.core.timedomain.pretrigger.PRE_HELD` rows are held, so the refit then
    measures the noise in its own band (:func:`_in_band`). :mod:`rigidid.io.records.refit` builds
    the same from record files read in row blocks.
    """
    p = records[0].shape[1]
    pre = [r[: max(0, o - 2)] for r, o in zip(records, onsets, strict=True)]
    factor = fit_factor([r.shape[0] - s for r, s in zip(records, starts, strict=True)], p, factor)
    decays = []
    for rec, start in zip(records, starts, strict=True):
        d = rec[start:]
        d = decimate(d, factor) if factor > 1 else d
        decays.append(np.asarray(d, dtype=float))
    decays = cut_decays(decays, p)
    squares = [((x - x.mean(axis=0)) ** 2).sum(axis=0) if x.shape[0] > 1 else np.zeros(p) for x in pre]
    counts = [x.shape[0] for x in pre]
    held = tuple(np.array(x[:PRE_HELD], dtype=float) for x in pre)
    sigma, noise_from = pretrigger_sigma(counts, squares, len(records), factor)
    return PreparedDecays(decays, sigma, dt * factor, noise_from, pre_counts=tuple(counts), pre_m2=np.array(squares),
                          pre_held=held)  # fmt: skip


_prepare = prepare_decays

_SAFE_PEAK = 2.0**200


def _in_range(records: list[Array]) -> list[Array]:
    """The records scaled together by a power of two when their largest value is outside ``[2^-200, 2^200]``
    (squares of 1e300 overflow, of 1e-300 underflow); the fit's body does not depend on a common factor."""
    top = max((float(np.max(np.abs(r))) if r.size else 0.0 for r in records), default=0.0)
    if top == 0.0 or not math.isfinite(top) or 1.0 / _SAFE_PEAK <= top <= _SAFE_PEAK:
        return records
    k = -math.frexp(top)[1]
    return [np.ldexp(r, k) for r in records]


def fit_factor(lengths: Sequence[int], p: int, factor: int) -> int:
    """The smallest decimation factor up to `factor` whose decays fit :data:`MAX_ROWS`.

    Decimation keeps the band, but its filter loses ``FIR_HALF_LENGTH q`` samples at the
    start of each decay, the part of a decay that holds the most signal (a 7 %-damped
    26 Hz mode loses more than half its energy in 20 samples at 512 Hz): the fit runs on
    the raw samples when they fit, and decimates only as much as memory requires.
    """
    for q in range(1, max(1, factor) + 1):
        if sum(n // q for n in lengths) * p <= MAX_ROWS:
            return q
    return max(1, factor)


_fit_factor = fit_factor


# --- variable projection ----------------------------------------------------------------


def _design(
    lam: CArray, phi: CArray, t: Array, drift: bool = False, extra: Array | None = None
) -> tuple[Array, CArray]:
    """Real design matrix (n p, 12 + p, or 12 + 2 p with a drift per channel) of one impact, and exp(lam t) (n, 6).

    `extra` (n, p, m): per-channel nuisance functions (the chain's AC-coupling transients), each a column
    per channel where it is not zero.
    """
    n, p = t.shape[0], phi.shape[0]
    ex = np.exp(np.outer(t, lam))  # (n, 6)
    u = ex[:, None, :] * phi[None, :, :]  # (n, p, 6)
    cols = np.concatenate([u.real, -u.imag], axis=2).reshape(n * p, 12)
    offs = np.tile(np.eye(p), (n, 1))
    blocks = [cols, offs]
    if drift:
        blocks.append(offs * np.repeat(t / max(float(t[-1]), 1e-300), p)[:, None])
    for m in range(0 if extra is None else extra.shape[2]):
        f = offs * extra[:, :, m].reshape(-1)[:, None]  # type: ignore[index]
        blocks.append(f[:, np.any(f != 0.0, axis=0)])
    return np.hstack(blocks), ex


def _projector(design: Array) -> Any:
    """``x -> (coefficients, x - design coefficients)``: least squares on `design`'s columns.

    ``project(x, out)`` writes the negated residual ``design coefficients - x`` into `out`
    (the refit's projected Jacobian, filled in place).

    From the Gram matrix of the column-normalised design (``(n, 12 + p)``: cost
    ``n (12 + p)^2``, a small fraction of a QR), by Cholesky; a QR where the Gram
    matrix is too ill-conditioned for that (condition above 1e10).
    """
    norms = np.sqrt(np.einsum("ij,ij->j", design, design))
    norms = np.where(norms > 0.0, norms, 1.0)
    scaled = design / norms
    gram = scaled.T @ scaled
    try:
        if np.linalg.cond(gram) > 1e10:
            raise np.linalg.LinAlgError("ill-conditioned")
        chol = np.linalg.cholesky(gram)
    except np.linalg.LinAlgError:
        q, rr = np.linalg.qr(scaled)

        def by_qr(x: Array, out: Array | None = None) -> tuple[Array, Array]:
            qx = q.T @ x
            return np.linalg.solve(rr, qx) / (norms if x.ndim == 1 else norms[:, None]), _minus(x, q, qx, out)

        return by_qr

    def by_gram(x: Array, out: Array | None = None) -> tuple[Array, Array]:
        c = np.linalg.solve(chol.T, np.linalg.solve(chol, scaled.T @ x))
        return c / (norms if x.ndim == 1 else norms[:, None]), _minus(x, scaled, c, out)

    return by_gram


def _minus(x: Array, basis: Array, coef: Array, out: Array | None) -> Array:
    """``x - basis coef``; with `out`, its negative ``basis coef - x`` written there (no temporary)."""
    if out is None:
        result: Array = x - basis @ coef
        return result
    np.matmul(basis, coef, out=out)
    out -= x
    return out


def _levenberg_marquardt(
    fun: Any,
    jacobian: Any,
    theta0: Array,
    max_evaluations: int,
    residuals: int,
    scale: float | None = None,
    constant: float = 0.0,
    damping: float = 1e-3,
) -> tuple[Array, int, Array, Array, bool]:
    """Minimise ``|r(theta)|^2`` by :func:`rigidid.core.optimize.levenberg_marquardt` with geodesic acceleration.

    `fun(theta)` gives the residual, `jacobian(theta)` the residual and its Jacobian (computed
    only at accepted points: the expensive call; `fun` costs about a fifteenth of it here).
    The geodesic acceleration's second directional derivative ``r''_v`` is a central
    difference along the step ``v`` (two residual evaluations).

    Stops, converged, when the Gauss-Newton decrement ``g^T (J^T J)^+ g`` (``g = J^T r``)
    over the residual variance ``|r|^2 / (n - n_theta)`` falls below :data:`_DECREMENT`:
    the remaining Gauss-Newton step, in standard-error units, is below about 0.2 of one
    standard error; or when the decrement is below 4 and the last step lowered the cost by
    less than :data:`_STALL` variances: a minimum on the boundary of the positive
    (semi-)definite J, K, C, where the Gauss-Newton step points out of the parameterisation's
    reach (a weakly damped direction whose estimate would be negative); or when the
    decrement is below the rounding floor of `scale` (``|y|^2`` of the weighted data; the
    cost at the start by default): exact data. Stops unconverged after `max_evaluations`
    residual evaluations (may overrun by three) or when no step lowers the cost.
    `residuals` is the length of ``r`` (the variance's degrees of freedom); `constant` is added
    to every cost (the part of ``|r|^2`` that no parameter moves, when `fun` gives the rest:
    :func:`_reduced`); `damping` is the initial Levenberg-Marquardt damping.

    Returns
    -------
    theta, evaluations, residual, jacobian, converged
    """
    last: dict[str, Array] = {}

    def normal(x: Array, index: Any) -> tuple[Array, Array, Array]:
        r, jm = jacobian(x[0])
        last.update(theta=x[0].copy(), r=r, jm=jm)
        return np.array([r @ r + constant]), (jm.T @ r)[None], (jm.T @ jm)[None]

    def residual(theta: Array) -> Array | None:
        try:
            return np.asarray(fun(theta))
        except np.linalg.LinAlgError:
            return None

    def cost(x: Array, index: Any) -> Array:
        r = residual(x[0])
        return np.array([math.inf if r is None else float(r @ r) + constant])

    def acceleration(x: Array, step: Array, index: Any) -> Array:
        h = _GEODESIC_H
        ahead, behind = residual(x[0] + h * step[0]), residual(x[0] - h * step[0])
        if ahead is None or behind is None:
            return np.zeros_like(step)
        out: Array = (last["jm"].T @ ((ahead - 2.0 * last["r"] + behind) / h**2))[None]
        return out

    best = levenberg_marquardt(
        normal, cost, theta0[None], max_evaluations=max_evaluations, scale=None if scale is None else np.array([scale]),
        residuals=residuals, decrement=_DECREMENT, stall=(_STALL, _STALL_DECREMENT), acceleration=acceleration,
        damping=damping,
    )  # fmt: skip
    return best.x[0], int(best.evaluations[0]), last["r"], last["jm"], bool(best.converged[0])


def _dropped_term(design: Array, res: Array, ex: CArray, t: Array, phiw: CArray, dphiw: CArray, dlam: CArray) -> Array:
    """The term of the full (Golub-Pereyra) variable-projection Jacobian that Kaufman's drops.

    ``(A^+)^T dA_j^T r = A (A^T A)^-1 dA_j^T r`` for every parameter j, shape (n p, 51);
    ``dA_j^T r`` from ``dU_jnck = e^{lambda_k t_n} (dphi_jck + phi_ck t_n dlambda_jk)``.
    """
    e1 = res.T @ ex  # (p, 6): sum_n r_nc e^{lambda_k t_n}
    e2 = res.T @ (ex * t[:, None])
    s = np.einsum("ck,jck->jk", e1, dphiw) + dlam * np.einsum("ck,ck->k", phiw, e2)[None, :]
    z = np.zeros((dphiw.shape[0], design.shape[1]))
    z[:, :6], z[:, 6:12] = s.real, -s.imag
    coef = np.linalg.lstsq(design.T @ design, z.T, rcond=None)[0]  # (A^T A)^-1 z^T
    out: Array = design @ coef
    return out


def _model_derivative(ex: CArray, t: Array, g1: CArray, g2: CArray) -> Array:
    """``Re sum_k e^{lambda_k t_n} (g1_jck + t_n g2_jck)`` as one real matrix product, shape (n, p, 51).

    The complex product ``[E, t E] [G1; G2]`` has real part ``[Re, Im] [Re G; -Im G]``: one BLAS
    call on (n, 24) by (24, 51 p), and no (n, 51, p) complex temporaries.
    """
    n, p, n_theta = t.shape[0], g1.shape[1], g1.shape[0]
    e = np.hstack([ex, ex * t[:, None]])  # (n, 12)
    g = np.concatenate([g1, g2], axis=2).transpose(2, 1, 0).reshape(12, p * n_theta)  # (12, p 51)
    left = np.hstack([e.real, e.imag])
    right = np.vstack([g.real, -g.imag])
    out: Array = (left @ right).reshape(n, p, n_theta)
    return out


def _evaluate(
    theta: Array,
    data: _Data,
    pos: Array,
    dirs: Array,
    omega: float,
    jac: bool,
    link: _Link | None = None,
    mix: Array | None = None,
) -> tuple[Array, Array]:
    """Weighted residual (n p,) and its projected Jacobian (n p, n_theta); `link` the chain's model
    (:class:`_Link`); with `mix` (m, p) the shapes are ``mix phi`` (the decays then hold the channels'
    combinations, :func:`_reduced`)."""
    lam, phi, dlam, dphi = _modes(theta, pos, dirs, jac)
    if link is not None:
        phi, dlam, dphi = link.apply(theta, lam, phi, dlam, dphi)
    if mix is not None:
        phi = mix @ phi
        dphi = np.matmul(mix, dphi) if jac else dphi
    w = 1.0 / data.sigma
    res_parts = []
    j_all = np.empty((sum(d.size for d in data.decays) if jac else 0, theta.size))
    row = 0
    for y in data.decays:
        n, p = y.shape
        t: Array = np.arange(n, dtype=float) * (data.dt * omega)
        extra = None if link is None else link.nuisance(t)
        design, ex = _design(lam, phi * w[:, None], t, data.drift, extra)
        yw = (y * w).reshape(-1)
        project = _projector(design)
        beta, r = project(yw)
        res_parts.append(r)
        if jac:
            amp = beta[:6] + 1j * beta[6:12]  # columns Re u and -Im u: model Re(u (a_re + i a_im))
            # d model = Re( sum_k a_k (dphi_k + phi_k t dlam_k) e^{lam_k t} )
            wd = dphi * w[None, :, None]  # (51, p, 6)
            g1 = wd * amp  # (51, p, 6)
            g2 = (phi * w[:, None])[None, :, :] * (dlam * amp)[:, None, :]
            dm = _model_derivative(ex, t, g1, g2).reshape(n * p, theta.size)  # d model / d theta
            jp = project(dm, j_all[row : row + n * p])[1]  # minus the projected derivative, in place
            del dm
            if _GOLUB_PEREYRA:
                jp -= _dropped_term(design, r.reshape(n, p), ex, t, phi * w[:, None], wd, dlam)
        row += n * p
    r_all = np.concatenate(res_parts)
    return r_all, j_all


# --- the sensors' tolerances (issue 23): their signatures in the residual ----------------


@dataclass(frozen=True)
class SensorTerms:
    """How the stated sensors' errors would show in the refit, linearised at its minimum.

    Per sensor ``i`` six unit errors, in the columns ``k p + i``: its gain (relative),
    its axis turned towards the two normals of :func:`rigidid.core.sensor_budget.axis_normals`
    (radians), its position shifted along x, y, z (the layout's length). Each error adds a
    signature ``g`` to the weighted records; ``G~`` is ``G`` less its projection on each
    impact's linear terms (modal amplitudes, offsets).

    Attributes
    ----------
    cross : ndarray, shape (51, 6 p)
        ``J^T G~`` (``J`` the refit's projected Jacobian).
    gram : ndarray, shape (6 p, 6 p)
        ``G~^T G~``.
    data : ndarray, shape (6 p,)
        ``G~^T r`` (``r`` the refit's residual).
    """

    cross: Array
    gram: Array
    data: Array


def sensor_terms(theta: Array, data: _Data, pos_l: Array, dirs: Array, omega: float, jm: Array, r: Array,
                 scale: float, link: _Link | None = None) -> SensorTerms:  # fmt: skip
    """The sensor errors' signatures at `theta`, projected and reduced (:class:`SensorTerms`).

    The signature of an error of sensor ``i`` is the model's motion read by a virtual
    sensor, in channel ``i`` only: at the same point along the same axis (gain), along
    a normal (tilt), or the difference of two points a unit apart (the reading is linear
    in the position, eq. (3) of [1]); the per-impact modal amplitudes are the fit's.
    Position columns are per layout length (`scale`: the local frame's length unit).
    With `link` (a modelled chain, fitted delays, hum) the virtual sensors read through
    channel ``i``'s chain and fitted delay, and ``G~`` is projected off the chain's nuisance
    columns too; `theta` and `jm` then hold the delays' parameters (``cross`` has a row each).
    """
    p = pos_l.shape[0]
    k = 6 * p
    cross, gram, proj = np.zeros((theta.size, k)), np.zeros((k, k)), np.zeros(k)
    row = 0
    for sig, off in _impact_signatures(theta, data, pos_l, dirs, omega, scale, link):
        n = sig.shape[0]
        gram += off.gram()  # r and J are orthogonal to the linear columns already: G~ = G in their products
        sig_c = sig.transpose(2, 0, 1)  # (c, n, kind): batched products per channel (BLAS, not einsum loops)
        jr = jm[row : row + n * p].reshape(n, p, theta.size)
        cross += np.matmul(jr.transpose(1, 2, 0), sig_c).transpose(1, 2, 0).reshape(theta.size, k)
        proj += np.einsum("nc,nkc->kc", r[row : row + n * p].reshape(n, p), sig).reshape(k)
        row += n * p
    return SensorTerms(cross, gram, proj)


@dataclass(frozen=True)
class _OffColumns:
    """One impact's sensor signatures off its linear columns, kept in their structure (:func:`_impact_signatures`).

    The linear columns are the modal ones (``Re`` and ``-Im`` of ``e^{s_k t} phi_ck``, across the channels) and
    each channel's own (offset, drift, the chain's transients, hum: ``L_c``). With ``P_c`` the projector off
    ``L_c`` and ``M~ = P M`` the modal columns off them, ``P_S = P - M~ (M~^T M~)^+ M~^T``; a signature lives in
    one channel, so ``G~ = P G - M~ (M~^T M~)^+ B`` with ``B = M~^T P G`` (12 by 6 p), formed from per-channel
    sums over time, never from the design (``n p`` by ``12 + q p``).
    """

    local: Array  # (n, kind, p): each channel's signatures off its own columns, P G
    groups: tuple[tuple[Array, CArray], ...]  # (channels, e^{s t} off their columns (n, 6)) per set of columns
    shapes: CArray  # (p, 6) the weighted shapes
    inv: Array  # (12, 12): (M~^T M~)^+
    b: Array  # (12, kind p)

    def gram(self) -> Array:
        """``G~^T G~`` (6 p, 6 p), columns ``kind p + c``."""
        _, kinds, p = self.local.shape
        block = np.matmul(self.local.transpose(2, 1, 0), self.local.transpose(2, 0, 1))  # (c, kind, kind)
        own = np.zeros((kinds, p, kinds, p))
        own[:, np.arange(p), :, np.arange(p)] = block
        out: Array = own.reshape(kinds * p, kinds * p) - self.b.T @ self.inv @ self.b
        return out

    def explicit(self) -> Array:
        """``G~`` written out, (n p, 6 p) (for the determined errors' rank, :func:`_augmented_null`)."""
        n, kinds, p = self.local.shape
        g = (self.local[:, None, :, :] * np.eye(p)[None, :, None, :]).reshape(n * p, kinds * p)
        modal = np.zeros((n, p, 12))
        for channels, e in self.groups:
            u = e[:, None, :] * self.shapes[channels][None]
            modal[:, channels] = np.concatenate([u.real, -u.imag], axis=2)
        out: Array = g - modal.reshape(n * p, 12) @ (self.inv @ self.b)
        return out


def _local_columns(t: Array, drift: bool, extra: Array | None, p: int) -> list[tuple[Array, Array]]:
    """Each channel's own linear columns as :func:`_design` has them, grouped: ``(channels, orthonormal basis)``."""
    base = [np.ones(t.size)] + ([t / max(float(t[-1]), 1e-300)] if drift else [])
    sets: dict[bytes, tuple[list[int], Array]] = {}
    for c in range(p):
        own = [] if extra is None else [extra[:, c, m] for m in range(extra.shape[2]) if np.any(extra[:, c, m] != 0.0)]
        cols = np.column_stack(base + own)
        sets.setdefault(cols.tobytes(), ([], cols))[0].append(c)
    out = []
    for channels, cols in sets.values():
        q, rr = np.linalg.qr(cols)
        d = np.abs(np.diag(rr))
        out.append((np.array(channels), q[:, d > 1e-12 * max(float(np.max(d)), 1e-300)]))
    return out


def _impact_signatures(theta: Array, data: _Data, pos_l: Array, dirs: Array, omega: float, scale: float,
                       link: _Link | None = None) -> Iterator[tuple[Array, _OffColumns]]:  # fmt: skip
    """Per impact: the signatures (n, 6, p) and what is left of them off the linear columns (:class:`_OffColumns`).

    The modal amplitudes are the least-squares ones with the linear columns (as the fit's). With `link`, every
    virtual sensor reads through its channel's chain ``H_c(s_k)`` (the fitted delay included) and each channel's
    columns hold the chain's nuisance ones (AC transients, hum), as :func:`_evaluate`'s."""
    from rigidid.core.sensor_budget import axis_normals

    p = pos_l.shape[0]
    e1, e2 = axis_normals(dirs)
    eye = np.eye(3)
    vpos = np.concatenate([pos_l, pos_l, pos_l, pos_l + eye[0], pos_l + eye[1], pos_l + eye[2]])
    vdir = np.concatenate([dirs, e1, e2, dirs, dirs, dirs])
    lam, phi_v, *_ = _modes(theta, vpos, vdir, False)
    phi_v = phi_v.reshape(6, p, 6)
    phi_v[3:] = (phi_v[3:] - phi_v[0]) / scale
    if link is not None:  # each channel's chain: linear, so the position's difference passes through it too
        phi_v = phi_v * link.transfer(theta, lam, p)[0][None]
    w = 1.0 / data.sigma
    phi = phi_v[0] * w[:, None]
    for y in data.decays:
        n = y.shape[0]
        t: Array = np.arange(n, dtype=float) * (data.dt * omega)
        ex = np.exp(np.outer(t, lam))  # (n, 6)
        groups = _local_columns(t, data.drift, None if link is None else link.nuisance(t), p)
        yw = y * w
        gram, fit, tilde = np.zeros((12, 12)), np.zeros(12), []
        for channels, q in groups:
            e = ex - q @ (q.T @ ex)
            gram += modal_gram(e, phi[channels])
            u = (e.T @ (yw[:, channels] - q @ (q.T @ yw[:, channels]))) * phi[channels].T  # (6, c)
            fit += np.concatenate([u.real.sum(axis=1), -u.imag.sum(axis=1)])
            tilde.append(e)
        norms = np.sqrt(np.maximum(np.diag(gram), 0.0))
        norms = np.where(norms > 0.0, norms, 1.0)
        inv = pseudo_inverse(gram / np.outer(norms, norms), symmetric=True)[0] / np.outer(norms, norms)
        beta = inv @ fit
        modal = ex * (beta[:6] + 1j * beta[6:12])  # (n, 6)
        sig = (modal.real @ phi_v.real.reshape(-1, 6).T - modal.imag @ phi_v.imag.reshape(-1, 6).T).reshape(n, 6, p) * w
        local, b = np.empty_like(sig), np.zeros((12, 6, p))
        for (channels, q), e in zip(groups, tilde, strict=True):
            part = sig[:, :, channels]
            local[:, :, channels] = part - np.einsum("nq,qjc->njc", q, np.einsum("nq,njc->qjc", q, part))
            v = np.einsum("nk,njc->kjc", e, local[:, :, channels]) * phi[channels].T[:, None, :]  # (6, kind, c)
            b[:6, :, channels] = v.real
            b[6:, :, channels] = -v.imag
        yield sig, _OffColumns(local, tuple((c, e) for (c, _), e in zip(groups, tilde, strict=True)), phi, inv,
                               b.reshape(12, 6 * p))  # fmt: skip


def _sensor_moments(bounds: Any, p: int) -> tuple[Array, Array, dict[str, Array]]:
    """Per column of :class:`SensorTerms`, ``E x^2`` and ``Var x^2``, and each source's ``E x^2`` per column."""
    mo = bounds.moments()
    (vs, ss), (vo, so), (vt, st), (vp, sp) = (mo[s] for s in ("sensitivity", "orientation", "transverse", "position"))
    kinds = np.repeat(np.arange(6), p)
    gain, tilt, shift = kinds == 0, (kinds == 1) | (kinds == 2), kinds >= 3
    v = np.where(gain, vs, np.where(tilt, vo + vt, vp))
    sv = np.where(gain, ss, np.where(tilt, so + st + 4.0 * vo * vt, sp))  # tilt: two independent errors summed
    per_source = {"sensitivity": np.where(gain, vs, 0.0), "orientation": np.where(tilt, vo, 0.0),
                  "transverse": np.where(tilt, vt, 0.0), "position": np.where(shift, vp, 0.0)}  # fmt: skip
    return v, sv, per_source


@dataclass(frozen=True)
class _Projection:
    """The sensors' signatures against the fit's Jacobian, at its minimum (:func:`_projection`).

    Attributes
    ----------
    hp : ndarray
        ``(J^T J)^+``.
    move : ndarray, shape (parameters, 6 p)
        ``(J^T J)^+ J^T G~``: the parameters' move per unit sensor error (Gauss-Newton, first order).
    q : ndarray, shape (6 p, 6 p)
        ``Q = G~^T G~ - (J^T G~)^T (J^T J)^+ J^T G~``, symmetrised: what the fit cannot absorb.
    """

    hp: Array
    move: Array
    q: Array


def _projection(terms: SensorTerms, jm: Array) -> _Projection:
    """:class:`_Projection` of `terms` on the Jacobian `jm`: one pseudo-inverse for the budget, the sensor
    test and the correction."""
    hp = pseudo_inverse(jm.T @ jm, symmetric=True)[0]
    move = hp @ terms.cross
    q = terms.gram - terms.cross.T @ move
    return _Projection(hp, move, 0.5 * (q + q.T))


def _sensor_outcome(
    terms: SensorTerms, proj: _Projection, bounds: Any, grad: Array
) -> tuple[Array, Array, Array, dict[str, dict[str, Array]]]:
    """The misfit's quadratic form, the moments, and each source's std of the physical values.

    ``Q`` is `proj`'s (what the fit cannot absorb); a sensor error ``x`` moves the parameters by
    ``(J^T J)^+ J^T G~ x`` (Gauss-Newton, first order), the physical values by `grad` times that.
    """
    v, sv, per_source = _sensor_moments(bounds, terms.gram.shape[0] // 6)
    effect = grad @ proj.move  # (outputs, k)
    std = {source: _physical_std(np.sqrt((effect**2) @ var)) for source, var in per_source.items()}
    return proj.q, v, sv, std


@dataclass(frozen=True)
class SensorCorrection:
    """Per-sensor errors estimated jointly with the body from the records' redundancy (issue 23).

    Rows of each (6, p) array: gain (relative), the axis turned towards the two normals of
    :func:`rigidid.core.sensor_budget.axis_normals` (radians), the position shifted along x, y,
    z (the layout's length); columns: sensors.

    Attributes
    ----------
    value : ndarray, shape (6, p)
        The estimate: the stated tolerances as a prior (rectangular, taken at its variance),
        the records as data (Gauss-Newton from the refit's minimum).
    std : ndarray, shape (6, p)
        Its posterior standard deviation (the prior's where the records say nothing).
    determined : ndarray of bool, shape (6, p)
        Whether the records determine it, at least relative to the others: less than half of
        its unit vector lies in the null space of the augmented Jacobian ``[J, G~]`` (rank by
        :func:`rigidid.core.linalg.rank_tolerance`). The null space holds what no records can
        tell: a common gain (the force is not measured), a common shift or turn of all sensors
        (the CG and the axes move with them), a shift along a sensor's own axis.
    rank : int
        Rank of the augmented Jacobian, of ``51 + 6 p`` columns.
    """

    value: Array
    std: Array
    determined: NDArray[np.bool_]
    rank: int


def _augmented_null(theta: Array, data: _Data, pos_l: Array, dirs: Array, omega: float, jm: Array,
                    scale: float, link: _Link | None = None) -> tuple[Array, int]:  # fmt: skip
    """Which sensor errors the records determine: null vectors of ``[J, G~]`` (column-normalised), by rows.

    The R factor of the stacked impacts (each impact's block factored, then the stack): the
    signatures formed whole here (``n p`` by ``6 p`` per impact), so this runs only when the errors
    are estimated. With `link`, the signatures through the chain and ``J``'s columns beyond the body's the
    delays' (:func:`sensor_terms`); the null vectors' parts on the sensors' columns are what is returned.
    """
    from rigidid.core.linalg import rank_tolerance

    p = pos_l.shape[0]
    blocks = []
    row = 0
    for sig, off in _impact_signatures(theta, data, pos_l, dirs, omega, scale, link):
        n = sig.shape[0]
        gt = off.explicit()
        blocks.append(np.linalg.qr(np.hstack([jm[row : row + n * p], gt]), mode="r"))
        row += n * p
    r = np.linalg.qr(np.vstack(blocks), mode="r")
    norms = np.linalg.norm(r, axis=0)
    _, sv, vt = svd(r / np.where(norms > 0.0, norms, 1.0))
    keep = sv > rank_tolerance(sv[0], row)
    null = vt[~keep]
    return np.linalg.norm(null[:, theta.size :], axis=0), int(np.sum(keep))


def _after_correction(q: Array, v: Array, ve: Array) -> tuple[Array, float]:
    """The misfit's quadratic form in the true sensor errors once the correction is made, and the noise's
    degrees of freedom the correction takes: what the after-check (:attr:`SensorTest.explains`) budgets.

    Parameters
    ----------
    q : ndarray, shape (6 p, 6 p)
        ``Q = G~^T (I - P_J) G~`` (:class:`_Projection`).
    v : ndarray, shape (6 p,)
        The errors' prior variances (every kind).
    ve : ndarray, shape (6 p,)
        The estimated errors' prior variances, zero for errors left at their prior (the refit estimates every
        kind: `v` itself).

    Returns
    -------
    q_after : ndarray, shape (6 p, 6 p)
        ``F^T Q F``, ``F = I - S Q``: ``E |.|^2`` of the errors' part is ``sum_k q_after_kk v_k``.
    absorbed : float
        ``2 tr(S Q) - tr(S Q S Q)``.

    Notes
    -----
    Linearised at the refit's minimum, the residual is ``r = R x + e`` with ``R = (I - P_J) G~`` (``Q = R^T
    R``), ``x`` the true errors (drawn from their prior: mean 0, variances ``V``), ``e`` the noise projected off
    the fit (unit variance per weighted residual). The correction (:func:`_sensor_correction`) estimates
    ``x^ = S R^T r`` with ``S = (V_e Q + I)^-1 V_e`` (``V_e`` the estimated errors' prior variances, zero for
    the others; ``S`` the posterior covariance, zero outside the estimated rows and columns), and leaves

    ``r_a = r - R x^ = R F x + (I - R S R^T) e``,  ``F = I - S Q``,

    so ``E |r_a|^2 = tr(V F^T Q F) + (m - 2 tr(S Q) + tr(S Q S Q))`` (``m`` the noise's degrees of freedom).
    On the estimated errors alone this is ``m - tr(S Q)``: the errors' remaining part ``x - x^`` (covariance
    ``S``) costs ``tr(S Q) - tr(S Q S Q)`` and its correlation with the noise gives back ``2 (tr(S Q) - tr(S Q S
    Q))``, as for any linear least-squares fit of ``tr(S Q)`` effective parameters. Errors left at their
    prior (none in the refit; positions until issue 23's position cell) cost ``tr(V_p F_p^T Q F_p)``: their
    signatures less what the estimated ones absorb.
    A later Gauss-Newton pass starts from ``r_a`` (its correction is then about zero), so its residual is what
    this describes; the nonlinearity of the passes is left out (its size is the passes' last move, under
    :data:`_SETTLED` of the body's standard errors).
    """
    s = np.linalg.solve(ve[:, None] * q + np.eye(v.size), np.diag(ve))
    sq = s @ q
    f = np.eye(v.size) - sq
    q_after = f.T @ q @ f
    return 0.5 * (q_after + q_after.T), float(2.0 * np.trace(sq) - np.trace(sq @ sq))


def _sensor_correction(
    terms: SensorTerms, proj: _Projection, bounds: Any, grad: Array
) -> tuple[Array, Array, Array, dict[str, dict[str, Array]], Array]:
    """The sensor errors estimated with the body (maximum a posteriori, linearised at the refit's minimum).

    Minimises ``|r + J d - G~ x|^2 + x^T V^-1 x`` (``V`` the errors' stated variances): ``x =
    (V Q + I)^-1 V G~^T r`` (``Q`` as in :func:`_sensor_outcome`); on a later pass, with the sensors
    already corrected by ``x0`` (`bounds` a :class:`_Centred`), the prior is on the total ``x0 + x``:
    ``x = (V Q + I)^-1 (V G~^T r - x0)``. The body's parameters move by
    ``d = (J^T J)^+ J^T G~ x``. What a true error ``x`` still costs the body is
    ``(J^T J)^+ J^T G~ (V Q + I)^-1 x``; the noise in ``x`` adds
    ``(V Q + I)^-1 V Q V (V Q + I)^-T`` through the same map.

    Every kind is estimated: the gains, the two tilts and the three position shifts; what the records do not
    determine (a shift along a sensor's own axis, whose signature is zero, or a shift common to all) keeps its
    prior through ``V``. Positions were once kept at their prior, because with them freed the sensor test
    flagged 5 of 20 clean runs at its 1 % rate (benchmarks/chain_matrix.py clean, default tolerances, seeds
    200-219: T 24-67 on 9 dof). The cause was the score's: the CG enters the model only through ``p - g``, so
    the sum of every sensor's shift columns is minus the CG's Jacobian column, and a fit stopped short of its
    minimum leaves ``J^T r`` there, which ``G~^T r`` read as a common shift. The score ``G~^T (I - P_J) r``
    (:func:`_sensor_gate`) takes that step out: the same 20 runs flag none at 1 %; seeds 500-559 flag 1 of 60,
    mean T 8.8, KS p 0.30; the position cell comes within the per-run target in 20 of 20 (seeds 500-519; 12
    of 20 on 400-419 with the positions at their prior).

    Returns
    -------
    x, x_std : ndarray, shape (6 p,)
    shift : ndarray, shape (51,)
        The parameters' move.
    sensor_std : dict
        Per source, the std of the physical values the errors leave after the correction.
    noise_var : ndarray
        Variance added to each physical value by the noise in ``x``.
    """
    move, q = proj.move, proj.q
    v, _, per_source = _sensor_moments(bounds, terms.gram.shape[0] // 6)
    system = v[:, None] * q + np.eye(v.size)
    earlier = getattr(bounds, "earlier", None)  # a later pass: the prior stays on the total (_Centred)
    rhs = v * terms.data if earlier is None else v * terms.data - np.where(v > 0.0, earlier, 0.0)
    x: Array = np.linalg.solve(system, rhs).astype(float)
    x_var: Array = np.where(v > 0.0, np.diag(np.linalg.solve(system, np.diag(v))), v)
    left = grad @ move @ np.linalg.solve(system, np.eye(v.size))  # physical value per unit true error, remaining
    std = {source: _physical_std(np.sqrt((left**2) @ var)) for source, var in per_source.items()}
    # a variance (q is a Schur complement, positive semi-definite): below zero only by rounding, where the
    # signatures are nearly the Jacobian's (as many sensors as the body's six motions)
    noise_var: Array = np.maximum(np.einsum("ij,jk,ik->i", left, (v[:, None] * q) * v[None, :], left), 0.0)
    shift: Array = move @ x
    x_std: Array = np.sqrt(np.maximum(x_var, 0.0))
    return x, x_std, shift, std, noise_var


def _corrected(
    theta: Array, data: _Data, sensors: tuple[Array, Array], frame: _Frame, jm: Array, terms: SensorTerms,
    bounds: Any, grad: Array, std: dict[str, Array], link: _Link | None, proj: _Projection,
) -> tuple[Array, dict[str, Array], dict[str, dict[str, Array]], SensorCorrection]:  # fmt: skip
    """The parameters, noise std and type-B std after :func:`_sensor_correction`, and the correction.

    With the delays fitted (`link`), ``theta`` and `jm` hold their parameters beyond the body's: the
    correction moves them with the body; their std (``"delay"``) stays the joint covariance's marginal.
    """
    pos_l, dirs = sensors
    x, x_std, shift, sensor_std, noise_var = _sensor_correction(terms, proj, bounds, grad)
    null, rank = _augmented_null(theta, data, pos_l, dirs, frame.omega, jm, frame.scale, link)
    p = pos_l.shape[0]
    correction = SensorCorrection(x.reshape(6, p), x_std.reshape(6, p), (null**2 < 0.5).reshape(6, p), rank)
    flat = np.concatenate([std[key].ravel() for key in std if key != "delay"])
    kept = {"delay": std["delay"]} if "delay" in std else {}
    return theta + shift, _physical_std(np.sqrt(flat**2 + noise_var)) | kept, sensor_std, correction


def _physical_std(sd: Array) -> dict[str, Array]:
    """The flat standard deviations of :func:`_outputs` as a dict of CG, J/m, K/m, C/m, frequencies, damping."""
    return {
        "center_of_gravity": sd[:3],
        "inertia_per_mass": sd[3:12].reshape(3, 3),
        "stiffness_per_mass": sd[12:48].reshape(6, 6),
        "damping_per_mass": sd[48:84].reshape(6, 6),
        "frequency_hz": sd[84:90],
        "damping_ratio": sd[90:96],
    }


def refine_body(
    records: Sequence[ArrayLike],
    dt: float,
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    starts: Sequence[int],
    onsets: Sequence[int],
    decimation: int,
    center_of_gravity: ArrayLike,
    inertia_per_mass: ArrayLike,
    stiffness_per_mass: ArrayLike,
    damping_per_mass: ArrayLike,
    max_evaluations: int = 240,
    drift: bool = False,
    chain: ChainModel | None = None,
    estimate_delays: bool = False,
    sensor_bounds: Any = None,
    estimate_sensors: bool | None = False,
    estimate_highpass: bool | None = False,
) -> Refinement:
    """Fit CG, J/m, K/m and C/m to the free decays of every impact (output error).

    Parameters
    ----------
    records : sequence of array_like, shape (n_k, p)
        The raw records, samples by sensors (sensor reading along its axis).
    dt : float
        Sample interval (s).
    positions, directions : array_like, shape (p, 3)
        The sensors (length; directions normalised here).
    starts, onsets : sequence of int
        Per record, the first sample of the free decay and of the impact
        (:class:`~rigidid.core.timedomain.preprocess.Impact`); samples before
        the onset are the pre-trigger the noise levels come from.
    decimation : int
        Decimation factor applied to the decays before the fit (the modal
        estimate's: it keeps the band with the anti-alias margin).
    center_of_gravity, inertia_per_mass, stiffness_per_mass, damping_per_mass
        The start: the structured identification from the estimated modes
        (layout units, per mass, at the CG).
    max_evaluations : int
        Largest number of residual evaluations (three per iteration of the
        optimiser, plus one Jacobian per accepted step); 0 evaluates the start only
        (its Cramér-Rao bound, e.g. at the truth of a simulation).
    drift : bool
        Fit a linear drift per channel and impact beside the offset
        (:attr:`PreparedDecays.drift`).
    chain, estimate_delays
        The acquisition chain and whether to fit the channels' delays
        (:func:`refine_prepared`).
    sensor_bounds : SensorBounds, optional
        The sensors' stated tolerances (:class:`rigidid.core.sensor_budget.SensorBounds`,
        length in the layout's unit): the acceptance test expects the misfit they leave
        (:func:`~rigidid.core.timedomain.acceptance.budgeted_misfit_test`) and
        ``sensor_std`` holds their effect on the body (:func:`sensor_terms`).
    estimate_sensors : bool or None
        With `sensor_bounds`: estimate every sensor's gain, axis and position errors with the
        body (the redundancy of more than six channels), the tolerances as their prior; the
        body corrected (``sensor_correction``). None: only when the sensor test flags
        (``sensor_test``, :mod:`rigidid.core.timedomain.sensor_test`) and the noise is the pre-trigger's (with
        mains hum too, its lines taken out), through the chain and fitted delays when they are modelled;
        otherwise the plain refit.
    estimate_highpass : bool or None
        Without a high-pass in `chain`: model an AC coupling at the corner the score test of the plain
        refit's residual finds (``coupling``, :mod:`rigidid.core.timedomain.coupling`), one first-order
        high-pass common to the channels. None: only when the test flags it; False: never (the test is
        still reported).

    Returns
    -------
    Refinement

    Raises
    ------
    InputError
        Records too short.
    numpy.linalg.LinAlgError
        When the start has not six underdamped modes.

    Notes
    -----
    Model: the state matrix ``A = [[-M^-1 C, -M^-1 K], [I, 0]]`` of eq. (19),
    per mass, in the layout's dimensionless frame (length over the RMS sensor
    radius, time times the median natural frequency). ``J/m``, ``K/m`` and
    ``C/m`` are ``L L^T`` of lower-triangular factors, so they stay positive
    (semi-)definite. Channel ``c`` of impact ``i`` reads
    ``y(t) = 2 Re sum_k a_ik phi_ck exp(lambda_k t) + o_ic + noise`` with
    ``phi_k = T_g (lambda_k v_k)``. The amplitudes ``a_ik`` and offsets
    ``o_ic`` are solved by linear least squares inside the residual; the
    Jacobian is Kaufman's projected one, from the eigenvalue and eigenvector
    derivatives ``dlambda_k = (V^-1 dA V)_kk``, ``dV = V C``,
    ``C_jk = (V^-1 dA V)_jk / (lambda_k - lambda_j)``. Residuals are divided
    by each channel's noise level: from the pre-trigger (at least 32 samples
    per record; measured in the fit's band, :mod:`rigidid.core.timedomain.pretrigger`), otherwise from
    the start's own residual, then from the fit's. The Cramér-Rao bound is
    ``(J^T J)^-1`` in whitened units, mapped to the physical values by their
    derivatives (delta method). At most :data:`MAX_ROWS` residuals are fitted
    (memory about ``80 MAX_ROWS`` bytes per 51 parameters), the end of long
    decays cut. Limits: modes must be distinct (the eigenvector derivative
    divides by pole gaps); noise assumed white and independent between
    channels; a start more than about the frequency resolution ``1 /
    duration`` away falls into a local minimum, which a normalised cost well
    above 1 exposes (the caller falls back).
    """
    recs = _in_range([np.asarray(r, dtype=float) for r in records])
    data = _prepare(recs, float(dt), starts, onsets, max(1, int(decimation)))
    del recs
    if drift:
        data = replace(data, drift=True)
    return refine_prepared(
        data, dt, positions, directions, center_of_gravity=center_of_gravity, inertia_per_mass=inertia_per_mass,
        stiffness_per_mass=stiffness_per_mass, damping_per_mass=damping_per_mass, max_evaluations=max_evaluations,
        chain=chain, estimate_delays=estimate_delays, sensor_bounds=sensor_bounds, estimate_sensors=estimate_sensors,
        estimate_highpass=estimate_highpass,
    )  # fmt: skip


def refine_prepared(
    data: PreparedDecays,
    dt: float,
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    center_of_gravity: ArrayLike,
    inertia_per_mass: ArrayLike,
    stiffness_per_mass: ArrayLike,
    damping_per_mass: ArrayLike,
    max_evaluations: int = 240,
    drift: bool | None = None,
    chain: ChainModel | None = None,
    estimate_delays: bool = False,
    sensor_bounds: Any = None,
    estimate_sensors: bool | None = False,
    sensor_passes: int = 5,
    estimate_highpass: bool | None = False,
) -> Refinement:
    """:func:`refine_body` on decays already prepared (:func:`prepare_decays`, or read in row blocks).

    Parameters
    ----------
    data : PreparedDecays
        The decays at the fit's rate and the channels' noise levels.
    dt : float
        Sample interval of the records the decays came from (s): the fit's
        factor is ``data.dt / dt``.
    positions, directions, center_of_gravity, inertia_per_mass, stiffness_per_mass, damping_per_mass, max_evaluations
        As for :func:`refine_body`.
    sensor_bounds, estimate_sensors, estimate_highpass
        As for :func:`refine_body`.
    sensor_passes : int
        With the sensors estimated: at most this many Gauss-Newton passes on the sensors' errors, each a refit
        with the sensors as the last corrected them (the errors' effect is not linear), until a pass moves
        the CG and J/m by less than :data:`_SETTLED` of their standard errors.
    drift : bool, optional
        Overrides ``data.drift``.
    chain : ChainModel, optional
        The channels' acquisition chain (:mod:`rigidid.core.timedomain.chain`): each mode's
        contribution to channel c is multiplied by ``H_c(s_k)``, the AC coupling's transients are
        nuisance columns, the fit starts after the anti-alias filter's settling time.
    estimate_delays : bool
        Fit a delay per channel beside the body, relative to the first channel (whose delay a
        common shift of every channel's would absorb in the modal amplitudes).

    Returns
    -------
    Refinement

    Raises
    ------
    numpy.linalg.LinAlgError
        When the start has not six underdamped modes.

    Notes
    -----
    The model, the fit and the bound are :func:`refine_body`'s (eq. (19)).
    """
    if drift is not None and drift != data.drift:
        data = replace(data, drift=drift)
    given = data
    data = _settled(data, chain, estimate_delays, float(dt))
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    body = (center_of_gravity, inertia_per_mass, stiffness_per_mass, damping_per_mass)
    pos_l, frame, theta0 = _started(pos, dirs, body)
    omega = frame.omega
    link = _link(chain, omega, pos.shape[0], estimate_delays)
    theta0 = theta0 if link is None else np.concatenate([theta0, np.zeros(len(link.free))])
    link, hum, data, theta0 = _with_hum(link, theta0, data, (pos_l, dirs, omega, chain, estimate_delays, float(dt)))
    out, plain, coupling = _refined(
        _Start(data, link, hum, chain), dt, (pos, dirs, pos_l, frame, theta0), max_evaluations,
        (sensor_bounds, estimate_sensors, sensor_passes),
    )  # fmt: skip
    later = out.coupling  # a later pass's, the sensors corrected (:func:`_next_pass`): their misfit out of it
    if (coupling is None or not coupling.flagged) and later is not None and later.flagged:
        coupling = later
    out = replace(_plain_kept(out, estimate_sensors, plain), coupling=coupling)
    if coupling is None or not (estimate_highpass or (estimate_highpass is None and coupling.flagged)):
        return out
    coupled = _with_highpass(chain, pos.shape[0], coupling.corner_hz)
    again = refine_prepared(
        given, dt, positions, directions, center_of_gravity=center_of_gravity, inertia_per_mass=inertia_per_mass,
        stiffness_per_mass=stiffness_per_mass, damping_per_mass=damping_per_mass, max_evaluations=max_evaluations,
        chain=coupled, estimate_delays=estimate_delays, sensor_bounds=sensor_bounds, estimate_sensors=estimate_sensors,
        sensor_passes=sensor_passes,
    )  # fmt: skip
    return replace(again, coupling=replace(coupling, modelled=True))


@dataclass(frozen=True)
class _Start:
    """What a refit starts from once the chain is settled and the hum found: the decays (their noise levels
    from the pre-trigger, or to be taken from the start's residual), the link (:class:`_Link`, None without
    one), the hum found and the stated chain (its delay score for a rejected fit). A later pass of the
    sensors' correction (:func:`_next_pass`) starts from the same, the gains taken out of the decays."""

    data: PreparedDecays
    link: _Link | None
    hum: tuple[tuple[float, float, float], ...]
    chain: ChainModel | None


def _refined(start: _Start, dt: float, sensors: tuple[Any, ...], max_evaluations: int,
             sensing: tuple[Any, bool | None, int]) -> tuple[Refinement, Callable[[], Refinement] | None,
                                                              CouplingScore | None]:  # fmt: skip
    """:func:`refine_prepared` from its start: `sensors` is ``(pos, dirs, pos_l, frame, theta0)`` (`theta0` with
    the delays' parameters when fitted), `sensing` ``(sensor_bounds, estimate_sensors, sensor_passes)``.

    Returns the refinement, when the sensors were corrected the plain refit's (this pass's fit without the
    correction, as ``estimate_sensors=False`` gives it) on call (:func:`_plain_kept`), else None, and the score
    test of an unstated AC coupling at the fit's minimum (:func:`_coupling`)."""
    pos, dirs, pos_l, frame, theta0 = sensors
    sensor_bounds, estimate_sensors, sensor_passes = sensing
    data, link, omega, p = start.data, start.link, frame.omega, pos.shape[0]
    if data.noise_from == "residual":
        r0 = _residual(theta0, data, pos_l, dirs, omega, link)
        per = r0.reshape(-1, pos.shape[0])
        sigma = np.sqrt(np.mean(per**2, axis=0))
        data = replace(data, sigma=np.where(sigma > 0, sigma, 1.0))

    if max_evaluations > 0:
        theta, nfev, r, jm, converged, reduced = _fit(data, pos_l, dirs, omega, theta0, max_evaluations, link)
    else:
        theta, nfev, converged, reduced = theta0, 0, False, None
        r, jm = _evaluate(theta, data, pos_l, dirs, omega, True, link)
    n_res = r.size
    n_linear = _linear_per_impact(p, data.drift) + (0 if link is None else link.extra_columns())
    dof = max(n_res - theta.size - len(data.decays) * n_linear, 1)
    s2 = float(r @ r) / dof
    cost = s2 if data.noise_from == "pretrigger" else 1.0
    q_fit = max(1, round(data.dt / float(dt)))  # _prepare may decimate less than `decimation`
    grad = _output_gradient(theta, frame, pos_l, dirs)
    lengths = [d.shape[0] for d in data.decays]
    std = _bound(theta, jm, s2, frame, pos_l, dirs, r, lengths, q_fit, n_linear, grad, reduced)
    misfit = _misfit(r, data, dof / n_res, q_fit)
    coupling = _coupling(theta, (r, jm), data, (pos_l, dirs, omega), link, s2)
    sensor_std, correction, test, fitted = None, None, None, theta
    fit_at = (data, pos_l, dirs, omega, frame, link), (jm, r, grad, s2)
    assemble = partial(_assembled, start, (frame, pos_l, dirs, s2), (cost, n_res, nfev, converged))

    def budgeted(form: tuple[Array, Array, Array], absorbed: float = 0.0) -> MisfitTest | None:
        return _misfit(r, data, dof / n_res, q_fit, form, absorbed)

    plain: Callable[[], Refinement] | None = None
    if sensor_bounds is not None:  # the sensors' signatures in this fit's model (the chain, delays, hum in it)
        plain_fit = (theta, std, misfit)
        theta, std, misfit, sensor_std, correction, test = _with_sensors(
            plain_fit, *fit_at, sensor_bounds, estimate_sensors, budgeted
        )  # fmt: skip
        if correction is not None:  # the plain refit, made again on call: what estimate_sensors=False gives
            plain = partial(_plain_refinement, assemble, plain_fit, fit_at, sensor_bounds, budgeted)
    out = assemble(theta, fitted, (std, misfit, sensor_std, correction, test), sensor_bounds)
    if correction is not None and sensor_passes > 1 and _unsettled(grad @ (theta - fitted), std):
        # a next pass whose model has not six underdamped modes: this pass is kept (its after-check judges it)
        with contextlib.suppress(np.linalg.LinAlgError):
            out = _next_pass(out, start, dt, (pos, dirs), sensor_bounds, max_evaluations, sensor_passes - 1)
    return out, plain, coupling


def _assembled(start: _Start, model: tuple[Any, ...], stats: tuple[Any, ...], theta: Array, fitted: Array,
               outcome: tuple[Any, ...], sensor_bounds: Any) -> Refinement:  # fmt: skip
    """The :class:`Refinement` of :func:`_refined` at `theta` (`fitted` the fit's own minimum): `model` is
    ``(frame, pos_l, dirs, s2)``, `stats` ``(cost, residuals, evaluations, converged)``, `outcome` ``(std, misfit,
    sensor_std, correction, test)``; the delays' results, or with the sensors corrected the skew's joint score."""
    frame, pos_l, dirs, s2 = model
    cost, n_res, nfev, converged = stats
    std, misfit, sensor_std, correction, test = outcome
    data, link, omega = start.data, start.link, frame.omega
    g, j, k, c = frame.physical(theta)  # with the sensors' correction, the body moved with it
    lam, *_ = _modes(theta, pos_l, dirs, False)
    rejected = (misfit is not None and not misfit.accepted) or (misfit is None and cost >= _GOOD_COST)
    if correction is not None and (link is None or not link.free):  # the skew's score with the sensors free
        delays, delays_std = None, None
        first = getattr(sensor_bounds, "earlier", None) is None
        at = (data, pos_l, dirs, omega, frame.scale)
        score = _joint_delay_score(fitted, at, link, sensor_bounds, s2) if first else None
    else:
        delays, delays_std, score = _delay_results(
            theta, std, link, rejected, (data, pos_l, dirs, omega, start.chain, s2)
        )  # fmt: skip
    body_std = {key: value for key, value in std.items() if key != "delay"}  # the delays' is `delays_std`
    return Refinement(
        center_of_gravity=g, inertia_per_mass=j, stiffness_per_mass=k, damping_per_mass=c, poles=lam * omega,
        std=body_std, normalised_cost=cost, noise_from=data.noise_from, residuals=n_res, evaluations=nfev,
        converged=converged, misfit=misfit, delays=delays, delays_std=delays_std, delay_score=score, hum=start.hum,
        sensor_std=sensor_std, sensor_correction=correction, sensor_test=test,
    )  # fmt: skip


def _plain_refinement(assemble: Callable[..., Refinement], plain_fit: tuple[Any, ...], fit_at: tuple[Any, ...],
                      sensor_bounds: Any, budgeted: Callable[..., MisfitTest | None]) -> Refinement:  # fmt: skip
    """The first pass's fit without the sensors' correction, as :func:`_refined` makes it with
    ``estimate_sensors=False`` (the same fit, its sensor terms formed again): `plain_fit` ``(theta, std, misfit)``
    at its minimum before :func:`_with_sensors`, `fit_at` its model and linearisation."""
    theta = plain_fit[0]
    model, linear = fit_at
    _, std, misfit, sensor_std, _, test = _with_sensors(plain_fit, model, linear, sensor_bounds, False, budgeted)
    return assemble(theta, theta, (std, misfit, sensor_std, None, test), sensor_bounds)


def _plain_kept(corrected: Refinement, estimate: bool | None, plain: Callable[[], Refinement] | None) -> Refinement:
    """`corrected`, or by default (`estimate` None) when the sensors' correction left a residual the noise and
    what the correction leaves of the tolerances do not explain
    (:attr:`rigidid.core.timedomain.sensor_test.SensorTest.explains`), the plain refit (`plain`: the first pass's
    fit without the correction, bit-identical to a refit with ``estimate_sensors=False``), its sensor test the
    corrected one's marked not estimated, and the corrected fit's skew score (with the sensors freed) when the plain
    one has none (an unmodelled skew is one thing a correction cannot explain: the records' API then refits with
    the delays fitted)."""
    test = corrected.sensor_test
    if estimate is not None or test is None or test.explains or plain is None:
        return corrected
    kept = plain()
    score = corrected.delay_score if kept.delay_score is None else kept.delay_score
    return replace(kept, sensor_test=replace(test, estimated=False), delay_score=score)


def _started(pos: Array, dirs: Array, body: tuple[ArrayLike, ...]) -> tuple[Array, _Frame, Array]:
    """The sensors in the layout's local frame, the fit's frame (time in units of the start's median
    natural frequency) and the start's parameters in it; `body` is (CG, J/m, K/m, C/m)."""
    lf = layout_frame(pos)
    pos_l = lf.to_local(pos)
    physical = [np.asarray(x, float) for x in body]
    lam0, *_ = _modes(_Frame(lf.centre, lf.scale, 1.0).to_theta(*physical), pos_l, dirs, False)
    frame = _Frame(lf.centre, lf.scale, float(np.median(np.abs(lam0))))
    return pos_l, frame, frame.to_theta(*physical)


def _delay_results(
    theta: Array, std: dict[str, Array], link: _Link | None, rejected: bool, fit: tuple[Any, ...]
) -> tuple[Array | None, Array | None, Array | None]:
    """The fitted delays and their std (s), or, for a rejected fit without them, the delay score (:func:`delay_step`).

    `fit` is ``(data, pos_l, dirs, omega, chain, s2)``; the delays' std is ``std``'s ``"delay"`` entry.
    """
    data, pos_l, dirs, omega, chain, s2 = fit
    p = pos_l.shape[0]
    if link is not None and link.free:
        delays, delays_std = np.zeros(p), np.zeros(p)
        delays[list(link.free)] = theta[N_PARAMETERS:] / omega
        delays_std[list(link.free)] = std["delay"] / omega
        return delays, delays_std, None
    if not rejected or p < 2:
        return None, None, None
    wide = _link(chain, omega, p, True, () if link is None else link.hum)
    r_d, j_d = _evaluate(np.concatenate([theta, np.zeros(p - 1)]), data, pos_l, dirs, omega, True, wide)
    return None, None, delay_step(r_d, j_d, p - 1, s2) / np.array([[omega], [1.0]])


def _joint_delay_score(
    theta: Array, model: tuple[Any, ...], link: _Link | None, bounds: Any, s2: float
) -> Array | None:
    """:func:`delay_step` with the sensors' errors freed too (their stated variances ``V`` as a prior), at the fit.

    With the sensors' errors estimated, an unmodelled skew would be taken for them (a tilt or gain of the late
    channel and the body moved), and the misfit test that the tolerances budget may accept the fit: the delays'
    score is then the Gauss-Newton step of ``min |r + J d - G~ x|^2 + x^T V^-1 x`` with every channel's delay
    among ``d`` (beyond the first's) and the estimated errors (gains, tilts) in ``x``, its covariance the inverse
    of the joint normal matrix. `model` is ``(data, pos_l, dirs, omega, scale)``; None for one channel.
    """
    data, pos_l, dirs, omega, scale = model
    p = pos_l.shape[0]
    if p < 2:
        return None
    chain = link.chain if link is not None else None
    wide = _link(chain, omega, p, True, () if link is None else link.hum)
    th = np.concatenate([theta[:N_PARAMETERS], np.zeros(p - 1)])
    r, jm = _evaluate(th, data, pos_l, dirs, omega, True, wide)
    terms = sensor_terms(th, data, pos_l, dirs, omega, jm, r, scale, wide)
    v = _sensor_moments(bounds, p)[0]
    free = v > 0.0
    cross, n_t = terms.cross[:, free], th.size
    normal = np.block([[jm.T @ jm, -cross], [-cross.T, terms.gram[np.ix_(free, free)] + np.diag(1.0 / v[free])]])
    cov = pseudo_inverse(normal, symmetric=True)[0]
    step = cov @ np.concatenate([-(jm.T @ r), terms.data[free]])
    sd = np.sqrt(np.maximum(np.diag(cov)[N_PARAMETERS:n_t] * max(s2, 1.0), 1e-300))
    out = np.zeros((2, p))
    out[0, 1:], out[1, 1:] = step[N_PARAMETERS:n_t], step[N_PARAMETERS:n_t] / sd
    scored: Array = out / np.array([[omega], [1.0]])
    return scored


def _link(
    chain: ChainModel | None, omega: float, p: int, estimate_delays: bool, hum: Sequence[float] = ()
) -> _Link | None:
    """The chain's link into the refit (None: nothing to model, no delays fitted, no hum)."""
    model = chain if chain is not None else ChainModel(tuple(ChannelChain() for _ in range(p)))
    if model.identity and not estimate_delays and not hum:
        return None
    return _Link(model, omega, tuple(range(1, p)) if estimate_delays else (), tuple(hum))


def _with_hum(
    link: _Link | None, theta0: Array, data: PreparedDecays, model: tuple[Any, ...]
) -> tuple[_Link | None, tuple[tuple[float, float, float], ...], PreparedDecays, Array]:
    """`link` with the hum :func:`~rigidid.core.timedomain.hum.find_hum` finds in the start's residual, and the
    noise measured in the fit's band (:func:`_in_band`) with the hum's lines out of the pre-trigger.

    `model` is ``(pos_l, dirs, omega, chain, estimate_delays, dt)`` (`dt` the raw sample interval).
    Returns the link, the hum found, the data and the start. With hum, the fit starts from a pilot fit
    (:data:`_PILOT` evaluations) with the hum modelled and the levels of the start's residual (the start's own
    residual holds its misfit and would weight the channels by it). Without the pre-trigger's rows
    (`data.pre_held` None) or too few of them, the pre-trigger's levels hold the hum, so with hum they come from
    the residual (``noise_from`` ``"residual"``, no misfit test).
    """
    from rigidid.core.timedomain.hum import find_hum

    pos_l, dirs, omega, chain, estimate_delays, dt = model
    r0 = _residual(theta0, data, pos_l, dirs, omega, link)
    parts, row, p = [], 0, pos_l.shape[0]
    for d in data.decays:
        parts.append(r0[row : row + d.size].reshape(-1, p))
        row += d.size
    found = tuple(find_hum(parts, data.dt))
    measured = _in_band(data, [f for f, _, _ in found], dt)
    if not found:
        return link, (), data if measured is None else measured, theta0
    link = _link(chain, omega, p, estimate_delays, [f for f, _, _ in found])
    data = replace(data, sigma=np.ones(p), noise_from="residual") if measured is None else measured
    per = _evaluate(theta0, replace(data, sigma=np.ones(p)), pos_l, dirs, omega, False, link)[0].reshape(-1, p)
    pilot = replace(data, sigma=np.sqrt(np.mean(per**2, axis=0)) + 1e-300)

    def both(theta: Array) -> tuple[Array, Array]:
        return _evaluate(theta, pilot, pos_l, dirs, omega, True, link)

    def fun(theta: Array) -> Array:
        return _evaluate(theta, pilot, pos_l, dirs, omega, False, link)[0]

    theta = _levenberg_marquardt(fun, both, theta0, _PILOT, per.size)[0]
    return link, found, data, theta


def _coupling(theta: Array, fit: tuple[Array, Array], data: PreparedDecays, model: tuple[Array, Array, float],
              link: _Link | None, s2: float) -> CouplingScore | None:  # fmt: skip
    """The score test of an unstated AC coupling in the fit's weighted residual and Jacobian `fit` at `theta` (None
    with a stated high-pass): the linear columns as :func:`_design`'s (the offsets, drifts and hum each channel has
    its own of), decay rates from half the longest decay's inverse to half the lowest mode's natural frequency (a
    corner above it is not tried: `interior` then false; `model` is ``(pos_l, dirs, omega)``, time in units of
    ``1 / omega``)."""
    pos_l, dirs, omega = model
    if link is not None and link.chain.highpass_modes():
        return None
    r, jm = fit
    p = pos_l.shape[0]
    lam, phi, *_ = _modes(theta, pos_l, dirs, False)
    if link is not None:
        phi = phi * link.transfer(theta, lam, p)[0]
    residuals, times, exps, local, tangent, row = [], [], [], [], [], 0
    for y in data.decays:
        n = y.shape[0]
        t: Array = np.arange(n, dtype=float) * (data.dt * omega)
        residuals.append(r[row : row + n * p].reshape(n, p))
        tangent.append(jm[row : row + n * p].reshape(n, p, -1))
        row += n * p
        # without a stated high-pass the link's nuisance is the hum alone, the same on every channel: one set
        ((_, basis),) = _local_columns(t, data.drift, None if link is None else link.nuisance(t), p)
        times.append(t)
        exps.append(np.exp(np.outer(t, lam)))
        local.append(basis)
    slowest, fastest = 0.5 / max(float(t[-1]) for t in times), 0.5 * float(np.min(np.abs(lam)))
    if fastest < 8.0 * slowest:  # decays too short to tell a coupling's transient from a drift
        return None
    return coupling_score(
        residuals, times, exps, local, phi / data.sigma[:, None], variance=s2, rate_range=(slowest, fastest),
        hz_per_rate=omega / (2.0 * math.pi), tangent=tangent,
    )  # fmt: skip


def _with_highpass(chain: ChainModel | None, channels: int, corner_hz: float) -> ChainModel:
    """`chain` (None: no chain) with a first-order high-pass at `corner_hz` on every channel (an AC coupling found)."""
    base = chain.channels if chain is not None else (ChannelChain(),) * channels
    return ChainModel(tuple(replace(c, highpass_hz=corner_hz, highpass_order=1) for c in base))


def _in_band(data: PreparedDecays, frequencies: Sequence[float], dt: float) -> PreparedDecays | None:
    """`data` with its noise measured in the fit's band on the pre-trigger's rows, the hum at `frequencies` out
    (:func:`~rigidid.core.timedomain.pretrigger.band_noise`; `dt` the raw sample interval): the levels, and each
    record's variance and degrees of freedom for the acceptance test. The levels replace the white-noise
    ones of :func:`pretrigger_sigma` and a stated anti-alias filter's ratio (:func:`_settled`): the band's noise is
    measured, whatever its colour. None when the levels do not come from the pre-trigger, its rows are not
    held, or they are too few."""
    if data.noise_from != "pretrigger" or data.pre_held is None or len(data.pre_held) != len(data.decays):
        return None
    noise = band_noise(data.pre_held, dt, max(1, round(data.dt / dt)), frequencies)
    if noise is None:
        return None
    return replace(data, sigma=noise.sigma, pre_variance=noise.variance, pre_dof=noise.dof, pre_held=None)


def _settled(
    data: PreparedDecays, chain: ChainModel | None, estimate_delays: bool = False, dt: float = 0.0
) -> PreparedDecays:
    """`data` with the first samples of each decay dropped while the chain settles (:meth:`ChainModel.settle_time`).

    With the delays estimated, :data:`_DELAY_SKIP` more samples (a late channel reads the impact's end there).
    With an anti-alias filter and a decimated fit, the pre-trigger's noise levels (and squares) are scaled
    for the noise's colour (:meth:`ChainModel.decimated_noise_ratio`; `dt` the raw sample interval): the levels
    the hum's detection whitens by, and the fallback when the pre-trigger is too short to measure the noise in
    the fit's band (:func:`_in_band`, which otherwise replaces them).
    """
    q = max(1, round(data.dt / dt)) if dt > 0.0 else 1
    if chain is not None and q > 1 and data.noise_from == "pretrigger":
        ratio = chain.decimated_noise_ratio(dt, fir_taps(q))
        m2 = None if data.pre_m2 is None else data.pre_m2 * ratio[None, :]
        data = replace(data, sigma=data.sigma * np.sqrt(ratio), pre_m2=m2)
    skip = (0 if chain is None else math.ceil(chain.settle_time() / data.dt)) + (_DELAY_SKIP if estimate_delays else 0)
    if skip == 0:
        return data
    return replace(data, decays=[d[skip:] for d in data.decays])


def delay_step(r: Array, jm: Array, n_delays: int, s2: float) -> Array:
    """The delays' part of one Gauss-Newton step from a fit without them, and its z scores.

    A score test for unmodelled channel delays: at the fitted body, the step
    ``-(J^T J)^-1 J^T r`` of the fit with delays freed (the body's parameters and the
    delays together, `jm`'s last `n_delays` columns the delays of channels 1..p-1) and its
    standard errors ``sqrt(s2 diag (J^T J)^-1)``.

    Parameters
    ----------
    r : ndarray, shape (n,)
        The residual at the fit (whitened).
    jm : ndarray, shape (n, n_theta)
        Its Jacobian with the delays' columns last.
    n_delays : int
        Number of delay columns.
    s2 : float
        Residual variance.

    Returns
    -------
    ndarray, shape (2, n_delays + 1)
        Row 0: each channel's delay step (local time units; 0 for the reference, channel 0);
        row 1: its z score.
    """
    info = jm.T @ jm
    cov = pseudo_inverse(info, symmetric=True)[0]
    step = -cov @ (jm.T @ r)
    sd = np.sqrt(np.maximum(np.diag(cov)[-n_delays:] * s2, 1e-300))
    out = np.zeros((2, n_delays + 1))
    out[0, 1:] = step[-n_delays:]
    out[1, 1:] = step[-n_delays:] / sd
    return out


def _with_sensors(
    fit: tuple[Array, dict[str, Array], MisfitTest | None],
    model: tuple[Any, ...],
    linear: tuple[Array, Array, Array, float],
    bounds: Any,
    estimate: bool | None,
    budgeted: Callable[..., MisfitTest | None],
) -> tuple[Array, dict[str, Array], MisfitTest | None, dict[str, dict[str, Array]], SensorCorrection | None,
           SensorTest]:  # fmt: skip
    """The stated sensor tolerances in the refit: the misfit they leave expected by the acceptance test,
    their effect on the body (``sensor_std``), the sensor test and, when `estimate` (None: when the test
    flags and the noise is the pre-trigger's, with or without a chain or delays), the sensors' errors estimated.

    `fit` is ``(theta, std, misfit)``, `model` ``(data, pos_l, dirs, omega, frame, link)``, `linear`
    ``(jm, r, grad, s2)`` at the minimum; `budgeted` the misfit test given the tolerances' quadratic form
    and moments (and the noise's degrees of freedom a correction takes: the after-check,
    :func:`_after_correction`). Returns theta, std, misfit, sensor_std, the correction (or None) and the test.

    Notes
    -----
    The correction is one Gauss-Newton step of ``min |r + J d - G~ x|^2 + x^T V^-1 x`` over the parameters
    ``d`` and the sensors' errors ``x`` (:func:`_sensor_correction`). With a link (:class:`_Link`) ``d`` holds
    the body's 51 parameters and the fitted delays' (``J``'s columns beyond the body's), ``G~`` the signatures
    read through each channel's chain and fitted delay and projected off the chain's nuisance columns
    (:func:`sensor_terms`); the elimination is the same: ``d = (J^T J)^+ J^T (G~ x - r)``, so the correction
    moves the delays with the body, and their std stays the joint covariance's marginal. ``J^T r`` is zero only
    at the fit's minimum: a fit stopped by its budget (a fit with delays, whose misfit holds the sensors'
    errors, converges slowly) leaves the step ``-(J^T J)^+ J^T r``, which the correction takes with it
    (``x``'s right-hand side ``V G~^T (r - J (J^T J)^+ J^T r)``): otherwise ``x`` absorbs what the fit left.
    """
    theta, std, misfit = fit
    data, pos_l, dirs, omega, frame, link = model
    jm, r, grad, s2 = linear
    terms = sensor_terms(theta, data, pos_l, dirs, omega, jm, r, frame.scale, link)
    proj = _projection(terms, jm)
    q, v, sv, sensor_std = _sensor_outcome(terms, proj, bounds, grad)
    misfit = budgeted((q, v, sv)) or misfit
    test = _sensor_gate(terms, proj, (jm, r), bounds, grad, (s2, std))
    if estimate is None:  # by default: the noise measured apart from the residual the test reads
        # with a link too (a chain, fitted delays, hum: its lines out of the pre-trigger's noise); not with the
        # noise from the residual: when hum took the noise from the residual, on benchmarks/chain_matrix.py's
        # "all" cell the correction, forced, came out worse than the plain refit (seed 501: inertia 52 % off
        # against 36 %, floor 13.8 %; sens+orient+transverse+position alone, forced: 55 %, the positions'
        # errors not estimated then), with no misfit test to drop it
        estimate = test.flagged and data.noise_from == "pretrigger"
    correction, after = None, None
    if estimate:
        left = proj.hp @ (jm.T @ r)  # the Gauss-Newton step left: -left
        theta, std, sensor_std, correction = _corrected(
            theta, data, (pos_l, dirs), frame, jm, replace(terms, data=terms.data - terms.cross.T @ left), bounds,
            grad, std, link, proj,
        )  # fmt: skip
        theta = theta - left
        # what the correction leaves, and the noise it takes
        q_after, absorbed = _after_correction(q, v, v)
        explained = budgeted((q_after, v, sv), absorbed)
        after = None if explained is None else explained.p_value
    return theta, std, misfit, sensor_std, correction, replace(test, estimated=bool(estimate), misfit_after=after)


_SETTLED = 0.2
"""The sensors' Gauss-Newton passes stop once a pass's correction moves every tested figure (CG, J/m) by less
than this many of its standard errors (or after ``sensor_passes``). The errors' effect is not linear: on
chain_matrix's orient cell (seed 115, orientation errors up to 3 degrees) one pass left the inertia 15 % off,
two 1.3 % (5.8 standard errors), four 0.7 % (2.9)."""


def _unsettled(move: Array, std: dict[str, Array]) -> bool:
    """Whether a pass's move of the physical values (:func:`_outputs`' order) exceeds :data:`_SETTLED` of `std`."""
    sd = np.concatenate([std["center_of_gravity"].ravel(), std["inertia_per_mass"].ravel()])[TESTED_OUTPUTS]
    return bool(np.any(np.abs(move[TESTED_OUTPUTS]) > _SETTLED * sd))


def _sensor_gate(terms: SensorTerms, proj: _Projection, linear: tuple[Array, Array], bounds: Any, grad: Array,
                 noise: tuple[float, dict[str, Array]]) -> SensorTest:  # fmt: skip
    """:func:`rigidid.core.timedomain.sensor_test.body_change_test` of the sensors as stated: the score
    ``G~^T (I - P_J) r`` (`linear` is ``(jm, r)``), the CG's and J/m's first-order move under
    :func:`_sensor_correction` per unit score.

    `noise` is ``(s2, std)``: the residual's variance and the body's noise std (the sandwich of
    :func:`_bound`). The score's noise is taken as ``c s2 Q``, ``c`` the median over the tested figures of
    the sandwich's variance over the white-noise bound's ``s2 D (J^T J)^+ D^T``: the decimation filter's
    correlation (and unequal noise between impacts) widen the score as they widen the body's, the
    signatures being modal responses like the Jacobian's columns
    (:func:`rigidid.core.timedomain.sensor_test.noise_inflation`).
    """
    s2, std = noise
    jm, r = linear
    hp, move, q = proj.hp, proj.move, proj.q
    v = _sensor_moments(bounds, terms.gram.shape[0] // 6)[0]
    effect = grad[TESTED_OUTPUTS] @ move @ np.linalg.solve(v[:, None] * q + np.eye(v.size), np.diag(v))
    tested = grad[TESTED_OUTPUTS]
    white = s2 * np.einsum("ij,jk,ik->i", tested, hp, tested)
    sandwich = np.concatenate([std["center_of_gravity"].ravel(), std["inertia_per_mass"].ravel()])[TESTED_OUTPUTS] ** 2
    score = terms.data - move.T @ (jm.T @ r)  # G~^T (I - P_J) r: the fit stopped short of its minimum moves none
    return body_change_test(effect, q, score, s2 * noise_inflation(sandwich, white))


@dataclass(frozen=True)
class _Centred:
    """Stated bounds on a later Gauss-Newton pass of the sensors' correction: ``earlier`` (6 p,) the
    correction the passes before applied, on which the prior's centre (zero total error) now lies at minus."""

    bounds: Any
    earlier: Array

    def moments(self) -> dict[str, tuple[float, float]]:
        """The stated bounds' moments (:meth:`rigidid.core.sensor_budget.SensorBounds.moments`)."""
        out: dict[str, tuple[float, float]] = self.bounds.moments()
        return out


def _next_pass(first: Refinement, start: _Start, dt: float, sensors: tuple[Array, Array], bounds: Any,
               max_evaluations: int, passes: int) -> Refinement:  # fmt: skip
    """The refit again with the sensors as `first` corrected them (gains out of the records, axes and
    positions moved), from its body; its correction added to `first`'s (Gauss-Newton on the sensors).

    The later pass keeps `first`'s link (:class:`_Start`: the chain, the channels whose delays are fitted,
    the hum found, in the new frame's time unit) and starts from `first`'s delays; its decays are `first`'s,
    settled once. Noise levels from the residual are taken again from the new start's residual (unit
    weights first: the levels `first` took would weight that residual twice)."""
    from rigidid.core.sensor_budget import axis_normals

    pos, dirs = sensors
    x = first.sensor_correction
    assert x is not None
    e1, e2 = axis_normals(dirs)
    dirs2 = normalise_directions(dirs + x.value[1][:, None] * e1 + x.value[2][:, None] * e2)
    unit = 1.0 / (1.0 + x.value[0])
    data = start.data
    m2 = None if data.pre_m2 is None else data.pre_m2 * unit**2
    variance = None if data.pre_variance is None else data.pre_variance * unit**2
    sigma = data.sigma * unit if data.noise_from == "pretrigger" else np.ones_like(data.sigma)
    data2 = replace(data, decays=[d * unit for d in data.decays], sigma=sigma, pre_m2=m2, pre_variance=variance)
    body = (first.center_of_gravity, first.inertia_per_mass, first.stiffness_per_mass, first.damping_per_mass)
    pos2 = pos + x.value[3:].T
    pos_l, frame, theta0 = _started(pos2, dirs2, body)
    link = start.link
    if link is not None:  # the same chain and hum; the delays from `first`'s, in the new frame's time unit
        link = replace(link, omega=frame.omega)
        if link.free:
            assert first.delays is not None
            theta0 = np.concatenate([theta0, first.delays[list(link.free)] * frame.omega])
    centred = _Centred(getattr(bounds, "bounds", bounds), getattr(bounds, "earlier", 0.0) + x.value.ravel())
    second, _, later = _refined(
        replace(start, data=data2, link=link), dt, (pos2, dirs2, pos_l, frame, theta0), max_evaluations,
        (centred, True, passes),
    )  # fmt: skip
    y = second.sensor_correction
    assert y is not None
    value = x.value + y.value
    value[0] = (1.0 + x.value[0]) * (1.0 + y.value[0]) - 1.0  # gains compose
    total = SensorCorrection(value, y.std, y.determined, y.rank)
    test = first.sensor_test
    if test is not None and second.sensor_test is not None:
        test = replace(test, misfit_after=second.sensor_test.misfit_after)  # the last pass's residual
    return replace(second, sensor_correction=total, evaluations=first.evaluations + second.evaluations,
                   delay_score=first.delay_score if second.delay_score is None else second.delay_score,
                   sensor_test=test, coupling=later if second.coupling is None else second.coupling)  # fmt: skip


_COARSE_ROWS = 24_000
"""Residuals (samples x channel combinations) of the coarse fit that starts the full one (:func:`_fit`)."""
_COARSE_STEP = 3  # the coarse fit runs only when it takes at most every third sample
_FINE_DAMPING = 1e-9
"""Initial Levenberg-Marquardt damping of the refit's stages: Gauss-Newton steps at once. The modal
estimate's body is near the minimum (its cost about 1.3 residual variances per residual on the
issue-23 records): Gauss-Newton ends there in three Jacobians, where Marquardt's 1e-3, cut by at
most 3 per accepted step, took eleven. A far start loses little: each refused step multiplies the
damping by 2, 4, 8, ..., to 1e-3 after six refusals."""


@dataclass(frozen=True)
class _Reduced:
    """The fit's problem on fewer columns (:func:`_reduced`)."""

    data: PreparedDecays  # the columns fitted, weights one
    mix: Array | None  # (m, p): the channels' shapes to the columns' (None: the channels themselves)
    constant: float  # the part of |r|^2 no parameter moves
    rest: tuple[Array, ...] = ()  # per impact (n, p): the weighted residual's part no parameter moves


def _channel_basis(sigma: Array, pos: Array, dirs: Array) -> Array | None:
    """Orthonormal basis (p, 6) of the span of ``diag(1/sigma) T_0`` (eq. (3)); None for p <= 6 or rank < 6."""
    if pos.shape[0] <= 6:
        return None
    q, rr = np.linalg.qr(sensor_matrix(pos, dirs) / sigma[:, None])
    d = np.abs(np.diag(rr))
    return q if float(d.min()) > 1e-8 * float(d.max()) else None


def _reduced(data: PreparedDecays, basis: Array | None, step: int = 1) -> _Reduced:
    """Every `step`-th sample of the decays, their weighted channels projected on `basis` (:func:`_channel_basis`).

    Every CG ``g`` gives shapes ``T_g (lambda v)`` in the span of ``T_0``'s columns
    (``T_g = T_0 [[I, G], [0, I]]``, ``G`` the skew matrix of ``g``, eq. (3)), so the model's
    weighted shapes lie in the span of ``Q`` (`basis`) whatever the parameters. The offsets
    (and drifts) are free per channel: the weighted data's part orthogonal to ``Q`` is fitted
    by them alone, and its least-squares ``|.|^2`` is `constant`. The rest is the same problem
    on the six columns ``Y W Q`` with shapes ``Q^T W phi``: the same cost (plus `constant`),
    gradient and ``J^T J``, exactly, at ``6 / p`` of the work.
    """
    if basis is None:
        return _Reduced(replace(data, decays=[d[::step] for d in data.decays], dt=data.dt * step), None, 0.0)
    w = 1.0 / data.sigma
    decays, constant, left = [], 0.0, []
    for y in data.decays:
        yw = y[::step] * w
        cols = yw @ basis
        rest = yw - cols @ basis.T
        n = rest.shape[0]
        trend = np.column_stack([np.ones(n), np.arange(n, dtype=float)]) if data.drift else np.ones((n, 1))
        rest -= trend @ np.linalg.lstsq(trend, rest, rcond=None)[0]
        constant += float(np.sum(rest**2))
        decays.append(cols)
        left.append(rest)
    reduced = replace(data, decays=decays, sigma=np.ones(basis.shape[1]), dt=data.dt * step, pre_m2=None,
                      pre_variance=None)  # fmt: skip
    return _Reduced(reduced, basis.T * w[None, :], constant, tuple(left))


def _expanded(red: _Reduced, basis: Array, r: Array, jm: Array) -> tuple[Array, Array]:
    """The weighted residual and Jacobian on every channel from the reduced fit's (:func:`_reduced`, step 1).

    The model's weighted shapes and their derivatives lie in the span of ``Q`` (`basis`) at every
    sample, and so does the projected Jacobian: the full one is ``Q A_n`` per sample ``n`` (``A_n``
    the reduced one's rows). The residual is ``Q r_n`` plus the part orthogonal to ``Q`` that only
    the offsets (and drifts) fit (``red.rest``). Exact, at ``p / 6`` of the cost of a full evaluation's
    residual and none of its Jacobian's.
    """
    m, k = basis.shape[1], jm.shape[1]
    jac_parts, row = [], 0
    for rest in red.rest:
        n = rest.shape[0]
        jac_parts.append(np.matmul(basis, jm[row : row + n * m].reshape(n, m, k)).reshape(-1, k))
        row += n * m
    return _expanded_residual(red, basis, r), np.concatenate(jac_parts)


def _expanded_residual(red: _Reduced, basis: Array, r: Array) -> Array:
    """The weighted residual on every channel from the reduced one (:func:`_expanded`)."""
    m, parts, row = basis.shape[1], [], 0
    for rest in red.rest:
        n = rest.shape[0]
        parts.append((r[row : row + n * m].reshape(n, m) @ basis.T + rest).reshape(-1))
        row += n * m
    return np.concatenate(parts)


def _residual(theta: Array, data: PreparedDecays, pos: Array, dirs: Array, omega: float, link: _Link | None) -> Array:
    """The weighted residual on every channel (:func:`_evaluate`); from the rigid combinations where they hold it."""
    basis = _channel_basis(data.sigma, pos, dirs) if link is None else None
    if basis is None:
        return _evaluate(theta, data, pos, dirs, omega, False, link)[0]
    red = _reduced(data, basis)
    r = _evaluate(theta, red.data, pos, dirs, omega, False, None, red.mix)[0]
    return _expanded_residual(red, basis, r)


def _fit(
    data: PreparedDecays,
    pos: Array,
    dirs: Array,
    omega: float,
    theta0: Array,
    max_evaluations: int,
    link: _Link | None = None,
) -> tuple[Array, int, Array, Array, bool, tuple[Array, Array] | None]:
    """:func:`_levenberg_marquardt` on the channels' rigid combinations (:func:`_reduced`), from a coarse fit's end.

    When the decays hold more than ``3 _COARSE_ROWS`` residuals, a fit on every k-th sample
    (about :data:`_COARSE_ROWS` residuals: the model is exact at any sample times) gives the
    full fit its start, a fraction of a standard error from the minimum, so the full fit ends
    in a few iterations. The full fit's end, its convergence test and the cost are those of the
    fit on every channel and sample; its residual and Jacobian on every channel (the acceptance
    test and the sensors' terms are per channel) are expanded from the combinations' own
    (:func:`_expanded`, exact), and the intervals take the combinations' Jacobian.

    Returns
    -------
    theta, evaluations, residual, jacobian, converged, reduced
        Evaluations of both fits; residual and Jacobian on every channel (:func:`_expanded`);
        `reduced` the reduced fit's Jacobian and the basis ``Q`` (None without a reduction).
    """
    # a modelled chain, delay or hum leaves the rigid span per channel: no reduction then
    basis = _channel_basis(data.sigma, pos, dirs) if link is None else None
    columns = data.sigma.size if basis is None else basis.shape[1]
    step = sum(d.shape[0] for d in data.decays) * columns // _COARSE_ROWS
    scale = sum(float(np.sum((d / data.sigma) ** 2)) for d in data.decays)
    theta, nfev, converged = theta0, 0, False
    r, jm = np.zeros(0), np.zeros((0, theta0.size))
    for k in [step, 1] if step >= _COARSE_STEP else [1]:
        red = _reduced(data, basis, k)
        budget = max_evaluations - nfev if k > 1 else max(max_evaluations - nfev, max_evaluations // 4)

        def both(th: Array, red: _Reduced = red) -> tuple[Array, Array]:
            return _evaluate(th, red.data, pos, dirs, omega, True, link, red.mix)

        def fun(th: Array, red: _Reduced = red) -> Array:
            return _evaluate(th, red.data, pos, dirs, omega, False, link, red.mix)[0]

        n_k = sum(d.shape[0] for d in red.data.decays) * data.sigma.size
        damping = _FINE_DAMPING
        theta, used, r, jm, converged = _levenberg_marquardt(
            fun, both, theta, budget, n_k, scale / k, red.constant, damping
        )
        nfev += used
    if basis is None:
        return theta, nfev, r, jm, converged, None
    r_full, j_full = _expanded(red, basis, r, jm)
    return theta, nfev, r_full, j_full, converged, (jm, basis)


def _misfit(
    r: Array,
    data: PreparedDecays,
    dof_fraction: float,
    factor: int,
    systematic: tuple[Array, Array, Array] | None = None,
    absorbed: float = 0.0,
) -> MisfitTest | None:
    """:func:`~rigidid.core.timedomain.acceptance.misfit_test` of the fit's residual against the pre-trigger.

    With `systematic` (the sensor errors' quadratic form and moments, :func:`_sensor_outcome`):
    :func:`~rigidid.core.timedomain.acceptance.budgeted_misfit_test`, less the noise's `absorbed` degrees of
    freedom (a correction's, :func:`_after_correction`).
    """
    if data.noise_from != "pretrigger" or data.pre_m2 is None or len(data.pre_counts) != len(data.decays):
        return None
    from rigidid.core.timedomain.intervals import noise_correlation

    if data.pre_variance is not None:  # measured in the fit's band (:func:`_in_band`)
        counts = np.asarray(data.pre_dof, dtype=float) + 1.0
        variance = data.pre_variance / data.sigma[None, :] ** 2
    else:  # white noise: the raw pre-trigger's variance times the decimation filter's gain
        gain = float(np.sum(fir_taps(factor) ** 2)) if factor > 1 else 1.0
        counts = np.asarray(data.pre_counts, dtype=float)
        variance = data.pre_m2 / np.maximum(counts - 1.0, 1.0)[:, None] * gain / data.sigma[None, :] ** 2
    lengths = [d.shape[0] for d in data.decays]
    rho = noise_correlation(factor)
    if systematic is not None:
        q, v, sv = systematic
        p = data.sigma.size
        return budgeted_misfit_test(r, lengths, p, dof_fraction, list(counts), variance, rho, q, (v, sv),
                                    absorbed=absorbed)  # fmt: skip
    return misfit_test(r, lengths, data.sigma.size, dof_fraction, list(counts), variance, rho)


def _linear_per_impact(p: int, drift: bool | int) -> int:
    """Linear unknowns per impact: 12 modal amplitudes, an offset per channel (and a drift)."""
    return 12 + (2 if drift else 1) * p


def _outputs(theta: Array, frame: _Frame, pos_l: Array, dirs: Array) -> Array:
    g, j, k, c = frame.physical(theta)
    lam, *_ = _modes(theta, pos_l, dirs, False)
    w = np.abs(lam)
    return np.concatenate([g, j.ravel(), k.ravel(), c.ravel(), w * frame.omega / (2 * np.pi), -lam.real / w])


def _bound(
    theta: Array,
    jm: Array,
    s2: float,
    frame: _Frame,
    pos_l: Array,
    dirs: Array,
    residual: Array | None = None,
    lengths: Sequence[int] | None = None,
    factor: int = 1,
    n_linear: int | None = None,
    grad: Array | None = None,
    reduced: tuple[Array, Array] | None = None,
) -> dict[str, Array]:
    """Standard errors of the physical values (delta method) from the parameters' covariance.

    With `residual` and `lengths` (decimated samples per impact): the calibrated
    covariance of :func:`rigidid.core.timedomain.intervals.parameter_covariance`
    (sandwich from the residual per impact and channel, the decimation filter's
    correlation, the remaining Gauss-Newton step). Without: the textbook bound
    ``s2 (J^T J)^+``. `n_linear`: linear unknowns per impact (default: 12 and an offset per channel).
    Parameters beyond the body's (the channels' delays) get the key ``"delay"``. `grad`:
    :func:`_output_gradient` at `theta` when computed already. `reduced`: the reduced fit's
    Jacobian and basis (:func:`_fit`): the same covariance from the rigid combinations' rows.
    """
    if residual is not None and lengths is not None:
        from rigidid.core.timedomain.intervals import parameter_covariance

        per = _linear_per_impact(pos_l.shape[0], False) if n_linear is None else n_linear
        j_rows, mix = (jm, None) if reduced is None else reduced
        cov = parameter_covariance(
            j_rows, residual, lengths, pos_l.shape[0], factor, len(lengths) * per, combinations=mix
        ).matrix
    else:
        cov = s2 * pseudo_inverse(jm.T @ jm, symmetric=True)[0]  # pseudo-inverse of the information
    if grad is None:
        grad = _output_gradient(theta, frame, pos_l, dirs)
    var = np.einsum("ij,jk,ik->i", grad, cov, grad)
    delays = np.sqrt(np.maximum(np.diag(cov)[N_PARAMETERS:], 0.0))
    return _physical_std(np.sqrt(np.maximum(var, 0.0))) | ({"delay": delays} if theta.size > N_PARAMETERS else {})


def _output_gradient(theta: Array, frame: _Frame, pos_l: Array, dirs: Array) -> Array:
    """Central-difference derivatives of :func:`_outputs` with respect to the 51 parameters."""
    base = _outputs(theta, frame, pos_l, dirs)
    grad = np.zeros((base.size, theta.size))
    for i in range(N_PARAMETERS):
        h = 1e-6 * max(1.0, abs(theta[i]))
        step = theta.copy()
        step[i] += h
        back = theta.copy()
        back[i] -= h
        grad[:, i] = (_outputs(step, frame, pos_l, dirs) - _outputs(back, frame, pos_l, dirs)) / (2 * h)
    return grad


def good_fit(refinement: Refinement) -> bool:
    """Whether the normalised cost says the fit is at the global minimum (below 2)."""
    return bool(np.isfinite(refinement.normalised_cost) and refinement.normalised_cost < _GOOD_COST)


@dataclass(frozen=True)
class RecordBound:
    """Cramér-Rao intervals of the refined body, in the form of the other record intervals.

    Attributes
    ----------
    center_of_gravity, inertia, principal_moments, stiffness_diagonal : IntervalEstimate
        Estimate, standard error and 95 % interval (estimate +- 1.96 std) of
        each quantity (:class:`rigidid.core.uncertainty.IntervalEstimate`).
    per_mass : bool
        Whether inertia and stiffness are per mass (no mass given).
    normalised_cost : float
        See :class:`Refinement`.
    noise_from : str
        See :class:`Refinement`.
    residuals : int
        Number of residuals fitted.
    variance_from : str
        How the standard errors were estimated: ``"sandwich"``, the calibrated
        covariance of :func:`rigidid.core.timedomain.intervals.parameter_covariance`
        (the fit's residual per impact and channel, the decimation filter's
        correlation, the remaining Gauss-Newton step).
    evaluations : int or None
        Residual evaluations of the optimiser (:class:`Refinement`).
    converged : bool or None
        Whether the optimiser met its convergence test (:class:`Refinement`);
        when False the intervals include the remaining Gauss-Newton step.
    sensor_budget, tolerances
        See :func:`record_bound`.
    misfit : MisfitTest or None
        The refit's acceptance test (:class:`Refinement`).
    delays : dict of str to (float, float), or None
        With the delays estimated: per channel id, its delay (s) relative to the reference
        channel and its standard error (:attr:`Refinement.delays`).
    hum_hz : tuple of float
        Mains hum frequencies modelled (:attr:`Refinement.hum`).
    sensor_correction : SensorCorrection or None
        With the sensors' errors estimated: the estimate (:attr:`Refinement.sensor_correction`).
    corrected_sensors : tuple of str
        The ids of `sensor_correction`'s columns.
    sensor_test : SensorTest or None
        The sensor test and whether the sensors were estimated (:attr:`Refinement.sensor_test`).
    coupling : CouplingScore or None
        The unstated AC coupling's test and whether it was modelled (:attr:`Refinement.coupling`).
    """

    center_of_gravity: Any
    inertia: Any
    principal_moments: Any
    stiffness_diagonal: Any
    per_mass: bool
    normalised_cost: float
    noise_from: str
    residuals: int
    variance_from: str = "sandwich"
    evaluations: int | None = None
    converged: bool | None = None
    sensor_budget: dict[str, dict[str, Array]] | None = None
    tolerances: dict[str, float] | None = None
    misfit: MisfitTest | None = None
    delays: dict[str, tuple[float, float]] | None = None
    hum_hz: tuple[float, ...] = ()
    sensor_correction: SensorCorrection | None = None
    corrected_sensors: tuple[str, ...] = ()
    sensor_test: SensorTest | None = None
    coupling: CouplingScore | None = None


def record_bound(
    refinement: Refinement,
    mass: float | None,
    sensor_std: dict[str, dict[str, Array]] | None = None,
    tolerances: dict[str, float] | None = None,
) -> RecordBound:
    """95 % intervals from the calibrated standard errors of a refinement.

    Parameters
    ----------
    refinement : Refinement
    mass : float or None
        Scales inertia and stiffness to absolute values when given.
    sensor_std : dict, optional
        Per type-B source (:data:`rigidid.core.sensor_budget.SOURCES`), the
        standard deviations ``"center_of_gravity"``, ``"inertia_per_mass"``,
        ``"stiffness_per_mass"`` (:attr:`rigidid.core.sensor_budget.SensorBudget.std`):
        combined with the noise's in quadrature (GUM 5.1.2).
    tolerances : dict, optional
        The bounds the budget used, recorded in the result.

    Returns
    -------
    RecordBound
        Normal intervals ``estimate +- 1.96 std``; the principal moments'
        standard errors come from the inertia tensor's by first-order
        perturbation of its eigenvalues. With `sensor_std`, ``sensor_budget``
        holds each source's std (``"noise"`` first) of the CG and the inertia.

    Notes
    -----
    ``refinement.std`` is the sandwich covariance of
    :func:`rigidid.core.timedomain.intervals.parameter_covariance` mapped to the
    physical values: on samples/four-mounts (two impacts, 8 s at 512 Hz) the
    textbook bound ``s^2 (J^T J)^-1`` covered the truth in about 0.8 of the
    cases, because the noise level differs between impacts while the weights pool
    them, and because fits stopped by the evaluation budget lie off the minimum
    (``benchmarks/coverage.py``).
    """
    from rigidid.core.timedomain.intervals import VARIANCE_FROM
    from rigidid.core.uncertainty import IntervalEstimate

    scale = 1.0 if mass is None else float(mass)

    def interval(estimate: Array, std: Array) -> IntervalEstimate:
        return IntervalEstimate(estimate, std, estimate - _Z95 * std, estimate + _Z95 * std)

    moments, axes = np.linalg.eigh(refinement.inertia_per_mass)
    std = dict(refinement.std)
    budget = None
    if sensor_std is not None:
        budget = {"noise": {"center_of_gravity": std["center_of_gravity"],
                            "inertia_per_mass": scale * std["inertia_per_mass"]}}  # fmt: skip
        for source, parts in sensor_std.items():
            budget[source] = {"center_of_gravity": parts["center_of_gravity"],
                              "inertia_per_mass": scale * parts["inertia_per_mass"]}  # fmt: skip
        for key in ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass"):
            std[key] = np.sqrt(std[key] ** 2 + sum(parts[key] ** 2 for parts in sensor_std.values()))
    sj = std["inertia_per_mass"]
    # var(lambda_i) ~ sum_ab (u_ai u_bi)^2 var(J_ab), entries treated independent
    pm_std = np.sqrt(np.einsum("ai,bi,ab->i", axes**2, axes**2, sj**2))
    return RecordBound(
        center_of_gravity=interval(refinement.center_of_gravity, std["center_of_gravity"]),
        inertia=interval(scale * refinement.inertia_per_mass, scale * sj),
        principal_moments=interval(scale * moments, scale * pm_std),
        stiffness_diagonal=interval(
            scale * np.diag(refinement.stiffness_per_mass), scale * np.diag(std["stiffness_per_mass"])
        ),
        per_mass=mass is None,
        normalised_cost=refinement.normalised_cost,
        noise_from=refinement.noise_from,
        residuals=refinement.residuals,
        variance_from=VARIANCE_FROM,
        evaluations=refinement.evaluations,
        converged=refinement.converged,
        sensor_budget=budget,
        tolerances=tolerances,
        misfit=refinement.misfit,
        sensor_test=refinement.sensor_test,
        coupling=refinement.coupling,
    )
