"""The measured force of an impact test: H1 FRFs with coherence, and the mass they measure.

A hammer's force channel turns the records into an input-output test. Per impact the force
and the responses are windowed as acquisition software windows them (a force window that
zeroes the force after the pulse; an exponential window on every channel from the pulse's
start), Fourier transformed, and averaged over the impacts into the H1 estimate
``H1 = S_fy / S_ff`` with its coherence ``|S_fy|^2 / (S_ff S_yy)`` [2].

The mass follows from the body the records identified per unit mass (CG, ``J / m``,
``K / m``, ``C / m``): its accelerance at the sensors for a unit force at the drive point is

    ``H(s) = s^2 T (s^2 M~ + s C~ + K~)^-1 t_f / m``

(the equation of motion, eq. (19) of [1], in the Laplace domain; ``T`` the sensor
transformation of eq. (3) at the CG, ``t_f`` the drive point's row of it, ``M~``, ``C~``,
``K~`` the mass, damping and stiffness matrices per unit mass), so ``1 / m`` is the one
parameter of a linear least-squares fit of the per-mass model to the measured H1, each line
weighted by its noise (``S_ff / sigma^2``). An exponential window ``exp(-a t)`` applied to
force and response alike turns the FRF ``H(i w)`` into ``H(i w + a)`` exactly (the
convolution theorem): the model is evaluated there, which is the damping correction
(every pole's decay rate raised by ``a``).

References
----------
.. [1] The paper of the project (``/work/shared/paper/NOTES.md``): eqs. (3), (19).
.. [2] J. S. Bendat and A. G. Piersol, *Random Data*, 4th ed., Wiley, 2010, sec. 9.1.3
   (H1 and the coherence function) and eq. (9.67) (the variance of an FRF estimate).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.frf import rigid_receptance
from rigidid.core.geometry import sensor_matrix

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

PULSE_LEVEL = 0.02
"""The pulse of a hit is where the force exceeds this fraction of its peak (on both sides of the peak)."""

TIP_LEVEL = 0.01
"""The hammer tip's usable band ends where the averaged force spectrum falls below this fraction of
its low-frequency level (20 dB, the usual criterion for choosing a tip)."""


@dataclass(frozen=True)
class Windows:
    """How the force and the responses are windowed before the FFT, as acquisition software does.

    Attributes
    ----------
    force_window : float or None
        Seconds after the pulse's start at which the force is zeroed (the force window);
        None: the pulse's own end (where the force falls below :data:`PULSE_LEVEL` of its
        peak after the peak) plus as many samples again as the pulse's rise.
    exponential_end : float or None
        Value of the exponential window at the shortest record's end, in (0, 1]
        (0.01: the window falls to 1 %); None or 1: no exponential window.
    """

    force_window: float | None = None
    exponential_end: float | None = None


@dataclass(frozen=True)
class ForceFrf:
    """H1 FRFs of the responses to the measured force, averaged over the impacts.

    Attributes
    ----------
    frequency_hz : ndarray, shape (f,)
        The FFT lines (Hz), from 0 to Nyquist.
    frf : ndarray of complex, shape (f, p)
        ``S_fy / S_ff`` per line and sensor (response unit per force unit).
    coherence : ndarray, shape (f, p)
        ``|S_fy|^2 / (S_ff S_yy)``, in [0, 1].
    force_power : ndarray, shape (f,)
        ``S_ff``, the force's auto spectrum summed over the impacts (force unit^2 s^2).
    decay_rate : float
        The exponential window's rate ``a`` (1/s; 0 without one): the FRF is ``H(i w + a)``.
    noise_factor : float
        ``N sum w^4 / (sum w^2)^2`` of the exponential window (1 without one): by how much
        neighbouring lines' noise is correlated (the window's equivalent noise bandwidth).
    pulses : tuple of (int, int)
        Per impact, the force window's first and last sample kept.
    force_noise : float
        Relative standard error of the FRFs' scale from the force channel's noise inside the
        force windows: ``sqrt(sum_i F_i^2 s_i^2 n_i) / sum_i F_i^2``, ``F_i`` the sum of the
        windowed force of impact ``i``, ``n_i`` its window's length, ``s_i`` the force's noise
        level measured outside the window (before the pulse, and after ten times its length).
    """

    frequency_hz: Array
    frf: CArray
    coherence: Array
    force_power: Array
    decay_rate: float
    noise_factor: float
    pulses: tuple[tuple[int, int], ...]
    force_noise: float = 0.0


def force_pulse(force: Array, dt: float, window: float | None = None) -> tuple[int, int]:
    """First and last sample of a hit's pulse: what the force window keeps.

    Parameters
    ----------
    force : ndarray, shape (n,)
        The force record of one impact.
    dt : float
        Sample interval (s).
    window : float, optional
        Length of the force window after the pulse's start (s); default: the pulse's end
        plus as many samples as its rise (see :class:`Windows`).

    Returns
    -------
    (int, int)
        First and last sample index kept (inclusive).
    """
    f = np.asarray(force, dtype=float)
    level = np.abs(f)
    peak = int(np.argmax(level))
    low = level < PULSE_LEVEL * level[peak]
    before = np.flatnonzero(low[:peak])
    start = int(before[-1]) + 1 if before.size else 0
    after = np.flatnonzero(low[peak:])
    end = peak + int(after[0]) if after.size else f.size - 1
    if window is not None:
        return start, min(f.size - 1, start + max(1, round(window / dt)))
    margin = max(1, peak - start)
    return max(0, start - 1), min(f.size - 1, end + margin)


def h1_frf(responses: Sequence[Array], forces: Sequence[Array], dt: float, windows: Windows = Windows()) -> ForceFrf:
    """H1 FRFs and coherence of the responses to the measured force, averaged over the impacts.

    Parameters
    ----------
    responses : sequence of ndarray, shape (n_i, p)
        Per impact, the sensors' records (samples x sensors).
    forces : sequence of ndarray, shape (n_i,)
        Per impact, the force record on the same time base.
    dt : float
        Sample interval (s), the same for every impact.
    windows : Windows
        The force and exponential windows.

    Returns
    -------
    ForceFrf
        The FFT is taken over the longest record's length (shorter ones zero-padded after
        their windows), so every impact gives the same lines.

    Notes
    -----
    Force window: the force is zeroed outside its pulse (:func:`force_pulse`), which
    removes the noise of the force channel between hits. Exponential window: ``exp(-a (t -
    t_0))`` from the pulse's start ``t_0`` (1 before it), on the force and the responses
    alike, so that ``H1`` estimates ``H(i w + a)``; ``a`` is set so the window reaches
    ``exponential_end`` at the end of the shortest record.
    """
    n = max(r.shape[0] for r in responses)
    pulses = tuple(force_pulse(f, dt, windows.force_window) for f in forces)
    rate = 0.0
    end = windows.exponential_end
    if end is not None and end < 1.0:
        span = min((r.shape[0] - 1 - p[0]) * dt for r, p in zip(responses, pulses, strict=True))
        rate = -float(np.log(end)) / max(span, dt)
    p = responses[0].shape[1]
    sff = np.zeros(n // 2 + 1)
    sfy = np.zeros((n // 2 + 1, p), dtype=complex)
    syy = np.zeros((n // 2 + 1, p))
    factors, areas, noise_terms = [], [], []
    for y, f, (first, last) in zip(responses, forces, pulses, strict=True):
        k = np.arange(y.shape[0])
        w = np.exp(-rate * np.clip(k - first, 0, None) * dt)
        fw = np.where((k >= first) & (k <= last), np.asarray(f, dtype=float), 0.0) * w
        spectrum_f = np.fft.rfft(fw, n)
        spectrum_y = np.fft.rfft(np.asarray(y, dtype=float) * w[:, None], n, axis=0)
        sff += np.abs(spectrum_f) ** 2
        sfy += np.conj(spectrum_f)[:, None] * spectrum_y
        syy += np.abs(spectrum_y) ** 2
        factors.append(y.shape[0] * np.sum(w**4) / np.sum(w**2) ** 2)
        areas.append(float(np.sum(fw)))
        noise_terms.append(
            _outside_noise(np.asarray(f, dtype=float), first, last) * float(np.sum(w[first : last + 1] ** 2))
        )
    with np.errstate(invalid="ignore", divide="ignore"):
        frf = sfy / sff[:, None]
        coherence = np.abs(sfy) ** 2 / (sff[:, None] * syy)
    frf_out: CArray = np.where(np.isfinite(frf), frf, 0.0).astype(complex)
    coherence = np.clip(np.where(np.isfinite(coherence), coherence, 0.0), 0.0, 1.0)
    lines = np.asarray(np.fft.rfftfreq(n, dt), dtype=float)
    a = np.asarray(areas)
    scale_noise = float(np.sqrt(np.sum(a**2 * np.asarray(noise_terms))) / np.sum(a**2)) if np.any(a) else 0.0
    return ForceFrf(lines, frf_out, coherence, sff * dt**2, rate, float(np.mean(factors)), pulses, scale_noise)


def _outside_noise(force: Array, first: int, last: int) -> float:
    """Variance of the force channel's noise: samples before the pulse and after ten times its length."""
    after = last + 10 * max(1, last - first)
    quiet = np.concatenate([force[: max(0, first - 1)], force[after:]])
    if quiet.size < 8:
        return 0.0
    return float(np.var(quiet))


