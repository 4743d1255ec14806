"""Modal parameters from free-decay records: the public entry point.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.timedomain.ar import ar_fits, ar_modes, f_test_order
from rigidid.core.timedomain.era import era_basis, era_modes
from rigidid.core.timedomain.gram import lagged_gram
from rigidid.core.timedomain.preprocess import (
    Impact,
    band_limit,
    block_peaks,
    content_from_spectrum,
    content_range,
    content_spectrum,
    decimate_in_stages,
    decimation_for,
    find_impact,
    impact_from_blocks,
    presum,
    stage_factors,
)
from rigidid.core.timedomain.preprocess import decimate as fir_decimate
from rigidid.core.timedomain.stabilisation import Criteria, OrderPoles, cluster_stable, stabilise
from rigidid.errors import IdentificationError, InputError
from rigidid.progress import ProgressCallback

__all__ = ["DEFAULT_METHOD", "METHODS", "ModalEstimate", "block_rows", "decimation_factors", "estimate_modes"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
Method = Literal["ar", "era"]
METHODS: tuple[str, ...] = ("ar", "era")

DEFAULT_METHOD: Method = "era"
"""The default estimator (see the module notes of :func:`estimate_modes` for why)."""

DECIMATION_MARGIN = 4.0  # new Nyquist frequency >= this times the highest frequency kept
MIN_DECIMATED_SAMPLES = 1000  # automatic decimation leaves at least this many samples per record
_MIN_BLOCK_ROWS = 20  # ERA: block rows of the Hankel matrix, at least
_ROW_PERIODS = 2.0  # ERA: block rows span this many periods of the lowest mode
_MAX_GRAM = 384  # ERA: block rows x channels fitted, at most (the Gram matrix is its square)
_RANK_PER_MODE = 2  # principal components kept per mode sought
_AR_EXTRA_STATES = 256  # AR: lags beyond the minimum, times the channels fitted
_AR_SWEEP_MODELS = 16  # AR: about this many orders are solved for poles
_FILTER_WIDENING = 1.25  # band-pass filter edges this factor outside the band of poles kept


@dataclass(frozen=True)
class ModalEstimate:
    """Modes estimated from free decays, and how they were found.

    Attributes
    ----------
    poles : ndarray of complex, shape (n_modes,)
        One pole per mode, ``Im > 0`` (rad/s), ascending frequency.
    shapes : ndarray of complex, shape (channels, n_modes)
        Column ``k`` is the shape of mode ``k`` as each channel (sensor, along
        its own direction) reads it, scaled so its largest value is ``1 + 0j``.
    frequency_hz : ndarray, shape (n_modes,)
        Undamped natural frequencies ``|lambda| / (2 pi)`` (Hz).
    damping_ratio : ndarray, shape (n_modes,)
        ``-Re(lambda) / |lambda|``.
    stable_count : ndarray of int, shape (n_modes,)
        At how many orders of the sweep each mode was stable.
    model_order : ndarray of int, shape (n_modes,)
        The order each mode's values were taken from.
    diagram : tuple of OrderPoles
        The stabilisation diagram: per model order, the physical poles found
        (rad/s, ascending frequency), which of them were stable, and their
        shapes at the channels (unscaled).
    method : str
        ``"ar"`` or ``"era"``.
    sample_interval : float
        Sample interval of the data the models were fitted to, after
        decimation (s).
    decimation : int
        Decimation factor applied (1: none).
    band : (float, float)
        Frequency band physical poles were kept in (Hz).
    channels_fitted : int
        Number of channels (principal components) the models were fitted to.
    adequate_order : int or None
        AR only: the order after which the F-test found no significant
        improvement (the last order of the sweep if every step helped).
    impacts : tuple of Impact
        Per record, where the impact and the free decay were found (sample
        indices of the record as given).
    channels : tuple of int or None
        The record columns the estimate was made from (the rows of `shapes`),
        when some were left out (clipped channels); None: all of them.
    trends : tuple of Trend or None
        Per record, the DC offset and drift taken out of it before the estimation
        (:class:`~rigidid.core.timedomain.trend.Trend`, in the records' rows; None for a
        record where none mattered); None when none was taken out of any record.
    decays : tuple or None
        Per record, the refit's impact and decay read with the records when they were read in
        blocks (:class:`~rigidid.core.timedomain.streaming.CapturedDecay`); None: not read on
        the way (the refit reads the records again).
    """

    poles: CArray
    shapes: CArray
    frequency_hz: Array
    damping_ratio: Array
    stable_count: NDArray[np.int_]
    model_order: NDArray[np.int_]
    diagram: tuple[OrderPoles, ...]
    method: str
    sample_interval: float
    decimation: int
    band: tuple[float, float]
    channels_fitted: int
    adequate_order: int | None
    impacts: tuple[Impact, ...]
    channels: tuple[int, ...] | None = None
    trends: tuple[Any, ...] | None = None
    decays: tuple[Any, ...] | None = None


def _check_records(records: Sequence[ArrayLike], dt: float) -> tuple[list[Array], list[tuple[Array, Array, int]]]:
    """The records as float arrays, checked, and their :func:`block_peaks` (``max |x|`` per channel and block)."""
    try:
        step = float(dt)
    except (TypeError, ValueError):
        step = math.nan
    if not (math.isfinite(step) and step > 0.0):
        raise InputError(f"the sample interval must be positive, got {dt}")
    arrays: list[Array] = []
    peaks: list[tuple[Array, Array, int]] = []
    for i, rec in enumerate(records):
        a = np.asarray(rec, dtype=float)
        if a.ndim != 2 or a.shape[0] < 2 or a.shape[1] < 1:
            raise InputError(f"a record must be samples x channels, got shape {a.shape}", location=f"record {i + 1}")
        if arrays and a.shape[1] != arrays[0].shape[1]:
            raise InputError(
                f"{a.shape[1]} channels, the first record has {arrays[0].shape[1]}", location=f"record {i + 1}"
            )
        blocks = block_peaks(a)  # NaN and infinities reach the peaks: no boolean copy of the record
        if not np.isfinite(blocks[0]).all():
            raise InputError("a value is NaN or infinite", location=f"record {i + 1}")
        arrays.append(a)
        peaks.append(blocks)
    if not arrays:
        raise InputError("no records")
    return arrays, peaks


_SAFE_PEAK = 2.0**200
"""Records whose largest value is above this or below its inverse are scaled by a power of two first."""


def _in_range(
    arrays: list[Array], peaks: list[tuple[Array, Array, int]], energies: Sequence[Array] | None
) -> tuple[list[Array], list[tuple[Array, Array, int]], Sequence[Array] | None]:
    """The records (their peaks and energies) scaled together by a power of two when their largest value is
    outside ``[2^-200, 2^200]``: squares and lagged products then neither overflow nor underflow (records of
    1e300 or 1e-300). A common factor changes no estimate: the channels are scaled by their RMS and the shapes
    normalised anyway."""
    top = max((float(np.max(p[0])) if p[0].size else 0.0 for p in peaks), default=0.0)
    if top == 0.0 or 1.0 / _SAFE_PEAK <= top <= _SAFE_PEAK:
        return arrays, peaks, energies
    k = -math.frexp(top)[1]  # the largest value in [0.5, 1)
    scaled = [np.ldexp(a, k) for a in arrays]
    moved = [(np.ldexp(p, k), np.ldexp(m, k), rows) for p, m, rows in peaks]
    power = None if energies is None else [np.ldexp(np.asarray(e, dtype=float), 2 * k) for e in energies]
    return scaled, moved, power


def _scales_and_covariance(decays: list[Array]) -> tuple[Array, Array]:
    """Per-channel RMS over all decays and their summed product ``sum_k d_k^T d_k`` (one matrix product each)."""
    m = decays[0].shape[1]
    cov = np.zeros((m, m))
    count = 0
    for d in decays:
        cov += d.T @ d
        count += d.shape[0]
    rms: Array = np.sqrt(np.clip(np.diag(cov), 0.0, None) / max(count, 1))
    dead = np.flatnonzero(rms <= 0.0)
    if dead.size:
        raise InputError("the channel reads zero in every record", location=f"channel {dead[0] + 1}")
    return rms, cov


def _principal_basis(cov: Array, rank: int) -> Array:
    """Orthonormal basis (m, rank) of the leading principal components of a (scaled) product matrix."""
    _, vectors = np.linalg.eigh(cov)
    basis: Array = vectors[:, ::-1][:, :rank]
    return basis


def _scaled_gram(fitted: list[Array], lags: int, scale: Array | None) -> tuple[Array, int]:
    """``lagged_gram`` of ``fitted * scale`` (channel-wise; None: of `fitted`), computed on `fitted` as given."""
    gram, columns = lagged_gram(fitted, lags)
    if scale is not None:
        weights = np.tile(scale, lags + 1)
        gram *= weights[:, None]
        gram *= weights[None, :]
    return gram, columns


def _normalise_shapes(shapes: CArray) -> CArray:
    if shapes.shape[1] == 0:
        return shapes
    peak = shapes[np.argmax(np.abs(shapes), axis=0), np.arange(shapes.shape[1])]
    result: CArray = shapes / np.where(peak == 0, 1.0, peak)
    return result


def estimate_modes(
    records: Sequence[ArrayLike],
    dt: float,
    *,
    method: Method = DEFAULT_METHOD,
    n_modes: int = 6,
    band: tuple[float, float] | None = None,
    max_order: int | None = None,
    decimate: int | None = None,
    trim: bool = True,
    pulse_width: float = 0.005,
    criteria: Criteria | None = None,
    progress: ProgressCallback | None = None,
    energies: Sequence[Array] | None = None,
    content: tuple[float, float] | None = None,
    settle: int = 0,
) -> ModalEstimate:
    """Natural frequencies, damping ratios and complex mode shapes from impact records.

    Parameters
    ----------
    records : sequence of array_like, shape (n_k, channels)
        One record per impact, samples by channels, the same channels in every
        record: accelerations (any consistent unit) read by each sensor along
        its own direction. Pre-trigger samples before the impact may be
        present; different impacts may excite different modes, but together
        they must excite all `n_modes`.
    dt : float
        Sample interval of the records (s).
    method : {"era", "ar"}
        ``"era"`` (default): the Eigensystem Realization Algorithm in Gram
        form, with the white-noise floor removed
        (:mod:`~rigidid.core.timedomain.era`). ``"ar"``: vector
        autoregressive models of increasing order fitted by least squares, the
        Data Dependent Systems approach of [1]
        (:mod:`~rigidid.core.timedomain.ar`).
    n_modes : int
        Number of modes to return (6 for the rigid-body modes).
    band : (float, float), optional
        Frequency band of interest (Hz): only poles strictly inside it are
        kept, and, when the records hold content more than 25 % above the
        band, the decimated records are low-pass filtered (zero-phase
        Butterworth, order 4) 25 % above it. A band that holds all the
        content changes nothing but the poles kept (no high-pass or
        band-pass filter: its start-up transient on the abrupt start of a
        free decay costs accuracy). Default: 0 to the Nyquist frequency
        after decimation.
    max_order : int, optional
        Highest model order of the sweep: the number of lags of the AR model,
        or the number of states of the ERA realization. Default: AR
        ``ceil(2 n_modes / r) + ceil(256 / r)`` lags, ERA
        ``max(8 n_modes, 48)`` states, with ``r`` the number of channels
        fitted (see Notes).
    decimate : int, optional
        Decimation factor. Default: chosen so that the new Nyquist frequency
        is at least 4 times the highest frequency standing out of the noise
        floor of the spectrum
        (:func:`~rigidid.core.timedomain.preprocess.content_range`), or the
        band's upper edge if that is lower (:func:`decimation_factors`: a band
        never decimates less than no band); if fewer than `n_modes` modes are
        then found, the estimation is repeated with the factor divided by 3
        until it is 1. An automatic factor leaves at least 1000 samples in the
        shortest record. 1 disables decimation.
    trim : bool
        Find the impact in each record and keep only the free decay after it
        (:func:`~rigidid.core.timedomain.preprocess.find_impact`). With false
        the records are used whole and must hold only free decay.
    pulse_width : float
        Longest expected duration of the impact force (s), for the trimming.
    criteria : Criteria, optional
        Stabilisation tolerances (default: frequency 0.5 %, damping 5 %, MAC
        0.98, damping ratio below 30 %).
    progress : ProgressCallback, optional
        Called with ``("decimating", done, records)`` and ``("model-order
        sweep", done, orders)`` (:mod:`rigidid.progress`).
    energies : sequence of ndarray, shape (n_k,), optional
        ``channel_energy`` of each record when the caller has it (the record
        reader computes it for its decay check): used to find the impacts.
    content : (float, float), optional
        ``content_range`` of the free decays when the caller measured it (the
        streamed reader, on the records before it decimated them).
    settle : int
        Samples dropped after each impact's free-decay start: for records
        decimated before they were trimmed (the streamed reader's second
        stage), the anti-alias filter's reach (``FIR_HALF_LENGTH``), so the
        decay holds no sample the filter spread the impact into, as when
        the decay is decimated after trimming.

    Returns
    -------
    ModalEstimate

    Raises
    ------
    InputError
        For records that are not 2-D, differ in channel count, hold NaN or
        infinite values, or are too short; a channel that is zero in every
        record; invalid options.
    IdentificationError
        When fewer than `n_modes` stable modes are found.

    Notes
    -----
    Steps: (1) trim each record to its free decay; (2) decimate with a
    zero-phase FIR anti-alias filter (:func:`~rigidid.core.timedomain.preprocess.decimate`);
    (3) band-pass filter if a band is given;
    (4) scale each channel to unit RMS and, with more than ``2 n_modes``
    channels, project on the ``2 n_modes`` leading principal components
    (shapes are mapped back to every channel afterwards); (5) accumulate the
    lagged Gram matrix of all records at once, so memory does not grow with
    record length; (6) sweep the model order, keep physical poles (inside the
    band, damping ratio between 0 and 30 %), mark those stable against the
    previous order; (7) cluster the stable poles and return the `n_modes`
    found stable at the most orders (a cluster must be stable at a third of
    the orders or more). AR solves about 16 orders spread over its sweep for
    poles, ERA every even number of states.

    Why ERA is the default: on simulated records of 20 random bodies (8
    sensors, 3 impacts) both methods found all modes at 1 % noise, ERA with a
    median damping error of 0.2 % (AR 0.25 %, worst 0.7 % against 1.6 %); at
    5 % noise ERA's median damping error was 0.55 % against AR's 2 % (worst
    11 % and 18 %), its shapes better (MAC >= 0.9992 against 0.992). ERA is
    also several times faster (one symmetric eigenproblem, then small ones;
    AR solves a companion matrix of ``p r`` states per order) and needs no
    scipy. AR is kept because it is the paper's approach.

    Limits: modes must be underdamped (damping ratio below 30 %) and separated
    by more than the frequency tolerance (0.5 %); two modes of nearly equal
    frequency need records long enough to resolve them (several times
    ``1 / (f2 - f1)``) and shapes that differ. Noise is assumed white and
    roughly proportional to each channel's level. A mode excited by no record
    is not found. The representative values of a mode come from one order of
    the sweep (see :func:`~rigidid.core.timedomain.stabilisation.cluster_stable`).
    """
    decays_in, peaks = _check_records(records, dt)
    decays_in, peaks, energies = _in_range(decays_in, peaks, energies)
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if not (isinstance(n_modes, int) and n_modes >= 1):
        raise InputError(f"the number of modes must be a positive integer, got {n_modes}")
    if band is not None:
        low, high = float(band[0]), float(band[1])
        if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low < high):
            raise InputError(f"the band must be two frequencies 0 <= low < high, got {band}")
    if decimate is not None and not (isinstance(decimate, int) and decimate >= 1):
        raise InputError(f"the decimation factor must be a positive integer, got {decimate}")
    if max_order is not None and not (isinstance(max_order, int) and max_order >= 1):
        raise InputError(f"the maximum order must be a positive integer, got {max_order}")
    if max_order is not None and method == "era" and max_order < 2 * n_modes:
        raise InputError(
            f"must be at least {2 * n_modes} for {n_modes} modes (an ERA model of n states holds n/2 modes), "
            f"got {max_order}",
            source="max_order",
        )
    if not (math.isfinite(pulse_width) and pulse_width > 0.0):
        raise InputError(f"the pulse width must be positive, got {pulse_width}")
    crit = criteria if criteria is not None else Criteria()
    dt = float(dt)

    # (1) free decays
    impacts: list[Impact] = []
    decays: list[Array] = []
    for k, rec in enumerate(decays_in):
        energy = energies[k] if energies is not None and k < len(energies) else None
        if not trim:
            impact = Impact(0, 0, 0)
        elif energy is not None:
            impact = find_impact(rec, dt, pulse_width=pulse_width, energy=energy)
        else:  # the energy of the few rows that can hold the impact, not of every row
            impact = impact_from_blocks(rec, dt, *peaks[k], pulse_width=pulse_width)
        if trim and settle > 0:
            impact = replace(impact, start=min(impact.start + int(settle), rec.shape[0] - 1))
        impacts.append(impact)
        decays.append(rec[impact.start :])

    # (2) decimation factor; automatic factors are retried smaller if modes are missing
    if content is None:
        content = content_range(decays, dt)
    presummed: dict[int, list[Array]] = {}
    if decimate is None:
        content = _finer_content(decays, dt, band, content, presummed)
    factors = [decimate] if decimate is not None else decimation_factors(decays, dt, band, content)
    options = _Options(method, n_modes, band, max_order, crit, content, progress)
    for attempt, factor in enumerate(factors):
        try:
            reduced, used = _decimated(
                decays, factor, exact=decimate is not None, presummed=presummed, progress=progress
            )
            result = _estimate(reduced, dt, used, options)
        except IdentificationError:
            if attempt == len(factors) - 1:
                raise
            continue
        return replace(result, impacts=tuple(impacts))
    raise AssertionError("unreachable")


def decimation_factors(
    decays: Sequence[Array], dt: float, band: tuple[float, float] | None, content: tuple[float, float]
) -> list[int]:
    """Decimation factors to try, first the largest the band allows.

    Parameters
    ----------
    decays : sequence of ndarray, shape (n_k, p)
        Free decays.
    dt : float
        Sample interval (s).
    band : (float, float) or None
        The user's band (Hz).
    content : (float, float)
        Lowest and highest frequency standing out of the noise floor
        (:func:`~rigidid.core.timedomain.preprocess.content_range`).

    Returns
    -------
    list of int
        Descending factors, ending at 1: the first keeps the new Nyquist
        frequency 4 times above the highest frequency kept, which is the
        band's upper edge or, if lower, the detected content (a band reaching
        beyond the content must not cost resolution); each next one is a
        third of the previous. The first leaves at least 1000 samples in the
        shortest record.

    Notes
    -----
    A band only ever lowers the highest frequency kept, so passing a band
    never decimates less than passing none.
    """
    f_high = content[1]
    if band is not None:
        f_high = min(float(band[1]), f_high)
    first = decimation_for(f_high, dt, margin=DECIMATION_MARGIN)
    shortest = min(d.shape[0] for d in decays)
    factors = [max(1, min(first, shortest // MIN_DECIMATED_SAMPLES))]
    while factors[-1] > 1:
        factors.append(max(1, factors[-1] // 3))
    return factors


def block_rows(n_states: int, channels: int, n_modes: int, samples: int, dt: float, f_low: float) -> int:
    """Block rows of the ERA Hankel matrix.

    Parameters
    ----------
    n_states : int
        Largest model order of the sweep.
    channels : int
        Channels (principal components) fitted.
    n_modes : int
        Modes sought.
    samples : int
        Samples in the shortest (decimated) record.
    dt : float
        Sample interval after decimation (s).
    f_low : float
        Lowest frequency of interest (Hz), 0 if unknown.

    Returns
    -------
    int
        At least enough rows for the model order and 20; raised so the rows
        span two periods of the lowest frequency (what separates close
        modes there: their resolution grows with the span of lags), but at
        most a quarter of the shortest record and 384 rows x channels.
    """
    rows = max(math.ceil(n_states / channels) + 1, math.ceil(8 * n_modes / channels), _MIN_BLOCK_ROWS)
    if f_low > 0.0:
        span = math.ceil(_ROW_PERIODS / (f_low * dt))
        cap = min(samples // 4, _MAX_GRAM // max(channels, 1))
        rows = max(rows, min(span, cap))
    return rows


@dataclass(frozen=True)
class _Options:
    method: str
    n_modes: int
    band: tuple[float, float] | None
    max_order: int | None
    criteria: Criteria
    content: tuple[float, float] = (0.0, math.inf)
    progress: ProgressCallback | None = None


def _finer_content(
    decays: list[Array],
    dt: float,
    band: tuple[float, float] | None,
    content: tuple[float, float],
    presummed: dict[int, list[Array]],
) -> tuple[float, float]:
    """The content range again, on the decays presummed by the first stage of the first factor.

    The spectrum at the records' rate resolves ``1 / (4096 dt)``: on a record
    sampled far above its modes (50 kHz, modes below 30 Hz) the modes fill
    its lowest bins and their window leakage reaches a few bins further, so
    the content seems to reach 5 times higher than it does and the factor
    comes out 5 times too small. The decays presummed by ``q1`` (the first
    stage of :func:`stage_factors` of the factor that content allows) are
    judged again, ``q1`` times finer, up to the Nyquist frequency of that
    factor (where the presum folds nothing onto the band). The presummed
    decays are kept in `presummed` for the decimation. Returns `content`
    unchanged when the factor is too small for two stages or nothing
    stands out of the finer spectrum.
    """
    factor = decimation_factors(decays, dt, band, content)[0]
    q1, _ = stage_factors(factor)
    if q1 <= 1:
        return content
    presummed[q1] = [presum(d, q1) for d in decays]
    freqs, total = content_spectrum(presummed[q1], dt * q1)
    keep = freqs <= 0.5 / (dt * factor)
    if np.count_nonzero(keep) < 16:
        return content
    low, high = content_from_spectrum(freqs[keep], total[keep], 0.5 / (dt * factor))
    if high >= 0.5 / (dt * factor):  # nothing stood out
        return content
    return low, high


def _decimated(
    decays: list[Array],
    factor: int,
    *,
    exact: bool,
    presummed: dict[int, list[Array]],
    progress: ProgressCallback | None,
) -> tuple[list[Array], int]:
    """The decays decimated by about `factor` in two stages (:func:`stage_factors`), and the factor used."""
    if factor <= 1:
        return decays, 1
    first, second = stage_factors(factor, exact=exact)
    for q1 in presummed:  # a first stage already computed serves any factor it leaves 4 or more of
        if factor // q1 >= 4 and (not exact or factor % q1 == 0):
            first, second = q1, factor // q1
    done: list[Array] = []
    for k, d in enumerate(decays):
        if progress is not None:
            progress("decimating", k, len(decays))
        if first > 1 and first in presummed:
            done.append(fir_decimate(presummed[first][k], second))
        else:
            done.append(decimate_in_stages(d, first, second))
    if progress is not None:
        progress("decimating", len(decays), len(decays))
    return done, first * second


def _estimate(decays: list[Array], dt: float, factor: int, options: _Options) -> ModalEstimate:
    """Steps (3)-(7) of :func:`estimate_modes` on the decays decimated by `factor` (sample interval `dt`)."""
    n_modes, band = options.n_modes, options.band
    dt_fit = dt * factor
    nyquist_fit = 0.5 / dt_fit

    # (3) band limit
    if band is not None:
        fit_band = (float(band[0]), min(float(band[1]), nyquist_fit))
        # low-pass only, and only with content above the band: a high-pass or
        # band-pass filter's start-up transient on the abrupt start of a free
        # decay costs accuracy (offsets and drift give poles at 0 Hz, outside
        # the band, anyway), so a band holding all the content filters nothing
        high_edge = fit_band[1] * _FILTER_WIDENING
        if options.content[1] > high_edge and high_edge < nyquist_fit:
            decays = [band_limit(d, dt_fit, (0.0, high_edge)) for d in decays]
    else:
        fit_band = (0.0, nyquist_fit)

    # (4) scaling and principal components
    # no scaled copy of the decays: the scaling is folded into the projection, or into the Gram matrix
    m = decays[0].shape[1]
    scales, cov = _scales_and_covariance(decays)
    inverse = 1.0 / scales
    r = min(m, _RANK_PER_MODE * n_modes)
    if r < m:
        basis = _principal_basis(cov * np.outer(inverse, inverse), r)
        fitted = [x @ (inverse[:, None] * basis) for x in decays]
        unscale: Array | None = None
    else:
        basis = np.eye(m)
        fitted = decays
        unscale = inverse
    to_sensors = scales[:, None] * basis

    # (5)-(6) sweep
    models: list[tuple[int, CArray, CArray]] = []
    adequate: int | None = None
    if options.method == "ar":
        adequate = _ar_sweep(fitted, unscale, to_sensors, r, dt_fit, options, models)
    else:
        _era_sweep(fitted, unscale, to_sensors, r, dt_fit, options, models)

    # (7) stabilisation and selection
    diagram = stabilise(models, fit_band, options.criteria)
    min_count = max(3, math.ceil(len(models) / 3))
    clusters = cluster_stable(diagram, frequency=options.criteria.frequency, min_count=min_count)
    if len(clusters) < n_modes:
        raise IdentificationError(
            f"found {len(clusters)} stable mode{'s' if len(clusters) != 1 else ''}, {n_modes} needed; "
            "narrow the frequency band (`band`) or raise the model order (`max_order`)"
        )
    chosen = sorted(clusters[:n_modes], key=lambda c: abs(c.pole))
    poles_out = np.array([c.pole for c in chosen], dtype=complex)
    shapes_out = _normalise_shapes(np.stack([c.shape for c in chosen], axis=1).astype(complex))
    w = np.abs(poles_out)
    return ModalEstimate(
        poles=poles_out,
        shapes=shapes_out,
        frequency_hz=w / (2.0 * np.pi),
        damping_ratio=-poles_out.real / w,
        stable_count=np.array([c.count for c in chosen], dtype=int),
        model_order=np.array([c.order for c in chosen], dtype=int),
        diagram=tuple(diagram),
        method=options.method,
        sample_interval=dt_fit,
        decimation=factor,
        band=fit_band,
        channels_fitted=r,
        adequate_order=adequate,
        impacts=(),
    )


def _ar_sweep(
    fitted: list[Array],
    unscale: Array | None,
    to_sensors: Array,
    r: int,
    dt_fit: float,
    options: _Options,
    models: list[tuple[int, CArray, CArray]],
) -> int:
    """Steps (5)-(6) with vector AR: models up to a few orders past the adequate one (F test) into `models`."""
    n_modes, max_order = options.n_modes, options.max_order
    min_samples = min(f.shape[0] for f in fitted)
    p_min = max(1, math.ceil(2 * n_modes / r))
    p_max = max_order if max_order is not None else p_min + math.ceil(_AR_EXTRA_STATES / r)
    if p_max < p_min:
        raise InputError(f"must be at least {p_min}: the AR lags {n_modes} modes need, got {p_max}", source="max_order")
    if min_samples <= 2 * p_max + 1:
        raise InputError(f"records too short ({min_samples} samples after trimming) for AR order {p_max}")
    gram, columns = _scaled_gram(fitted, p_max, unscale)
    orders = list(range(p_min, p_max + 1))
    fits = ar_fits(gram, r, orders)
    adequate = f_test_order([f.rss for f in fits], orders, columns, r)
    stop = min(p_max, max(adequate + 4, p_min + 8))
    step = max(1, math.ceil((stop - p_min) / _AR_SWEEP_MODELS))
    for fit in fits[stop - p_min :: -step][::-1]:
        poles, shapes = ar_modes(fit, dt_fit)
        models.append((fit.order, poles, to_sensors @ shapes))
    return adequate


def _era_sweep(
    fitted: list[Array],
    unscale: Array | None,
    to_sensors: Array,
    r: int,
    dt_fit: float,
    options: _Options,
    models: list[tuple[int, CArray, CArray]],
) -> None:
    """Steps (5)-(6) with Gram-form ERA: the models of every even order up to the highest into `models`."""
    n_modes, max_order = options.n_modes, options.max_order
    min_samples = min(f.shape[0] for f in fitted)
    n_max = max_order if max_order is not None else max(8 * n_modes, 48)
    n_max += n_max % 2
    rows = block_rows(n_max, r, n_modes, min_samples, dt_fit, options.content[0])
    if min_samples <= 2 * rows + 1:
        raise InputError(f"records too short ({min_samples} samples after trimming) for {rows} Hankel block rows")
    gram, _ = _scaled_gram(fitted, rows, unscale)
    basis_era = era_basis(gram, r, max_order=n_max)
    for n in range(2, n_max + 1, 2):
        if options.progress is not None:
            options.progress("model-order sweep", n // 2 - 1, n_max // 2)
        poles, shapes = era_modes(basis_era, n, dt_fit)
        models.append((n, poles, to_sensors @ shapes))