def per_mass_accelerance(
    s: CArray,
    positions: Array,
    directions: Array,
    drive_position: Array,
    drive_direction: Array,
    *,
    center_of_gravity: Array,
    inertia_per_mass: Array,
    stiffness_per_mass: Array,
    damping_per_mass: Array,
) -> CArray:
    """Accelerance of the body per unit mass: ``m H(s)``, at the sensors for a force at the drive point.

    Parameters
    ----------
    s : ndarray of complex, shape (f,)
        Laplace variable (rad/s): ``i w`` for the FRF, ``i w + a`` behind an exponential window.
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    drive_position, drive_direction : ndarray, shape (3,)
        Where the force acts and its unit direction.
    center_of_gravity : ndarray, shape (3,)
    inertia_per_mass : ndarray, shape (3, 3)
    stiffness_per_mass, damping_per_mass : ndarray, shape (6, 6)
        The body per unit mass, at the CG (DOF order x, y, z, rx, ry, rz).

    Returns
    -------
    ndarray of complex, shape (f, p)
        ``s^2 T (s^2 M~ + s C~ + K~)^-1 t_f`` (eq. (19) of [1] in the Laplace domain; ``T``
        eq. (3) at the CG), in length / s^2 per force unit per mass unit.
    """
    cg = np.asarray(center_of_gravity, dtype=float)
    t = sensor_matrix(positions, directions, cg)
    tf = sensor_matrix(np.reshape(drive_position, (1, 3)), np.reshape(drive_direction, (1, 3)), cg)[0]
    m = np.eye(6)
    m[3:, 3:] = inertia_per_mass
    x = rigid_receptance(s, m, np.asarray(stiffness_per_mass), np.asarray(damping_per_mass), tf[:, None])[..., 0]
    result: CArray = (s**2)[:, None] * (x @ t.T)
    return result


@dataclass(frozen=True)
class ForceMass:
    """The mass measured by the force.

    Attributes
    ----------
    mass : float
        The estimate (mass unit).
    std : float
        Its standard error: noise (:attr:`noise_std`) and the gains' tolerances (type B) in quadrature.
    noise_std : float
        The noise's part: the responses' (weighted least squares with each sensor's noise level
        from its residual, widened by the window's line correlation) and the force's
        (:attr:`ForceFrf.force_noise`) in quadrature.
    budget : dict of str to float
        Standard deviation of the mass per source: ``noise`` (the responses'), ``force_noise``,
        ``sensitivity`` (the sensors' gains, independent), ``force_sensitivity`` (the force
        sensor's gain).
    band_hz : (float, float)
        The lines fitted.
    lines : int
        How many.
    relative_residual : float
        RMS misfit of the fit over the band relative to the measured FRFs (weighted as the fit).
    coherence : float
        Mean coherence over the band and the sensors.
    misfit : float
        RMS residual over the noise seen in its third differences along frequency (white noise
        stays there, a smooth lack of fit vanishes): about 1 when the per-mass body explains the
        FRFs to their noise. The responses' part of the standard error is multiplied by
        ``max(1, misfit)``.
    estimator : str
        ``"H1"`` (:func:`fit_mass`) or ``"errors-in-variables"`` (:func:`fit_mass_eiv`).
    response_noise : ndarray, shape (p,), or None
        The responses' noise variance per line and sensor the errors-in-variables fit weighted by.
    """

    mass: float
    std: float
    noise_std: float
    budget: dict[str, float]
    band_hz: tuple[float, float]
    lines: int
    relative_residual: float
    coherence: float
    misfit: float = 1.0
    estimator: str = "H1"
    response_noise: Array | None = None


def tip_limit(frf: ForceFrf) -> float:
    """The hammer tip's usable band: the first line above 0 where the force spectrum falls 20 dB
    (:data:`TIP_LEVEL`) below its level over the lowest tenth of the band, at most 0.8 times Nyquist (Hz)."""
    f = frf.frequency_hz
    low = (f > 0) & (f <= 0.1 * f[-1])
    ref = float(np.median(frf.force_power[low])) if np.any(low) else float(np.max(frf.force_power))
    weak = np.flatnonzero((f > 0) & (frf.force_power < TIP_LEVEL * ref))
    top = 0.8 * float(f[-1])
    return min(top, float(f[weak[0]])) if weak.size else top


def fit_band(frf: ForceFrf, frequencies_hz: Array, band: tuple[float, float] | None = None) -> tuple[float, float]:
    """The lines the mass is fitted on: half the lowest rigid-body frequency to 2.5 times the highest.

    The upper end is lowered to where the hammer tip's force spectrum has fallen 20 dB
    (:data:`TIP_LEVEL`) and to 0.4 times the sampling rate; `band` overrides the whole.
    """
    if band is not None:
        return float(band[0]), float(band[1])
    low, high = 0.5 * float(np.min(frequencies_hz)), 2.5 * float(np.max(frequencies_hz))
    return low, min(high, tip_limit(frf))


def _misfit(resid: CArray, sff: Array, sigma2: Array) -> float:
    """RMS of the whitened residual over its noise level from third differences along frequency."""
    z = resid * np.sqrt(sff)[:, None]
    if z.shape[0] < 8:
        return 1.0
    third = np.diff(z, n=3, axis=0)
    noise = float(np.mean(np.abs(third) ** 2)) / 20.0  # var of a third difference of white noise: 20 sigma^2
    total = float(np.mean(np.abs(z) ** 2))
    return float(np.sqrt(total / noise)) if noise > 0 else 1.0


def fit_mass(
    frf: ForceFrf,
    model: CArray,
    band: tuple[float, float],
    *,
    sensitivity: float = 0.0,
    force_sensitivity: float = 0.0,
) -> ForceMass:
    """Least-squares ``1 / m`` of the measured H1 against the per-mass accelerance, and its standard error.

    Parameters
    ----------
    frf : ForceFrf
        The measured FRFs (:func:`h1_frf`).
    model : ndarray of complex, shape (f, p)
        :func:`per_mass_accelerance` at ``s = i w + a`` for every line of `frf`.
    band : (float, float)
        Lines fitted (Hz), see :func:`fit_band`.
    sensitivity, force_sensitivity : float
        Bounds (half-widths of rectangular distributions, relative) of each sensor's gain
        error and of the force sensor's: their type-B part of the standard error.

    Returns
    -------
    ForceMass

    Notes
    -----
    The noise of ``H1`` at a line is ``sigma_c^2 / S_ff`` for white response noise of level
    ``sigma_c`` (Bendat and Piersol eq. (9.67) at high coherence), so each line of sensor ``c``
    is weighted by ``S_ff / sigma_c^2``, ``sigma_c`` re-estimated from the fit's residual
    (twice). ``x = 1 / m`` then has variance ``nu / (2 sum w |G|^2)`` with ``nu`` the window's
    noise factor.
    """
    f = frf.frequency_hz
    keep = (f >= band[0]) & (f <= band[1]) & (frf.force_power > 0)
    lines = int(np.count_nonzero(keep))
    if lines < 4:
        raise ValueError(f"{lines} FFT lines between {band[0]:.4g} and {band[1]:.4g} Hz; the mass needs at least 4")
    y, g, sff = frf.frf[keep], model[keep], frf.force_power[keep]
    sigma2 = np.ones(y.shape[1])
    x = 0.0
    for _ in range(3):
        w = sff[:, None] / sigma2[None, :]
        x = float(np.sum(w * np.real(np.conj(g) * y)) / np.sum(w * np.abs(g) ** 2))
        resid = y - x * g
        sigma2 = np.maximum(np.mean(np.abs(resid) ** 2 * sff[:, None], axis=0), 1e-300)
    w = sff[:, None] / sigma2[None, :]
    info = float(np.sum(w * np.abs(g) ** 2))
    misfit = _misfit(resid, sff, sigma2)
    noise_x = max(1.0, misfit) * float(np.sqrt(frf.noise_factor / (2.0 * info)))
    share = np.sum(w * np.real(np.conj(g) * y), axis=0) / (x * info)  # d x / x per unit gain of each sensor
    sens_rel = float(np.sqrt(np.sum(share**2))) * sensitivity / np.sqrt(3.0)
    force_rel = force_sensitivity / np.sqrt(3.0)
    mass = 1.0 / x
    budget = {
        "noise": noise_x / x**2,
        "force_noise": frf.force_noise * mass,
        "sensitivity": sens_rel * mass,
        "force_sensitivity": force_rel * mass,
    }
    relative = float(np.sqrt(np.sum(np.abs(y - x * g) ** 2 * w) / np.sum(np.abs(y) ** 2 * w)))
    used = f[keep]
    return ForceMass(
        mass=mass,
        std=float(np.sqrt(sum(v**2 for v in budget.values()))),
        noise_std=float(np.hypot(budget["noise"], budget["force_noise"])),
        budget=budget,
        band_hz=(float(used[0]), float(used[-1])),
        lines=lines,
        relative_residual=relative,
        misfit=misfit,
        coherence=float(np.mean(frf.coherence[keep])),
    )


@dataclass(frozen=True)
class ImpactSpectra:
    """Per impact, the responses' spectra over the fitted band and the force inside its window.

    What the errors-in-variables fit (:func:`fit_mass_eiv`) needs: the force is kept in the time
    domain, where its noise is white and limited to the force window's samples.

    Attributes
    ----------
    frequency_hz : ndarray, shape (l,)
        The lines of the band (Hz).
    responses : ndarray of complex, shape (i, l, p)
        Per impact, the windowed responses' FFT (``rfft`` over the longest record) at those lines.
    forces : tuple of ndarray, shape (n_i,)
        Per impact, the windowed force's samples inside its force window.
    samples : tuple of ndarray of int, shape (n_i,)
        Their indices in the record.
    force_sigma : tuple of ndarray, shape (n_i,)
        The force noise's standard deviation at those samples (the channel's noise outside the
        window times the exponential window there).
    dt : float
        Sample interval (s).
    noise_factor : float
        :attr:`ForceFrf.noise_factor`.
    transforms : tuple of ndarray of complex, shape (l, n_i)
        Per impact, ``D``: the window samples' Fourier transform at the lines,
        ``exp(-2 pi i f_l k dt)`` (the ``rfft`` convention), so the force's spectrum is ``D phi``.
    """

    frequency_hz: Array
    responses: CArray
    forces: tuple[Array, ...]
    samples: tuple[NDArray[np.intp], ...]
    force_sigma: tuple[Array, ...]
    dt: float
    noise_factor: float = 1.0
    transforms: tuple[CArray, ...] = ()


def impact_spectra(
    responses: Sequence[Array], forces: Sequence[Array], dt: float, frf: ForceFrf, band: tuple[float, float]
) -> ImpactSpectra:
    """The per-impact spectra of :func:`h1_frf`'s windowed records at the lines of `band`.

    Parameters
    ----------
    responses, forces, dt
        As for :func:`h1_frf`.
    frf : ForceFrf
        :func:`h1_frf` of the same records (its force windows and exponential rate are used).
    band : (float, float)
        Lines kept (Hz).

    Returns
    -------
    ImpactSpectra
    """
    n = max(r.shape[0] for r in responses)
    lines = np.asarray(np.fft.rfftfreq(n, dt), dtype=float)
    keep = (lines >= band[0]) & (lines <= band[1])
    spectra, kept, where, sigmas = [], [], [], []
    floor = 1e-9 * max(float(np.max(np.abs(f))) for f in forces)
    for y, f, (first, last) in zip(responses, forces, frf.pulses, strict=True):
        k = np.arange(y.shape[0])
        w = np.exp(-frf.decay_rate * np.clip(k - first, 0, None) * dt)
        spectra.append(np.fft.rfft(np.asarray(y, dtype=float) * w[:, None], n, axis=0)[keep])
        idx = np.arange(first, last + 1)
        force = np.asarray(f, dtype=float)
        kept.append(force[idx] * w[idx])
        where.append(idx)
        sigmas.append(max(float(np.sqrt(_outside_noise(force, first, last))), floor) * w[idx])
    transforms = tuple(np.exp(-2j * np.pi * np.outer(lines[keep], idx * dt)) for idx in where)
    return ImpactSpectra(
        lines[keep], np.asarray(spectra), tuple(kept), tuple(where), tuple(sigmas), float(dt), frf.noise_factor,
        transforms,
    )  # fmt: skip


def _eiv_terms(spectra: ImpactSpectra, model: CArray, sigma2: Array) -> list[tuple[Array, Array, CArray]]:
    """Per impact: ``Q = Re(D^H diag(g) D)``, ``r = Re(D^H h)`` and ``D`` (lines x window samples).

    ``g_l = sum_c 2 |G_lc|^2 / (nu sigma_c^2)`` and ``h_l = sum_c 2 conj(G_lc) Y_lc / (nu sigma_c^2)``:
    the responses' term of the chi-square is ``x^2 phi' Q phi - 2 x phi' r + const`` for a window force
    ``phi`` (complex circular noise of variance ``sigma_c^2`` per line, ``nu`` the window's noise factor).
    """
    weight = 2.0 / (spectra.noise_factor * sigma2)
    g = np.sum(np.abs(model) ** 2 * weight, axis=1)
    out = []
    for y, d in zip(spectra.responses, spectra.transforms, strict=True):
        h = np.sum(np.conj(model) * y * weight, axis=1)
        q = np.real(np.conj(d).T @ (g[:, None] * d))
        out.append((q, np.real(np.conj(d).T @ h), d))
    return out


def _eiv_forces(x: float, terms: list[tuple[Array, Array, CArray]], spectra: ImpactSpectra) -> list[Array]:
    """The window forces minimising the chi-square for a given ``x = 1 / m``."""
    out = []
    for (q, r, _), f, s in zip(terms, spectra.forces, spectra.force_sigma, strict=True):
        prec = 1.0 / s**2
        out.append(np.asarray(np.linalg.solve(x * x * q + np.diag(prec), x * r + prec * f), dtype=float))
    return out


def _eiv_cost(x: float, terms: list[tuple[Array, Array, CArray]], spectra: ImpactSpectra) -> float:
    """The chi-square minimised over the window forces, less the constant ``sum w |Y|^2``."""
    total = 0.0
    for (q, r, _), f, s, phi in zip(terms, spectra.forces, spectra.force_sigma, _eiv_forces(x, terms, spectra),
                                    strict=True):  # fmt: skip
        total += x * x * float(phi @ q @ phi) - 2.0 * x * float(phi @ r) + float(np.sum(((f - phi) / s) ** 2))
    return total


def _eiv_residuals(x: float, spectra: ImpactSpectra, model: CArray, forces: list[Array],
                   terms: list[tuple[Array, Array, CArray]]) -> CArray:  # fmt: skip
    """The responses' residuals ``Y - x G D phi`` per impact, shape (i, l, p)."""
    return np.asarray([y - x * model * (t[2] @ phi)[:, None]
                       for y, phi, t in zip(spectra.responses, forces, terms, strict=True)])  # fmt: skip


def _eiv_minimise(x0: float, terms: list[tuple[Array, Array, CArray]], spectra: ImpactSpectra) -> float:
    """``x = 1 / m`` minimising :func:`_eiv_cost`, bracketed about `x0`."""
    from scipy.optimize import minimize_scalar

    found = minimize_scalar(
        lambda v: _eiv_cost(float(v), terms, spectra), bracket=(0.98 * x0, x0), method="brent",
        options={"xtol": 1e-10},
    )  # fmt: skip
    return float(found.x)


def _eiv_information(x: float, terms: list[tuple[Array, Array, CArray]], spectra: ImpactSpectra) -> tuple[float, float]:
    """Fisher information of ``x``, the window forces profiled out, and the force channel's share of it.

    Per impact ``phi' Q phi - x^2 phi' Q (x^2 Q + S)^-1 Q phi`` (the Schur complement of the
    Gauss-Newton information, ``S`` the force samples' precision); with noise-free responses it
    becomes ``phi' S phi / x^2``, the force's own information.
    """
    total, force_only = 0.0, 0.0
    for (q, _, _), s, phi in zip(terms, spectra.force_sigma, _eiv_forces(x, terms, spectra), strict=True):
        prec = 1.0 / s**2
        qp = q @ phi
        total += float(phi @ qp) - x * x * float(qp @ np.linalg.solve(x * x * q + np.diag(prec), qp))
        force_only += float(np.sum(prec * phi**2)) / (x * x)
    return total, force_only


def fit_mass_eiv(
    spectra: ImpactSpectra,
    model: CArray,
    start: ForceMass,
    *,
    coherence: float = 1.0,
    sigma2: Array | None = None,
) -> ForceMass:
    """``1 / m`` by errors in variables: the force's noise and the responses' both in the likelihood.

    Parameters
    ----------
    spectra : ImpactSpectra
        The responses' spectra over the band and the forces in their windows (:func:`impact_spectra`).
    model : ndarray of complex, shape (l, p)
        :func:`per_mass_accelerance` at ``s = i w + a`` for the lines of `spectra`.
    start : ForceMass
        The H1 fit (:func:`fit_mass`) on the same band: its ``1 / m`` starts the search, and its
        type-B parts (the gains' tolerances) are kept.
    coherence : float
        Reported as it is (the H1 FRFs' mean coherence over the band).
    sigma2 : ndarray, shape (p,), optional
        The responses' noise variance per line and sensor (:attr:`ForceMass.response_noise` of a
        previous fit): one search from `start`, no re-estimation (for perturbed models).

    Returns
    -------
    ForceMass
        ``noise_std`` from the profile's Fisher information, split into ``force_noise`` (the
        force channel's, ``m / sqrt(sum_i phi_i' S_i phi_i)``) and ``noise`` (the rest).

    Notes
    -----
    The model, per impact ``i``: the window's force samples ``f_i = phi_i + e`` (white, of the
    channel's noise level ``s_i`` measured outside the window), the responses
    ``Y_i(w) = x G(w) D(w) phi_i + E`` with ``D`` the window samples' Fourier transform and ``G``
    the per-mass accelerance (eq. (19) of [1]). The chi-square
    ``sum_i |f_i - phi_i|^2 / s_i^2 + 2 |Y_i - x G D phi_i|^2 / (nu sigma^2)`` is quadratic in
    ``phi_i``: they are solved for in closed form, and ``x`` found by a one-dimensional search.
    Unlike H1 (``S_fy / S_ff``, which takes the measured force as exact and sees its noise only
    in the pulse's area), the true pulse is estimated from both channels, and the force's
    information becomes ``sum phi^2 / s^2`` (its energy over its noise) rather than
    ``(sum phi)^2 / (n s^2)``. The responses' noise ``sigma_c`` per sensor comes from the fit's
    residuals (twice).
    """
    x = 1.0 / start.mass
    forces = [f.copy() for f in spectra.forces]
    given = sigma2 is not None
    noise2 = np.ones(model.shape[1]) if sigma2 is None else np.asarray(sigma2, dtype=float)
    terms = _eiv_terms(spectra, model, noise2)
    for _ in range(1 if given else 3):
        if not given:
            resid = _eiv_residuals(x, spectra, model, forces, terms)
            noise2 = np.maximum(np.mean(np.abs(resid) ** 2, axis=(0, 1)), 1e-300)
            terms = _eiv_terms(spectra, model, noise2)
        x = _eiv_minimise(x, terms, spectra)
        forces = _eiv_forces(x, terms, spectra)
    info, force_info = _eiv_information(x, terms, spectra)
    resid = _eiv_residuals(x, spectra, model, forces, terms)
    misfit = _eiv_misfit(resid, noise2)
    mass = 1.0 / x
    noise = mass * float(np.sqrt(1.0 / (x * x * info))) * max(1.0, misfit) if info > 0 else np.inf
    force_part = min(noise, mass / float(np.sqrt(force_info * x * x))) if force_info > 0 else 0.0
    budget = {
        **start.budget,
        "noise": float(np.sqrt(max(noise**2 - force_part**2, 0.0))),
        "force_noise": float(force_part),
        "sensitivity": start.budget["sensitivity"] * mass / start.mass,
        "force_sensitivity": start.budget["force_sensitivity"] * mass / start.mass,
    }
    w = 1.0 / noise2
    fitted = np.asarray([y - r for y, r in zip(spectra.responses, resid, strict=True)])
    relative = float(np.sqrt(np.sum(np.abs(resid) ** 2 * w) / np.sum(np.abs(fitted) ** 2 * w)))
    return ForceMass(
        mass=mass,
        std=float(np.sqrt(sum(v**2 for v in budget.values()))),
        noise_std=float(noise),
        budget=budget,
        band_hz=(float(spectra.frequency_hz[0]), float(spectra.frequency_hz[-1])),
        lines=int(spectra.frequency_hz.size),
        relative_residual=relative,
        coherence=coherence,
        misfit=misfit,
        estimator="errors-in-variables",
        response_noise=noise2,
    )


def _eiv_misfit(resid: CArray, sigma2: Array) -> float:
    """RMS of the residual over its noise level from third differences along frequency (see :func:`_misfit`)."""
    z = resid / np.sqrt(sigma2)
    if z.shape[1] < 8:
        return 1.0
    noise = float(np.mean(np.abs(np.diff(z, n=3, axis=1)) ** 2)) / 20.0
    return float(np.sqrt(float(np.mean(np.abs(z) ** 2)) / noise)) if noise > 0 else 1.0
