"""Modes from FRFs: poles by pLSCF with a stabilisation diagram, residues by least squares, scaled shapes.

The poles come from the poly-reference least-squares complex frequency-domain
estimator (pLSCF): for every order ``n`` of a sweep, a right matrix-fraction
model ``H(w) = B(z) A(z)^-1`` with ``z = exp(i w dt)`` and ``A`` a ``q x q``
matrix polynomial common to all responses is fitted by linear least squares
(weighted to relative errors), and the poles are the roots of ``det A(z)``.
The sweep goes through the stabilisation diagram of the time-domain route
(:func:`rigidid.core.timedomain.stabilisation.stabilise`, ``cluster_stable``).
With the poles known, the residues ``R_k`` (``p x q``) follow by least squares
in the frequency domain (LSFD) on the accelerance

``H(w) = -w^2 sum_k [R_k / (i w - l_k) + conj(R_k) / (i w - conj(l_k))] + L + U w^2``

with a lower residual ``L`` (modes below the band) and an upper residual ``U``
(modes above it), both optional. For a rigid body the residue of a mode with
unity-modal-A scaling is ``T u u^T T_f^T`` (``u``: the mode in rigid-body
coordinates), so the force scales the shapes, and the six scaled rigid-body
modes give the mass matrix, the stiffness and the damping in absolute units:

``M^-1 = sum 2 Re(l u u^T)``, ``K^-1 = -sum 2 Re(u u^T / l)``,
``M^-1 C M^-1 = -sum 2 Re(l^2 u u^T)``

(the expansion of the receptance ``(M s^2 + C s + K)^-1`` at large and at
zero ``s``).

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
.. [2] B. Peeters, H. Van der Auweraer, P. Guillaume, J. Leuridan, "The
   PolyMAX frequency-domain method: a new standard for modal parameter
   estimation?", Shock and Vibration 11 (2004) 395-409.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.frfstats import local_noise, misfit_units, sandwich_variance
from rigidid.core.geometry import sensor_matrix, transfer_matrix
from rigidid.core.linalg import pseudo_inverse
from rigidid.core.timedomain.stabilisation import Cluster, Criteria, OrderPoles, cluster_stable, stabilise
from rigidid.errors import IdentificationError, InputError
from rigidid.progress import ProgressCallback

__all__ = [
    "FrfModes",
    "PeakShortfall",
    "ResidueLimit",
    "ScaledBody",
    "body_from_frfs",
    "body_from_scaled_modes",
    "body_from_scaled_shapes",
    "fit_frf_modes",
    "peak_shortfall",
    "peak_split",
    "plscf_poles",
    "prominent_peaks",
    "refine_poles",
    "refine_rigid_modes",
    "residue_limit",
    "residues_lsfd",
    "rigid_band",
    "rigid_shapes",
    "rigid_six",
    "summed_power",
    "with_nonrigid_residual",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

MIN_LINES = 20
"""Fewest frequency lines in the band of a modal fit."""


@dataclass(frozen=True)
class FrfModes:
    """Modes fitted to FRFs.

    Attributes
    ----------
    poles : ndarray of complex, shape (n,)
        Poles (rad/s, ``Im > 0``), ascending frequency.
    residues : ndarray of complex, shape (n, p, q)
        Receptance residues ``R_k`` (length / force / s).
    shapes : ndarray of complex, shape (p, n)
        Mode shapes at the sensors: the left factor of the rank-one fit of each
        residue, unity-modal-A scaled (``R_k ~ shape_k participation_k^T``)
        when `scaled` is true for that mode, else scaled so the largest value
        is ``1 + 0j``. Scaled shapes are the rigid-body projection ``T u_k``
        plus the left factor's part that no rigid-body motion explains
        (:func:`with_nonrigid_residual`): eq. (18) and the mass see only
        ``T u_k``, the noise estimate of an uncertainty sees the rest.
    participation : ndarray of complex, shape (q, n)
        The right factor (the shape at the references, along the force).
    scaled : ndarray of bool, shape (n,)
        Whether each shape is scaled by the force (rigid-body modes: see
        :func:`fit_frf_modes`).
    stable_count : ndarray of int, shape (n,)
        Orders of the sweep at which each mode was stable.
    diagram : tuple of OrderPoles
        The stabilisation diagram (per polynomial order: poles, stable flags,
        shapes at the sensors).
    band : (float, float)
        Band of the pole fit (Hz).
    residue_band : (float, float)
        Band of the residue fit (Hz).
    lower, upper : ndarray of complex, shape (p, q)
        Lower residual (accelerance constant) and upper residual (coefficient
        of ``(w / w_top)^2``); zero when not fitted.
    residual : float
        RMS misfit of the LSFD model relative to the RMS of the data
        (weighted as fitted).
    """

    poles: CArray
    residues: CArray
    shapes: CArray
    participation: CArray
    scaled: NDArray[np.bool_]
    stable_count: NDArray[np.int_]
    diagram: tuple[OrderPoles, ...]
    band: tuple[float, float]
    residue_band: tuple[float, float]
    lower: CArray
    upper: CArray
    residual: float

    @property
    def frequency_hz(self) -> Array:
        """Undamped natural frequencies ``|lambda| / (2 pi)`` (Hz)."""
        result: Array = np.abs(self.poles) / (2.0 * np.pi)
        return result

    @property
    def damping_ratio(self) -> Array:
        """``-Re(lambda) / |lambda|``."""
        result: Array = -self.poles.real / np.abs(self.poles)
        return result


@dataclass(frozen=True)
class ScaledBody:
    """Mass, CG, inertia, stiffness and damping from six scaled rigid-body modes.

    Attributes
    ----------
    mass : float
        Mass (1 / accelerance unit).
    center_of_gravity : ndarray, shape (3,)
        Layout coordinates (length).
    inertia_tensor : ndarray, shape (3, 3)
        About the CG (mass length^2), tensor convention.
    stiffness_matrix, damping_matrix : ndarray, shape (6, 6)
        Support stiffness (mass / s^2) and damping (mass / s) at the CG, DOF
        order x, y, z, rx, ry, rz (rotations in radians).
    mass_matrix : ndarray, shape (6, 6)
        The mass matrix at the CG, as fitted (its translational block is not
        forced to ``m I``).
    """

    mass: float
    center_of_gravity: Array
    inertia_tensor: Array
    stiffness_matrix: Array
    damping_matrix: Array
    mass_matrix: Array


def rigid_band(frequencies: ArrayLike, frf: ArrayLike) -> tuple[tuple[float, float], tuple[float, float]]:
    """Default bands of the modal fit: poles of the rigid-body modes, and their residues.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz, ascending.
    frf : array_like of complex, shape (p, q, f)
        Accelerance.

    Returns
    -------
    poles : (float, float)
        From the first line to twice the highest rigid-body peak (at most the
        geometric mean of it and the first elastic peak, at most the last line).
    residues : (float, float)
        From the first line to half the first elastic peak, or the last line.

    Notes
    -----
    Peaks of ``sum |H|^2`` standing a factor 2 above their valleys; they are
    split into rigid and elastic ones by :func:`peak_split` (one cluster: all
    rigid). Without any peak, both bands are every line.
    """
    freq, h = _check(frequencies, frf)
    fp, split = peak_split(freq, h)
    first, last = float(freq[0]), float(freq[-1])
    if fp.size == 0:
        return (first, last), (first, last)
    if split is not None:
        top, elastic = float(fp[split]), float(fp[split + 1])
        return (first, min(2.0 * top, float(np.sqrt(top * elastic)))), (first, 0.5 * elastic)
    top = float(fp[-1])
    return (first, min(2.0 * top, last)), (first, last)


PEAK_SPLIT_RATIO = 4.0
"""Neighbouring FRF peaks further apart than this frequency ratio are taken for the last rigid-body
mode and the first elastic one (:func:`peak_split`; the mass line's band then needs a ratio above 6,
3x the one to half the other)."""


def summed_power(frf: ArrayLike) -> Array:
    """``sum |H|^2`` over responses and references per line (plus the smallest float: its log is finite).

    Parameters
    ----------
    frf : array_like of complex, shape (p, q, f)
        Accelerance.

    Returns
    -------
    ndarray, shape (f,)
    """
    s: Array = np.sum(np.abs(np.asarray(frf)) ** 2, axis=(0, 1)) + np.finfo(float).tiny
    return s


def prominent_peaks(x: ArrayLike, prominence: float) -> NDArray[np.intp]:
    """Indices of the local maxima of `x` that stand at least `prominence` above their higher valley.

    The peaks and prominences of ``scipy.signal.find_peaks(x, prominence=...)``,
    in a few lines of numpy (``scipy.signal`` costs about a second to import).

    Parameters
    ----------
    x : array_like, shape (n,)
        Finite samples.
    prominence : float
        The least prominence kept (units of `x`).

    Returns
    -------
    ndarray of int, shape (k,)
        Ascending indices. A flat top counts once, at its middle sample (the left
        one of the two middle samples); a top at either end of `x` is no peak.

    Notes
    -----
    The prominence of a peak is its height above the higher of its two bases: the
    lowest sample on each side before a sample higher than the peak (or the end).
    """
    v = np.asarray(x, dtype=float).reshape(-1)
    if v.size < 3:
        return np.zeros(0, dtype=np.intp)
    starts = np.flatnonzero(np.r_[True, v[1:] != v[:-1]])  # runs of equal samples
    ends = np.r_[starts[1:], v.size] - 1
    level = v[starts]
    top = np.flatnonzero((level[1:-1] > level[:-2]) & (level[1:-1] > level[2:])) + 1
    peaks: NDArray[np.intp] = (starts[top] + ends[top]) // 2
    keep = []
    for i in peaks:
        higher_left = np.flatnonzero(v[:i] > v[i])
        higher_right = np.flatnonzero(v[i + 1 :] > v[i])
        lo = higher_left[-1] + 1 if higher_left.size else 0
        hi = i + 1 + higher_right[0] if higher_right.size else v.size
        base = max(float(np.min(v[lo : i + 1])), float(np.min(v[i:hi])))
        keep.append(v[i] - base >= prominence)
    kept: NDArray[np.intp] = peaks[np.asarray(keep, dtype=bool)] if keep else peaks
    return kept


def peak_split(frequencies: Array, frf: CArray) -> tuple[Array, int | None]:
    """The peaks of the FRFs and where they split into rigid-body and elastic ones.

    Parameters
    ----------
    frequencies : ndarray, shape (f,)
        Hz, ascending.
    frf : ndarray of complex, shape (p, q, f)
        Accelerance.

    Returns
    -------
    peaks : ndarray
        Frequencies (Hz) of the maxima of ``sum |H|^2`` standing a factor 2 above both
        neighbouring valleys.
    split : int or None
        Index of the last rigid-body peak when the largest ratio between neighbouring
        peaks exceeds :data:`PEAK_SPLIT_RATIO` (the next peak is the first elastic one);
        None: one cluster, all rigid.
    """
    idx = prominent_peaks(np.log(summed_power(frf)), np.log(2.0))
    fp: Array = np.asarray(frequencies, dtype=float)[idx]
    ratios = fp[1:] / fp[:-1]
    if ratios.size and ratios.max() > PEAK_SPLIT_RATIO:
        return fp, int(np.argmax(ratios))
    return fp, None


def _band_lines(f: Array, band: tuple[float, float] | None) -> tuple[tuple[float, float], NDArray[np.bool_]]:
    lo, hi = (float(f[0]), float(f[-1])) if band is None else (float(band[0]), float(band[1]))
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 <= lo < hi):
        raise InputError(f"band must be two frequencies low < high, got {band}")
    sel = (f >= lo) & (f <= hi)
    n = int(np.count_nonzero(sel))
    if n < MIN_LINES:
        raise InputError(f"band {lo:g}-{hi:g} Hz holds {n} frequency lines, need at least {MIN_LINES}")
    return (lo, hi), sel


def _check(f: ArrayLike, frf: ArrayLike) -> tuple[Array, CArray]:
    freq = np.asarray(f, dtype=float).reshape(-1)
    h = np.asarray(frf, dtype=complex)
    if h.ndim != 3 or h.shape[2] != freq.size:
        raise InputError(f"frf must have shape (sensors, references, frequencies), got {h.shape} for {freq.size} lines")
    if freq.size < 2 or np.any(np.diff(freq) <= 0.0) or freq[0] <= 0.0:
        raise InputError("frequencies must be positive and ascending")
    if not (np.all(np.isfinite(h)) and np.all(np.isfinite(freq))):
        raise InputError("frf holds NaN or infinite values")
    return freq, h


def _weights(h: CArray, weighting: str) -> Array:
    """Per response and line (p, f): 1 / RMS over the references, floored at 1e-3 of its median."""
    if weighting == "none":
        return np.ones((h.shape[0], h.shape[2]))
    if weighting != "relative":
        raise InputError(f"weighting must be 'relative' or 'none', got {weighting!r}")
    mag = np.sqrt(np.mean(np.abs(h) ** 2, axis=1))
    floor = 1e-3 * np.median(mag, axis=1, keepdims=True) + np.finfo(float).tiny
    result: Array = 1.0 / np.maximum(mag, floor)
    return result


def plscf_poles(
    frequencies: ArrayLike,
    frf: ArrayLike,
    orders: range | list[int],
    *,
    band: tuple[float, float] | None = None,
    weighting: str = "relative",
) -> list[tuple[int, CArray, CArray]]:
    """Poles and shapes of pLSCF models of several orders (the input of a stabilisation diagram).

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz, ascending, positive.
    frf : array_like of complex, shape (p, q, f)
        FRFs (any consistent type; accelerance here).
    orders : sequence of int
        Polynomial orders ``n`` (each model has ``n q`` poles), ascending.
    band : (float, float), optional
        Band of the fit (Hz); all lines by default.
    weighting : {"relative", "none"}
        ``"relative"`` weights each response and line by the inverse of its RMS
        over the references (errors relative to the value, as for noise
        proportional to the FRF); ``"none"``: unweighted.

    Returns
    -------
    list of (order, poles, shapes)
        Poles (rad/s, all roots, both half planes) and their shapes at the
        responses ``B(z_k) v_k`` (``p x k``).

    Notes
    -----
    The reduced normal equations of [2]: per response ``o``, with ``X_o`` the
    polynomial basis and ``Y_o = -X_o kron H_o`` weighted, ``M = sum_o (T_o -
    S_o^T R_o^-1 S_o)`` with ``R = Re(X^H X)``, ``S = Re(X^H Y)``, ``T =
    Re(Y^H Y)``; the highest coefficient ``A_n = I``; the roots from the block
    companion matrix. ``dt = 1 / (2 f_high)``. Real coefficients, so the roots
    come in conjugate pairs.
    """
    freq, h = _check(frequencies, frf)
    (_, hi), sel = _band_lines(freq, band)
    f, hb = freq[sel], h[:, :, sel]
    p, q, nf = hb.shape
    wts = _weights(hb, weighting)
    dt = 1.0 / (2.0 * hi)
    w = 2.0 * np.pi * f
    n_max = max(orders)
    if n_max < 1:
        raise InputError("orders must be positive")
    basis = np.exp(1j * np.outer(w * dt, np.arange(n_max + 1)))  # (f, n+1)
    out: list[tuple[int, CArray, CArray]] = []
    # per response: X (f, n+1) weighted, Y = -kron(X, H_o) (f, (n+1) q); the blocks of a lower order are
    # the leading blocks of the highest order's, so they are formed once
    big = (n_max + 1) * q
    blocks = []
    for o in range(p):
        xw = basis * wts[o][:, None]
        yw = -(xw[:, :, None] * hb[o].T[:, None, :]).reshape(nf, big)
        blocks.append(((xw.conj().T @ xw).real, (xw.conj().T @ yw).real, (yw.conj().T @ yw).real))
    for n in orders:
        size = (n + 1) * q
        m_mat = np.zeros((size, size))
        keep: list[Array] = []
        for r_all, s_all, t_all in blocks:
            r_o, s_o, t_o = r_all[: n + 1, : n + 1], s_all[: n + 1, :size], t_all[:size, :size]
            rs = np.linalg.solve(r_o, s_o)
            m_mat += t_o - s_o.T @ rs
            keep.append(rs)
        m_mat = 0.5 * (m_mat + m_mat.T)
        nq = n * q
        alpha_low = -np.linalg.lstsq(m_mat[:nq, :nq], m_mat[:nq, nq:], rcond=None)[0]  # (n q, q)
        alpha = np.vstack([alpha_low, np.eye(q)])  # rows: alpha_0 .. alpha_n stacked (each q x q)
        comp = np.zeros((nq, nq))
        if n > 1:
            comp[: nq - q, q:] = np.eye(nq - q)
        comp[nq - q :, :] = -alpha_low.reshape(n, q, q).transpose(1, 0, 2).reshape(q, nq)
        z, vec = np.linalg.eig(comp)
        lam = np.log(z.astype(complex)) / dt
        v = vec[:q, :]  # right null vectors of A(z_k)
        # shapes B_o(z_k) v_k with beta_o = -R_o^-1 S_o alpha
        shapes = np.zeros((p, lam.size), dtype=complex)
        zpow = z[None, :] ** np.arange(n + 1)[:, None]  # (n+1, k)
        for o, rs in enumerate(keep):
            beta = -rs @ alpha  # (n+1, q)
            shapes[o] = np.einsum("rk,rj,jk->k", zpow, beta, v)
        out.append((int(n), lam.astype(complex), shapes))
    return out


def residues_lsfd(
    frequencies: ArrayLike,
    frf: ArrayLike,
    poles: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
    lower: bool = False,
    upper: bool | int = True,
    weighting: str = "relative",
) -> tuple[CArray, CArray, CArray, float]:
    """Residues of accelerance FRFs with known poles, by least squares in the frequency domain.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz.
    frf : array_like of complex, shape (p, q, f)
        Accelerance.
    poles : array_like of complex, shape (n,)
        Poles (rad/s, ``Im > 0``) of every mode in the band.
    band : (float, float), optional
        Band (Hz); all lines by default.
    lower : bool
        Fit a lower residual (a constant in accelerance: modes below the band).
    upper : bool or int
        Fit an upper residual (``(w / w_top)^2``: modes above the band); an
        integer ``n`` fits the ``n`` terms ``(w / w_top)^2 .. (w / w_top)^(2 n)``.
    weighting : {"relative", "none"}
        As :func:`plscf_poles`, per response and reference pair.

    Returns
    -------
    residues : ndarray of complex, shape (n, p, q)
        Receptance residues ``R_k``.
    lower, upper : ndarray of complex, shape (p, q)
        The residual terms (zero when not fitted; `upper` is the coefficient of
        ``(w / w_top)^2``).
    residual : float
        Weighted RMS misfit over the weighted RMS of the data.

    Notes
    -----
    One real linear least-squares problem per response and reference pair
    (real and imaginary parts stacked), ``2 n`` unknowns plus the residual
    terms; weighted by ``1 / |H|`` (floored) with relative weighting, the
    maximum-likelihood fit for noise proportional to the FRF.
    """
    freq, h = _check(frequencies, frf)
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    if lam.size == 0 or np.any(lam.imag <= 0.0) or not np.all(np.isfinite(lam)):
        raise InputError("poles must be finite with positive imaginary parts")
    (lo, hi), sel = _band_lines(freq, band)
    hb = h[:, :, sel]
    w = 2.0 * np.pi * freq[sel]
    g, n_modal = _design(w, lam, lower, upper)
    if g.shape[1] > 2 * w.size:
        raise InputError(f"band {lo:g}-{hi:g} Hz holds too few lines for {lam.size} modes")
    wts = _pair_weights(hb, weighting)
    coef, resid, den = _solve_pairs(g, hb, wts)
    p, q = hb.shape[:2]
    residues = (coef[0:n_modal:2] + 1j * coef[1:n_modal:2]).astype(complex)
    k = n_modal
    low = np.zeros((p, q), dtype=complex)
    up = np.zeros((p, q), dtype=complex)
    if lower:
        low = coef[k] + 1j * coef[k + 1]
        k += 2
    if upper:
        up = coef[k] + 1j * coef[k + 1]
    return residues, low, up, float(np.linalg.norm(resid) / max(den, np.finfo(float).tiny))


def _design(w: Array, lam: CArray, lower: bool, upper: bool | int) -> tuple[CArray, int]:
    """LSFD columns (f, 2 n + residual terms): real and imaginary part of each residue, then the residuals."""
    iw = 1j * w
    w_top = float(w[-1])
    cols = []
    for lk in lam:
        g1 = -(w**2) / (iw - lk)
        g2 = -(w**2) / (iw - np.conj(lk))
        cols.extend([g1 + g2, 1j * (g1 - g2)])
    n_modal = len(cols)
    if lower:
        cols.extend([np.ones(w.size, dtype=complex), 1j * np.ones(w.size)])
    for power in range(1, int(upper) + 1):
        cols.extend([(w / w_top) ** (2 * power) + 0j, 1j * (w / w_top) ** (2 * power)])
    return np.stack(cols, axis=1), n_modal


def _pair_weights(hb: CArray, weighting: str) -> Array:
    """Weights (p, q, f): 1 / |H| floored at 1e-3 of the pair's median, or ones."""
    if weighting == "none":
        return np.ones(hb.shape)
    if weighting != "relative":
        raise InputError(f"weighting must be 'relative' or 'none', got {weighting!r}")
    mag = np.abs(hb)
    floor = 1e-3 * np.median(mag, axis=2, keepdims=True) + np.finfo(float).tiny
    result: Array = 1.0 / np.maximum(mag, floor)
    return result


def _solve_pairs(g: CArray, hb: CArray, wts: Array) -> tuple[Array, Array, float]:
    """Weighted least squares per response and reference pair: coefficients, stacked residuals, data norm."""
    coef, resid, den, _ = _solve_pairs_qr(g, hb, wts)
    return coef, resid.reshape(-1), den


def _solve_pairs_qr(g: CArray, hb: CArray, wts: Array) -> tuple[Array, Array, float, tuple[Array, Array, Array]]:
    """:func:`_solve_pairs` with residuals (pq, 2f) and its factors ``(Q, R, column scales)``.

    All pairs at once: stacked QR of the column-scaled real designs ``[Re; Im]``.
    """
    p, q, nf = hb.shape
    k = g.shape[1]
    gw = g[None, :, :] * wts.reshape(p * q, nf)[:, :, None]  # (pq, f, k)
    yw = (hb * wts).reshape(p * q, nf)
    design = np.concatenate([gw.real, gw.imag], axis=1)  # (pq, 2f, k)
    target = np.concatenate([yw.real, yw.imag], axis=1)  # (pq, 2f)
    scale = np.linalg.norm(design, axis=1)  # (pq, k)
    scale[scale == 0.0] = 1.0
    qm, rm = np.linalg.qr(design / scale[:, None, :])
    diag = np.abs(np.diagonal(rm, axis1=1, axis2=2))
    if np.any(diag < 1e-12 * np.max(diag, axis=1, keepdims=True)):
        raise IdentificationError("the residues cannot be separated in this band (poles too close?)")
    qty = np.einsum("bfk,bf->bk", qm, target)
    sol = np.linalg.solve(rm, qty[:, :, None])[:, :, 0] / scale
    resid = np.einsum("bfk,bk->bf", qm, qty) - target
    coef = sol.T.reshape(k, p, q)
    return coef, resid, float(np.linalg.norm(target)), (qm, rm, scale)


def _noise_weights(g: CArray, hb: CArray, passes: int = 2) -> Array:
    """Weights (p, q, f) ``1 / sigma`` from the noise the misfit shows (:func:`rigidid.core.frfstats.local_noise`).

    The first fit is unweighted; each pass refits with the weights of the previous misfit.
    """
    p, q, nf = hb.shape
    wts = np.ones(hb.shape)
    for _ in range(passes):
        _, resid, _, (qm, _, _) = _solve_pairs_qr(g, hb, wts)
        resid = _unshrunk(resid, qm).reshape(p * q, 2, nf)
        e = (resid[:, 0] + 1j * resid[:, 1]) / wts.reshape(p * q, nf)
        wts = 1.0 / local_noise(e).reshape(p, q, nf)
    return wts


def _unshrunk(resid: Array, qm: Array) -> Array:
    """The misfits divided by ``sqrt(1 - h)``, ``h`` each value's leverage (``|row of Q|^2``).

    A least-squares fit pulls its misfit towards zero where a value alone determines a parameter:
    with few lines per half-power band (coarse spacing, light damping) the lines at a resonance
    have leverages near 1, and their raw misfits understate the noise there (the oracle with the
    true poles was 4.3 of its standard errors off at 1 Hz spacing, benchmarks/frf_regimes.py df1).
    ``E[e^2] = (1 - h) sigma^2``: the corrected misfits estimate ``sigma^2`` without that bias,
    for the noise weights and for the sandwich variance (HC2).
    """
    lev = np.minimum(np.sum(qm**2, axis=2), 1.0 - 1e-6)
    out: Array = resid / np.sqrt(1.0 - lev)
    return out


def _limit_weights(coef: Array, qm: Array, rm: Array, scale: Array, lam: CArray, n_modal: int) -> tuple[Array, Array]:
    """``sum 2 Re(l_k R_k)`` per pair (p, q) and its weights on the weighted data (pq, 2f)."""
    k = coef.shape[0]
    c = np.zeros(k)
    c[0:n_modal:2] = 2.0 * lam.real
    c[1:n_modal:2] = -2.0 * lam.imag
    limit = np.tensordot(c, coef, axes=1)
    v = np.linalg.solve(np.transpose(rm, (0, 2, 1)), (c[None, :] / scale)[:, :, None])[:, :, 0]  # R^-T c
    return limit, np.einsum("bfk,bk->bf", qm, v)


def _pole_parameters(lam: CArray) -> Array:
    return np.stack([lam.real, lam.imag], axis=1).reshape(-1)


def _poles_of(theta: Array) -> CArray:
    pair = theta.reshape(-1, 2)
    return (pair[:, 0] + 1j * pair[:, 1]).astype(complex)


def _varpro_residual(w: Array, hb: CArray, wts: Array, theta: Array, upper: int) -> Array:
    """Weighted misfit (flat) of the residues fitted with the poles ``theta`` (variable projection)."""
    return _solve_pairs_qr(_design(w, _poles_of(theta), False, upper)[0], hb, wts)[1].reshape(-1)


def _varpro_jacobian(w: Array, hb: CArray, wts: Array, theta: Array, upper: int) -> tuple[Array, Array]:
    """Projected weighted residual (flat) and its derivative in the pole parameters (forward differences)."""
    r0 = _varpro_residual(w, hb, wts, theta, upper)
    jac = np.empty((r0.size, theta.size))
    for i in range(theta.size):
        d = np.zeros_like(theta)
        d[i] = 1e-7 * float(np.max(np.abs(theta)))
        jac[:, i] = (_varpro_residual(w, hb, wts, theta + d, upper) - r0) / d[i]
    return r0, jac


def _refine_poles_varpro(w: Array, hb: CArray, wts: Array, lam: CArray, upper: int, steps: int = 6) -> CArray:
    """Gauss-Newton on the poles with the residues projected out (variable projection), fixed weights."""
    theta = _pole_parameters(lam)
    r0, jac = _varpro_jacobian(w, hb, wts, theta, upper)
    cost = float(r0 @ r0)
    for _ in range(steps):
        step = np.linalg.lstsq(jac, -r0, rcond=None)[0]
        for _half in range(5):
            trial = theta + step
            if np.all(trial.reshape(-1, 2)[:, 1] > 0.0) and np.all(trial.reshape(-1, 2)[:, 0] < 0.0):
                r_t = _varpro_residual(w, hb, wts, trial, upper)
                if float(r_t @ r_t) < cost:
                    break
            step = 0.5 * step
        else:
            break
        gain = cost - float(r_t @ r_t)
        theta, cost = trial, float(r_t @ r_t)
        if gain < 1e-6 * cost:
            break
        r0, jac = _varpro_jacobian(w, hb, wts, theta, upper)
    return _poles_of(theta)


def _pole_covariance(
    w: Array, hb: CArray, wts: Array, lam: CArray, upper: int, resid: Array, k: int
) -> tuple[Array, Array]:
    """Covariance of the pole parameters (Gauss-Newton, misfit variance per its degrees of freedom) and the
    derivative of the limit in them (p, q, 2 n)."""
    theta = _pole_parameters(lam)
    _, jac = _varpro_jacobian(w, hb, wts, theta, upper)
    n_val = resid.size
    s2 = float(np.sum(resid**2)) / max(n_val - resid.shape[0] * k - theta.size, 1)
    cov = s2 * pseudo_inverse(jac.T @ jac, symmetric=True)[0]
    p, q, _ = hb.shape
    jl = np.empty((p, q, theta.size))
    for i in range(theta.size):
        d = np.zeros_like(theta)
        d[i] = 1e-6 * float(np.max(np.abs(theta)))
        lims = []
        for sgn in (1.0, -1.0):
            lam_i = _poles_of(theta + sgn * d)
            g_i, n_modal = _design(w, lam_i, False, upper)
            coef, _, _, (qm, rm, scale) = _solve_pairs_qr(g_i, hb, wts)
            lims.append(_limit_weights(coef, qm, rm, scale, lam_i, n_modal)[0])
        jl[:, :, i] = (lims[0] - lims[1]) / (2.0 * d[i])
    return cov, jl


@dataclass(frozen=True)
class ResidueLimit:
    """The high-frequency limit of rigid-body residues fitted with known poles, with its variance.

    Attributes
    ----------
    limit : ndarray, shape (p, q)
        ``sum_k 2 Re(l_k R_k)`` (``T M^-1 T_f^T`` for the six rigid-body modes).
    variance : ndarray, shape (p, q)
        Its variance per response and reference (sandwich, :func:`rigidid.core.frfstats.sandwich_variance`).
    residual : float
        Weighted RMS misfit over the weighted RMS of the data.
    misfit_units : float
        The misfit over the noise seen in its third differences (:func:`rigidid.core.frfstats.misfit_units`).
    poles : ndarray of complex, shape (n,)
        The poles used (refined when asked).
    pole_covariance : ndarray, shape (2 n, 2 n)
        Covariance of ``(Re l_1, Im l_1, ...)`` when refined, else empty.
    limit_jacobian : ndarray, shape (p, q, 2 n)
        Derivative of `limit` with respect to those pole parameters (empty when not refined):
        the limit's variance from the poles is ``J C J^T`` (correlated across FRFs).
    worst : tuple of int
        Response and reference whose FRF the model misfits most, in noise units.
    worst_units : float
        That FRF's misfit in noise units.
    peak_shortfall : PeakShortfall or None
        How far the FRFs fall short of the fit at the resonance peaks (:func:`peak_shortfall`).
    """

    limit: Array
    variance: Array
    poles: CArray
    pole_covariance: Array
    limit_jacobian: Array
    residual: float
    misfit_units: float
    worst: tuple[int, int]
    worst_units: float
    peak_shortfall: PeakShortfall | None = None


PEAK_SHORTFALL_Z = 4.0
"""A fit whose FRFs fall short of (or exceed) it at the resonance peaks by more than this many standard
errors (:func:`peak_shortfall`) is warned about. On the H1-bias cell of benchmarks/frf_regimes.py (2 % at
the highest peak, 1 % noise) the statistic was 10-13 standard errors; on the clean cells within 2."""


@dataclass(frozen=True)
class PeakShortfall:
    """The fraction by which the FRFs fall short of a modal fit in proportion to their summed power.

    Attributes
    ----------
    fraction : float
        ``b`` of the model ``H = (1 - b g) H_fit``, ``g`` the summed power ``sum |H|^2`` per line
        over its largest value (1 at the highest peak); positive: the FRFs fall short at the peaks.
    z : float
        `fraction` over its standard error.
    frequency : float
        The highest peak (Hz), where the shortfall is largest.
    """

    fraction: float
    z: float
    frequency: float


def peak_shortfall(frequencies: Array, frf: CArray, misfit: CArray, weights: Array) -> PeakShortfall:
    """How far FRFs fall short of their modal fit at the resonance peaks, in standard errors.

    Parameters
    ----------
    frequencies : ndarray, shape (f,)
        Hz.
    frf : ndarray of complex, shape (p, q, f)
        The measured FRFs.
    misfit : ndarray of complex, shape (p, q, f)
        Fit minus FRFs, weighted (unit noise per complex value).
    weights : ndarray, shape (p, q, f)
        The fit's weights (inverse noise standard deviations).

    Returns
    -------
    PeakShortfall

    Notes
    -----
    An H1 estimate ``G_xf / G_ff`` falls short of the FRF where leakage or a low coherence
    strike, at the resonance peaks. Modelled as ``H = (1 - b g) H_fit`` with ``g`` the summed
    power of the FRFs (1 at the highest peak), ``b`` is the weighted least-squares projection
    of the misfit on ``g H_fit``: one parameter, so a shortfall that the poles and residues
    absorb almost entirely (2 % at the peak left the misfit at 1.01 noise units) still
    shows at 10 of its standard errors. Its variance ``1 / (2 sum |w g H_fit|^2)`` (complex
    noise of unit variance after weighting).
    """
    g = summed_power(frf)
    g = g / g.max()
    fitted = frf + misfit / weights
    x = g * fitted * weights
    den = float(np.sum(np.abs(x) ** 2))
    if not den > 0.0:
        return PeakShortfall(0.0, 0.0, float(frequencies[int(np.argmax(g))]))
    b = float(np.sum((np.conj(x) * misfit).real)) / den
    return PeakShortfall(b, b * float(np.sqrt(2.0 * den)), float(frequencies[int(np.argmax(g))]))


def residue_limit(
    frequencies: ArrayLike,
    frf: ArrayLike,
    poles: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
    upper: int = 2,
    weighting: str = "noise",
    refine: bool = True,
) -> ResidueLimit:
    """Residues of accelerance FRFs with known poles and their high-frequency limit, with its variance.

    Parameters
    ----------
    frequencies, frf, poles, band, upper
        As :func:`residues_lsfd` (no lower residual).
    weighting : {"noise", "relative", "none"}
        ``"noise"`` (default): each value weighted by the inverse of its noise level, found
        from the misfit of the neighbouring lines of the same FRF
        (:func:`rigidid.core.frfstats.local_noise`, two passes from an unweighted fit);
        ``"relative"``: ``1 / |H|`` (right for noise proportional to the FRF only: with a
        noise floor it weights the anti-resonances by their noise); ``"none"``: unweighted.
    refine : bool
        Refine the poles on the weighted FRFs (variable projection, Gauss-Newton) and count
        their uncertainty in the limit's (``pole_covariance``, ``limit_jacobian``).

    Returns
    -------
    ResidueLimit

    Notes
    -----
    The limit is linear in the data, ``a^T h`` per FRF, so its variance is
    ``sum a_l^2 e_l^2`` over the weighted misfits ``e_l`` (with the fit's degrees of
    freedom); the poles' uncertainty adds ``J C J^T`` when they are refined (the
    residues' covariance given the poles plus the poles' propagated: the two are
    uncorrelated to first order in variable projection).
    """
    freq, h = _check(frequencies, frf)
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    if lam.size == 0 or np.any(lam.imag <= 0.0) or not np.all(np.isfinite(lam)):
        raise InputError("poles must be finite with positive imaginary parts")
    (lo, hi), sel = _band_lines(freq, band)
    hb = h[:, :, sel]
    g, n_modal = _design(2.0 * np.pi * freq[sel], lam, False, upper)
    p, q, nf = hb.shape
    k = g.shape[1]
    if k > 2 * nf:
        raise InputError(f"band {lo:g}-{hi:g} Hz holds too few lines for {lam.size} modes")
    w = 2.0 * np.pi * freq[sel]
    wts = _noise_weights(g, hb) if weighting == "noise" else _pair_weights(hb, weighting)
    pole_cov = np.zeros((0, 0))
    if refine:
        lam = _refine_poles_varpro(w, hb, wts, lam, upper)
        g = _design(w, lam, False, upper)[0]
        if weighting == "noise":
            wts = _noise_weights(g, hb)
    coef, resid, den, (qm, rm, scale) = _solve_pairs_qr(g, hb, wts)
    limit, a = _limit_weights(coef, qm, rm, scale, lam, n_modal)
    var = sandwich_variance(a, _unshrunk(resid, qm), 0).reshape(p, q)  # HC2: leverage, not n / (n - k)
    jac_limit = np.zeros((p, q, 0))
    if refine:
        pole_cov, jac_limit = _pole_covariance(w, hb, wts, lam, upper, resid, k)
    units, per_row = misfit_units(resid.reshape(p * q, 2, nf).reshape(2 * p * q, nf), k // 2)
    per_pair = np.sqrt(np.mean(per_row.reshape(p * q, 2) ** 2, axis=1))
    worst = int(np.argmax(per_pair))
    unshrunk = _unshrunk(resid, qm).reshape(p, q, 2, nf)
    shortfall = peak_shortfall(freq[sel], hb, unshrunk[:, :, 0] + 1j * unshrunk[:, :, 1], wts)
    return ResidueLimit(
        limit=limit,
        variance=var,
        poles=lam,
        pole_covariance=pole_cov,
        limit_jacobian=jac_limit,
        residual=float(np.linalg.norm(resid) / max(den, np.finfo(float).tiny)),
        misfit_units=units,
        worst=(worst // q, worst % q),
        worst_units=float(per_pair[worst]),
        peak_shortfall=shortfall,
    )


def refine_poles(
    frequencies: ArrayLike,
    frf: ArrayLike,
    poles: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
    lower: bool = False,
    upper: bool = True,
    weighting: str = "relative",
) -> CArray:
    """Poles refined by nonlinear least squares on the FRFs, the residues projected out.

    Parameters
    ----------
    frequencies, frf, band, lower, upper, weighting
        As :func:`residues_lsfd`.
    poles : array_like of complex, shape (n,)
        Starting poles (rad/s, ``Im > 0``), e.g. from :func:`plscf_poles`.

    Returns
    -------
    ndarray of complex, shape (n,)
        The poles minimising the weighted LSFD misfit (variable projection over
        natural frequency and damping ratio of each pole; Levenberg-Marquardt).

    Notes
    -----
    pLSCF solves a linearised problem whose noise bias is of the order of the
    noise; the misfit of the full model to the data (weighted as
    :func:`residues_lsfd`) is the maximum-likelihood criterion for complex
    noise proportional to the FRF. The starting poles are kept when the
    refinement does not lower it.
    """
    from scipy.optimize import least_squares

    freq, h = _check(frequencies, frf)
    lam0 = np.asarray(poles, dtype=complex).reshape(-1)
    if lam0.size == 0 or np.any(lam0.imag <= 0.0) or not np.all(np.isfinite(lam0)):
        raise InputError("poles must be finite with positive imaginary parts")
    _, sel = _band_lines(freq, band)
    hb = h[:, :, sel]
    w = 2.0 * np.pi * freq[sel]
    wts = _pair_weights(hb, weighting)

    def to_poles(x: Array) -> CArray:
        wn, z = np.exp(x[0::2]), np.clip(x[1::2], 1e-9, 0.999)
        result: CArray = wn * (-z + 1j * np.sqrt(1.0 - z**2))
        return result

    def residual(x: Array) -> Array:
        return _solve_pairs(_design(w, to_poles(x), lower, upper)[0], hb, wts)[1]

    x0 = np.empty(2 * lam0.size)
    x0[0::2] = np.log(np.abs(lam0))
    x0[1::2] = -lam0.real / np.abs(lam0)
    start = residual(x0)
    try:
        fit = least_squares(residual, x0, method="lm", x_scale="jac", max_nfev=100 * x0.size)
    except IdentificationError:
        return lam0
    if not (np.all(np.isfinite(fit.x)) and np.all(fit.x[1::2] > 0.0) and fit.x[1::2].max() < 0.999):
        return lam0
    if float(fit.fun @ fit.fun) >= float(start @ start):
        return lam0
    return to_poles(fit.x)


def rigid_six(fitted: FrfModes, positions: ArrayLike, directions: ArrayLike) -> tuple[NDArray[np.intp] | None, Array]:
    """Which six of the fitted modes are the rigid-body ones, by how well their shapes fit rigid motion.

    Parameters
    ----------
    fitted : FrfModes
        Modes fitted to the FRFs (:func:`fit_frf_modes`), six or more.
    positions, directions : array_like, shape (p, 3)
        Sensors (length, unit axes), ``p > 6``.

    Returns
    -------
    six : ndarray of int, shape (6,), or None
        Indices of the six rigid-body modes: all six when six are fitted and none
        stands out as elastic (:func:`rigidid.core.selection.elastic_suspect`); with
        seven, the six left when the seventh is clearly elastic
        (:func:`rigidid.core.selection.separate_elastic`); else None.
    residuals : ndarray, shape (n,)
        Each mode's rigid-fit residual: the left factor of its residue matrix (the
        shape before any projection) fitted by rigid-body motion, relative.

    Notes
    -----
    The records route leaves an elastic mode out the same way (``ElasticModeWarning``):
    rigid-body shapes measured with noise fit rigid motion to about the noise, an
    elastic shape to 0.1-1. With six sensors or fewer every shape fits, and nothing
    is told: the six fitted modes are returned as they are.
    """
    from rigidid.core.selection import elastic_suspect, rigid_fit_residuals, separate_elastic

    t = sensor_matrix(np.asarray(positions, dtype=float), np.asarray(directions, dtype=float))
    shapes = _rank_one_shapes(fitted.residues)[0]
    n = shapes.shape[1]
    if t.shape[0] <= 6:
        return (np.arange(6) if n >= 6 else None), np.zeros(n)
    residuals = rigid_fit_residuals(t, shapes)
    if n == 6:
        return (np.arange(6) if elastic_suspect(residuals) is None else None), residuals
    if n == 7:
        return separate_elastic(t, shapes), residuals
    return None, residuals


def scaled_frame(positions: Array, directions: Array) -> tuple[Array, float, Array]:
    """Origin (the sensor centroid), span (largest distance from it) and the sensor matrix in that frame.

    Raises
    ------
    IdentificationError
        The sensors do not see six independent rigid-body motions.
    """
    origin = positions.mean(axis=0)
    span = float(np.max(np.linalg.norm(positions - origin, axis=1))) or 1.0
    t = sensor_matrix((positions - origin) / span, directions)
    sv = np.linalg.svd(t, compute_uv=False)
    if sv.size < 6 or sv[-1] < 1e-8 * sv[0]:
        raise IdentificationError("the sensors do not see six independent rigid-body motions")
    return origin, span, t


def _rigid_modes(residues: CArray, t: Array, tf: Array) -> tuple[CArray, Array]:
    """Unity-modal-A rigid-body modes ``u_k`` (6, n) with ``R_k = T u_k u_k^T T_f^T``, and the fit residual per mode."""
    n = residues.shape[0]
    u = np.zeros((6, n), dtype=complex)
    miss = np.zeros(n)
    for k in range(n):
        y = np.linalg.lstsq(t, residues[k], rcond=None)[0]  # (6, q): u (T_f u)^T
        left = np.linalg.svd(y)[0]
        a = left[:, 0]
        g = np.outer(a, tf @ a)
        c2 = complex(np.vdot(g, y) / np.vdot(g, g))
        u[:, k] = np.sqrt(c2) * a
        model = t @ np.outer(u[:, k], u[:, k]) @ tf.T
        miss[k] = float(np.linalg.norm(model - residues[k])) / max(float(np.linalg.norm(residues[k])), 1e-300)
    return u, miss


def rigid_shapes(
    residues: ArrayLike,
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
) -> tuple[CArray, CArray, Array]:
    """Unity-modal-A shapes of rigid-body modes from their residues (the force scales them).

    Parameters
    ----------
    residues : array_like of complex, shape (n, p, q)
        Receptance residues of rigid-body modes.
    positions, directions : array_like, shape (p, 3)
        Sensors, rank 6.
    reference_positions, reference_directions : array_like, shape (q, 3)
        Force points and directions.

    Returns
    -------
    shapes : ndarray of complex, shape (p, n)
        ``T u_k``: each mode at the sensors, ``R_k ~ shapes_k participation_k^T``.
    participation : ndarray of complex, shape (q, n)
        ``T_f u_k``: each mode at the references along the force.
    misfit : ndarray, shape (n,)
        ``|T u u^T T_f^T - R_k| / |R_k|``: how far each residue is from a rigid-body mode's.

    Notes
    -----
    ``T^+ R_k = u_k (T_f u_k)^T``: the leading left singular vector gives the
    direction of ``u_k``, and the force its scale (one complex least-squares
    factor); the sign of ``u_k`` is arbitrary, as for any mode.
    """
    res = np.asarray(residues, dtype=complex)
    _, _, t, tf = _frames(positions, directions, reference_positions, reference_directions)
    u, misfit = _rigid_modes(res, t, tf)
    return t @ u, tf @ u, misfit


def body_from_scaled_modes(
    poles: ArrayLike,
    residues: ArrayLike,
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
) -> ScaledBody:
    """Mass, CG, inertia, stiffness and damping from the six rigid-body residues.

    Parameters
    ----------
    poles : array_like of complex, shape (6,)
        The rigid-body poles (rad/s, ``Im > 0``).
    residues : array_like of complex, shape (6, p, q)
        Their receptance residues (from :func:`residues_lsfd`).
    positions, directions : array_like, shape (p, 3)
        Sensors (length, unit axes), rank 6.
    reference_positions, reference_directions : array_like, shape (q, 3)
        Force points and unit directions.

    Returns
    -------
    ScaledBody

    Raises
    ------
    IdentificationError
        If the sensors do not see six rigid-body motions, a mode's residue is
        not excited by the references, or the mass is not positive.

    Notes
    -----
    Each residue is projected on rigid-body motion, ``T^+ R_k = u_k (T_f
    u_k)^T``, which fixes the scale of ``u_k`` (the force is known); then
    ``M^-1 = sum_k 2 Re(l_k u_k u_k^T)``, ``K^-1 = -sum_k 2 Re(u_k u_k^T /
    l_k)`` and ``M^-1 C M^-1 = -sum_k 2 Re(l_k^2 u_k u_k^T)``, exact for a
    rigid body on massless mounts (eq. (1) of [1]) whatever the damping. The
    mass, CG and inertia are read from ``M`` about the sensor centroid (mass
    from the translational block's trace, CG from its coupling block); ``K``
    and ``C`` are moved to the CG with the transfer matrix (eqs. (11)-(14)).
    """
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    res = np.asarray(residues, dtype=complex)
    p, q = np.shape(positions)[0], np.shape(reference_positions)[0]
    if lam.size != 6 or res.shape != (6, p, q):
        raise InputError("poles and residues must be those of the six rigid-body modes, residues (6, p, q)")
    origin, span, t, tf = _frames(positions, directions, reference_positions, reference_directions)
    return _excited_body(lam, _rigid_modes(res, t, tf)[0], origin, span)


def body_from_frfs(
    frequencies: ArrayLike,
    frf: ArrayLike,
    poles: ArrayLike,
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
) -> ScaledBody:
    """Mass, CG, inertia, K and C from the six rigid-body modes fitted to the FRFs with their structure.

    :func:`residues_lsfd` (upper residual), :func:`rigid_shapes`' projection as the start,
    :func:`refine_rigid_modes` (the structure ``R_k = T u_k u_k^T T_f^T`` imposed, the poles
    fixed), then as :func:`body_from_scaled_modes`.

    Parameters
    ----------
    frequencies, frf : array_like
        Hz (f,) and accelerance (p, q, f).
    poles : array_like of complex, shape (6,)
        The rigid-body poles (rad/s, ``Im > 0``).
    positions, directions, reference_positions, reference_directions : array_like
        Sensors (p, 3) and references (q, 3).
    band : (float, float), optional
        Band of the fit (Hz); all lines by default.

    Returns
    -------
    ScaledBody
    """
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    if lam.size != 6:
        raise InputError("poles must be those of the six rigid-body modes")
    origin, span, t, tf = _frames(positions, directions, reference_positions, reference_directions)
    res = residues_lsfd(frequencies, frf, lam, band=band)[0]
    u = refine_rigid_modes(frequencies, frf, lam, _rigid_modes(res, t, tf)[0], t, tf, band=band)[0]
    return _excited_body(lam, u, origin, span)


def body_from_scaled_shapes(
    poles: ArrayLike,
    shapes: ArrayLike,
    positions: ArrayLike,
    directions: ArrayLike,
) -> ScaledBody:
    """Mass, CG, inertia, stiffness and damping from six unity-modal-A shapes at the sensors.

    What ``modes.csv`` with ``scaling`` ``modal_a`` (written by ``rigidid modes
    --frf``) carries: :func:`body_from_scaled_modes` without the FRFs.

    Parameters
    ----------
    poles : array_like of complex, shape (6,)
        The rigid-body poles (rad/s, ``Im > 0``).
    shapes : array_like of complex, shape (p, 6)
        Their shapes at the sensors scaled to unity modal A (``T u_k``, in
        ``sqrt(1 / (mass s))`` times length units: :attr:`FrfModes.shapes`).
    positions, directions : array_like, shape (p, 3)
        Sensors (length, unit axes), rank 6.

    Returns
    -------
    ScaledBody

    Raises
    ------
    InputError
        Not six poles and six shapes of the sensors' length.
    IdentificationError
        The sensors do not see six rigid-body motions, a shape is zero, or the
        mass is not positive.

    Notes
    -----
    ``u_k = T^+ shape_k`` (least squares on rigid-body motion, eq. (30) in
    spirit), then as :func:`body_from_scaled_modes`. The scale of the shapes
    carries the mass: any other scaling (e.g. largest value 1) gives a
    meaningless mass.
    """
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    phi = np.asarray(shapes, dtype=complex)
    pos = np.asarray(positions, dtype=float)
    dirs = np.asarray(directions, dtype=float)
    if lam.size != 6 or phi.shape != (pos.shape[0], 6):
        raise InputError("poles and shapes must be those of the six rigid-body modes, shapes (p, 6)")
    origin, span, t = scaled_frame(pos, dirs)
    u = np.linalg.lstsq(t, phi, rcond=None)[0]
    if np.any(np.linalg.norm(u, axis=0) == 0.0):
        raise IdentificationError("a scaled rigid-body shape is zero")
    return _body_from_modes(lam, u, origin, span)


def refine_rigid_modes(
    frequencies: ArrayLike,
    frf: ArrayLike,
    poles: ArrayLike,
    modes: ArrayLike,
    t: ArrayLike,
    tf: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
    iterations: int = 8,
) -> tuple[CArray, Array]:
    """Unity-modal-A rigid-body modes fitted to the FRFs themselves, the poles fixed.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz.
    frf : array_like of complex, shape (p, q, f)
        Accelerance.
    poles : array_like of complex, shape (n,)
        The rigid-body poles (rad/s, ``Im > 0``).
    modes : array_like of complex, shape (6, n)
        Starting modes ``u_k`` in the frame of `t` (e.g. from the residues).
    t : array_like, shape (p, 6)
        Sensor matrix (rigid coordinates to sensor readings).
    tf : array_like, shape (q, 6)
        The references' matrix (rigid coordinates to motion along each force).
    band : (float, float), optional
        Band (Hz); all lines by default.
    iterations : int
        Gauss-Newton steps at most.

    Returns
    -------
    modes : ndarray of complex, shape (6, n)
        The modes minimising the misfit of
        ``H = sum_k [T u_k u_k^T T_f^T g_k + conj(.) h_k] + U (w / w_top)^2``
        (``g_k = -w^2 / (i w - l_k)``, ``h_k`` with ``conj(l_k)``, the upper residual
        ``U`` free per pair), weighted to relative errors (by the first model's
        magnitude); the starting modes when the misfit does not drop.
    noise : ndarray, shape (n,)
        Per mode, the standard deviation of ``T u_k`` per sensor value that white
        noise would need to give the same scatter of ``u_k`` through a rigid-body fit:
        ``sqrt(trace(T C_k T^T) / 6)``, ``C_k`` the covariance of ``u_k`` (real and
        imaginary parts) from ``s^2 (J^T J)^-1`` of the fit (NaN if undetermined).

    Notes
    -----
    The residues fitted freely per pair (:func:`residues_lsfd`) and then projected on
    rigid-body motion (:func:`rigid_shapes`) do not use the structure ``R_k = T u_k u_k^T
    T_f^T`` in the fit itself; here it is imposed, which is the maximum-likelihood fit of
    the modes for complex noise proportional to the FRF (poles known). On the simulated
    tests of ``benchmarks/frf_eq18.py`` it brings eq. (18)'s inertia error close to its
    Cramer-Rao bound.
    """
    freq, h = _check(frequencies, frf)
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    u0 = np.asarray(modes, dtype=complex)
    tm = np.asarray(t, dtype=float)
    tfm = np.asarray(tf, dtype=float)
    _, sel = _band_lines(freq, band)
    w = 2.0 * np.pi * freq[sel]
    hb = h[:, :, sel]
    n = lam.size
    g = -(w**2)[None, :] / (1j * w[None, :] - lam[:, None])
    gc = -(w**2)[None, :] / (1j * w[None, :] - np.conj(lam)[:, None])
    x = (w / w[-1]) ** 2

    def model(u: CArray) -> CArray:
        out = np.zeros(hb.shape, dtype=complex)
        for k in range(n):
            r = tm @ np.outer(u[:, k], u[:, k]) @ tfm.T
            out += r[:, :, None] * g[k] + np.conj(r)[:, :, None] * gc[k]
        return out

    # relative weights from the starting model (not the noisy data), floored as _pair_weights
    mag = np.abs(model(u0))
    wts = 1.0 / np.maximum(mag, 1e-3 * np.median(mag, axis=2, keepdims=True) + np.finfo(float).tiny)
    # the upper residual (one complex coefficient per pair) is projected out line-wise per pair
    xw = x[None, None, :] * wts
    xn = xw / np.linalg.norm(xw, axis=2, keepdims=True)

    def stacked(c: CArray) -> Array:
        cw = c * wts
        cw = cw - xn * np.sum(xn * cw, axis=2, keepdims=True)  # real basis: projects Re and Im alike
        return np.concatenate([cw.real.ravel(), cw.imag.ravel()])

    def cost(u: CArray) -> float:
        r = stacked(hb - model(u))
        return float(r @ r)

    def jacobian(u: CArray) -> Array:
        cols = []
        for k in range(n):
            for a in range(6):
                b = tm @ (np.outer(np.eye(6)[a], u[:, k]) + np.outer(u[:, k], np.eye(6)[a])) @ tfm.T
                cols.append(stacked(b[:, :, None] * g[k] + np.conj(b)[:, :, None] * gc[k]))
                cols.append(stacked(1j * b[:, :, None] * g[k] - 1j * np.conj(b)[:, :, None] * gc[k]))
        return np.stack(cols, axis=1)

    u = u0.copy()
    best = cost(u)
    for _ in range(iterations):
        jac = jacobian(u)
        step = np.linalg.lstsq(jac, stacked(hb - model(u)), rcond=None)[0]
        du = (step[0::2] + 1j * step[1::2]).reshape(n, 6).T
        trial = u + du
        new = cost(trial)
        if not new < best:
            break
        done = best - new < 1e-10 * best
        u, best = trial, new
        if done:
            break
    # the modes' covariance s^2 (J^T J)^-1, s^2 from the weighted misfit (relative noise per real value)
    jac = jacobian(u)
    n_rows, n_par = jac.shape
    n_free = n_rows - n_par - 2 * hb.shape[0] * hb.shape[1]  # the upper residual, two reals per pair
    noise = np.full(n, np.nan)
    if n_free > 0:
        info = jac.T @ jac
        try:
            cov = (best / n_free) * np.linalg.solve(info, np.eye(n_par))
        except np.linalg.LinAlgError:
            return u, noise
        for k in range(n):
            block = cov[12 * k : 12 * k + 12, 12 * k : 12 * k + 12]
            var = np.trace(tm @ block[0::2, 0::2] @ tm.T) + np.trace(tm @ block[1::2, 1::2] @ tm.T)
            noise[k] = float(np.sqrt(max(var, 0.0) / 6.0))
    return u, noise


def with_nonrigid_residual(
    scaled: ArrayLike, raw: ArrayLike, positions: ArrayLike, directions: ArrayLike, noise: ArrayLike | None = None
) -> CArray:
    """Rigid-body shapes projected and scaled by the force, with the raw shapes' non-rigid part added back.

    Parameters
    ----------
    scaled : array_like of complex, shape (p, n)
        ``T u_k``: shapes on rigid-body motion, unity-modal-A scaled
        (:func:`rigid_shapes`).
    raw : array_like of complex, shape (p, n)
        The same modes as fitted, before the projection (e.g. the left factor
        of each residue), any scale.
    positions, directions : array_like, shape (p, 3)
        Sensors, rank 6.

    noise : array_like, shape (n,), optional
        Per mode, the noise per sensor value of ``T u_k`` (as
        :func:`refine_rigid_modes` gives it): the non-rigid part is then rescaled
        to the norm ``sqrt(p - 6) noise_k`` that such noise leaves after a rigid-body
        fit, so that a noise estimate from the residual reads that level.

    Returns
    -------
    ndarray of complex, shape (p, n)
        ``T u_k + c_k (I - P) raw_k``, ``P`` the projector on rigid-body motion
        and ``c_k`` the complex factor that best maps ``P raw_k`` onto ``T u_k``
        (or the factor that gives the norm of `noise`).

    Notes
    -----
    ``T^+`` of the result is ``u_k`` exactly, so everything computed from the
    rigid-body part (eq. (18), the scaled-mode mass) is unchanged; but the
    part no rigid-body motion explains, which the projection discards, is the
    measure of the shape noise that an uncertainty estimate needs
    (:func:`rigidid.core.noise.estimate_noise` reads it from the rigid-fit
    residual). Without it a modes file fitted to FRFs looks noise-free.
    """
    base = np.asarray(scaled, dtype=complex)
    phi = np.asarray(raw, dtype=complex)
    _, _, t = scaled_frame(np.asarray(positions, dtype=float), np.asarray(directions, dtype=float))
    rigid = t @ np.linalg.lstsq(t, phi, rcond=None)[0]
    out = base.copy()
    sigma = None if noise is None else np.asarray(noise, dtype=float).reshape(-1)
    for k in range(base.shape[1]):
        norm = complex(np.vdot(rigid[:, k], rigid[:, k]))
        c = complex(np.vdot(rigid[:, k], base[:, k]) / norm) if abs(norm) > 0.0 else 0.0
        rest = phi[:, k] - rigid[:, k]
        size = float(np.linalg.norm(rest))
        if sigma is not None and np.isfinite(sigma[k]) and size > 0.0:
            c = c / abs(c) * np.sqrt(max(base.shape[0] - 6, 0)) * sigma[k] / size if c != 0.0 else 0.0
        out[:, k] = base[:, k] + c * rest
    return out


def _frames(
    positions: ArrayLike, directions: ArrayLike, reference_positions: ArrayLike, reference_directions: ArrayLike
) -> tuple[Array, float, Array, Array]:
    """:func:`scaled_frame` of the sensors, and the references' sensor matrix ``T_f`` in that frame."""
    origin, span, t = scaled_frame(np.asarray(positions, dtype=float), np.asarray(directions, dtype=float))
    rpos = np.asarray(reference_positions, dtype=float)
    tf = sensor_matrix((rpos - origin) / span, np.asarray(reference_directions, dtype=float))
    return origin, span, t, tf


def _excited_body(lam: CArray, u: CArray, origin: Array, span: float) -> ScaledBody:
    """:func:`_body_from_modes`, refused when a mode has no residue (not excited by the references)."""
    if np.any(np.linalg.norm(u, axis=0) == 0.0):
        raise IdentificationError("a rigid-body mode has no residue: the references do not excite it")
    return _body_from_modes(lam, u, origin, span)


def _body_from_modes(lam: CArray, u: CArray, origin: Array, span: float) -> ScaledBody:
    """M, K, C and the body from six unity-modal-A modes ``u`` (6, 6) in the scaled frame (origin, span)."""
    m_inv = np.sum(2.0 * (lam[None, None, :] * u[:, None, :] * u[None, :, :]).real, axis=2)
    k_inv = -np.sum(2.0 * (u[:, None, :] * u[None, :, :] / lam[None, None, :]).real, axis=2)
    mcm = -np.sum(2.0 * (lam[None, None, :] ** 2 * u[:, None, :] * u[None, :, :]).real, axis=2)
    m_s = np.linalg.solve(0.5 * (m_inv + m_inv.T), np.eye(6))
    m_s = 0.5 * (m_s + m_s.T)
    k_s = np.linalg.solve(0.5 * (k_inv + k_inv.T), np.eye(6))
    c_s = m_s @ (0.5 * (mcm + mcm.T)) @ m_s
    # scaled coordinates x~ = [x_t, span theta]: physical matrices D X~ D with D = diag(I, span I)
    d = np.concatenate([np.ones(3), span * np.ones(3)])
    m_o, k_o, c_o = (d[:, None] * x * d[None, :] for x in (m_s, k_s, 0.5 * (c_s + c_s.T)))
    mass = float(np.trace(m_o[:3, :3]) / 3.0)
    if not mass > 0.0:
        raise IdentificationError(f"the scaled modes give a mass of {mass:.4g}, not positive")
    # M_o = [[m I, -m S(c)], [m S(c), J_o]]: c from the coupling block (least squares over both blocks)
    sc = 0.5 * (m_o[3:, :3] - m_o[:3, 3:]) / mass
    c_rel = np.array([sc[2, 1] - sc[1, 2], sc[0, 2] - sc[2, 0], sc[1, 0] - sc[0, 1]]) / 2.0
    cg = origin + c_rel
    g = transfer_matrix(-c_rel)  # x_o = G x_g: the origin's motion from the CG's
    m_g, k_g, c_g = (g.T @ x @ g for x in (m_o, k_o, c_o))
    inertia = 0.5 * (m_g[3:, 3:] + m_g[3:, 3:].T)
    return ScaledBody(mass, cg, inertia, 0.5 * (k_g + k_g.T), 0.5 * (c_g + c_g.T), 0.5 * (m_g + m_g.T))


ORDER_RAISE = 4
"""Without ``max_order``, the pLSCF order is doubled from its default until ``n_modes`` stable modes
are found, up to this many times the default."""


def _stable_modes(
    freq: Array,
    h: CArray,
    band: tuple[float, float],
    top: int,
    cap: int,
    n_modes: int | None,
    weighting: str,
    criteria: Criteria | None,
    progress: ProgressCallback | None,
) -> tuple[list[OrderPoles], list[Cluster], int]:
    """Stabilisation diagram and stable clusters over orders 1..top, the order doubled up to `cap` until
    `n_modes` are stable (the models of the lower orders are kept: each order is fitted once).

    Returns
    -------
    diagram, clusters, top
        The diagram over every order fitted, its clusters (a mode stable at a
        third of the orders at least), and the highest order.
    """
    models = plscf_poles(freq, h, list(range(1, top + 1)), band=band, weighting=weighting)
    crit = criteria if criteria is not None else Criteria()
    while True:
        if progress is not None:
            progress("pLSCF orders", top, top)
        diagram = stabilise(models, band, crit)
        clusters = cluster_stable(diagram, min_count=max(3, top // 3))
        if n_modes is None or len(clusters) >= n_modes or top >= cap:
            return diagram, clusters, top
        new_top = min(cap, 2 * top)
        models += plscf_poles(freq, h, list(range(top + 1, new_top + 1)), band=band, weighting=weighting)
        top = new_top


def fit_frf_modes(
    frequencies: ArrayLike,
    frf: ArrayLike,
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
    *,
    band: tuple[float, float] | None = None,
    residue_band: tuple[float, float] | None = None,
    n_modes: int | None = None,
    max_order: int | None = None,
    lower: bool = False,
    upper: bool = True,
    weighting: str = "relative",
    refine: bool = True,
    criteria: Criteria | None = None,
    progress: ProgressCallback | None = None,
    structured: bool = True,
) -> FrfModes:
    """Poles, residues and shapes from accelerance FRFs: pLSCF, stabilisation diagram, LSFD.

    Parameters
    ----------
    frequencies : array_like, shape (f,)
        Hz, ascending, positive.
    frf : array_like of complex, shape (p, q, f)
        Accelerance: sensor ``i`` per unit force at reference ``j``.
    positions, directions : array_like, shape (p, 3)
        Sensors (length, unit axes).
    reference_positions, reference_directions : array_like, shape (q, 3)
        Force points and unit directions.
    band : (float, float), optional
        Band of the pole fit (Hz); default :func:`rigid_band`.
    residue_band : (float, float), optional
        Band of the residue fit (Hz), which may reach further up than the
        poles' (the upper residual stands for what lies above); default
        the poles' band.
    n_modes : int, optional
        Keep the `n_modes` modes stable at the most orders; default every mode
        stable at a third of the orders or more.
    max_order : int, optional
        Highest polynomial order of the sweep (``n q`` poles). The sweep
        starts at ``max(8, ceil(48 / q))`` (or `max_order`, if lower) and, with
        `n_modes` given, the order is doubled until `n_modes` stable modes are
        found, up to `max_order` (default: :data:`ORDER_RAISE` times the
        start); the orders already fitted are kept, so raising costs only the
        new ones. Without `n_modes`, every order up to `max_order` is fitted.
    lower, upper : bool
        Residual terms of the LSFD (:func:`residues_lsfd`).
    weighting : {"relative", "none"}
        Weighting of both fits (:func:`plscf_poles`).
    refine : bool
        Refine the poles of the diagram by nonlinear least squares on the FRFs
        (:func:`refine_poles`) before the residues are taken.
    criteria : Criteria, optional
        Tolerances of the stabilisation diagram (default :class:`Criteria`).
    progress : ProgressCallback, optional
        Called per order of the sweep.
    structured : bool
        Fit the six rigid-body modes to the FRFs with the structure ``R_k = T u_k
        u_k^T T_f^T`` imposed (:func:`refine_rigid_modes`, poles fixed) instead of
        projecting the free residues on it: eq. (18)'s worst inertia error on the
        issue's test drops from 14 % to 2.5 % (``benchmarks/frf_eq18.py``).

    Returns
    -------
    FrfModes
        Modes ascending in frequency. The six lowest are taken as the rigid-body
        modes and their shapes scaled by the force (``scaled``), when the sensors
        see six rigid-body motions; other shapes are scaled to a largest value of 1.

    Raises
    ------
    InputError
        Bad shapes, band or options.
    IdentificationError
        No stable mode (or fewer than `n_modes`).
    """
    freq, h = _check(frequencies, frf)
    pos = np.asarray(positions, dtype=float)
    dirs = np.asarray(directions, dtype=float)
    rpos = np.asarray(reference_positions, dtype=float)
    rdirs = np.asarray(reference_directions, dtype=float)
    p, q = h.shape[:2]
    if pos.shape != (p, 3) or dirs.shape != (p, 3) or rpos.shape != (q, 3) or rdirs.shape != (q, 3):
        raise InputError(f"frf has {p} responses and {q} references; positions and directions must match")
    if n_modes is not None and not (isinstance(n_modes, int) and n_modes >= 1):
        raise InputError(f"n_modes must be a positive integer, got {n_modes}")
    top = max_order if max_order is not None else max(8, -(-48 // q))
    if not (isinstance(top, int) and top >= 3):
        raise InputError(f"must be an integer of at least 3, got {max_order}", source="max_order")
    auto_poles = rigid_band(freq, h)[0]
    (lo, hi), _ = _band_lines(freq, band if band is not None else auto_poles)
    res_band = residue_band if residue_band is not None else (lo, hi)
    if max_order is not None and n_modes is not None:  # raised up to the order given, stopped once stable
        top, cap = min(top, max(8, -(-48 // q))), top
    else:
        cap = top if n_modes is None else ORDER_RAISE * top
    first = top
    diagram, clusters, top = _stable_modes(freq, h, (lo, hi), top, cap, n_modes, weighting, criteria, progress)
    if n_modes is not None:
        if len(clusters) < n_modes:
            raised = f" at orders up to {top} (raised from {first})" if top > first else ""
            raise IdentificationError(
                f"{len(clusters)} stable mode(s) in {lo:.4g}-{hi:.4g} Hz{raised}, {n_modes} asked: widen the band "
                "or raise the order"
            )
        clusters = clusters[:n_modes]
    if not clusters:
        raise IdentificationError(f"no stable mode in {lo:.4g}-{hi:.4g} Hz")
    clusters.sort(key=lambda c: abs(c.pole))
    lam = np.array([c.pole for c in clusters], dtype=complex)
    if refine:
        lam = refine_poles(freq, h, lam, band=res_band, lower=lower, upper=upper, weighting=weighting)
        lam = lam[np.argsort(np.abs(lam))]
    residues, low, up, misfit = residues_lsfd(
        freq, h, lam, band=res_band, lower=lower, upper=upper, weighting=weighting
    )
    n = lam.size
    shapes, part = _rank_one_shapes(residues)
    scaled = np.zeros(n, dtype=bool)
    if n >= 6 and _scale_rigid(freq, h, lam, residues, (pos, dirs, rpos, rdirs), shapes, part, structured, res_band):
        scaled[:6] = True
    return FrfModes(
        poles=lam,
        residues=residues,
        shapes=shapes,
        participation=part,
        scaled=scaled,
        stable_count=np.array([c.count for c in clusters], dtype=int),
        diagram=tuple(diagram),
        band=(lo, hi),
        residue_band=(float(res_band[0]), float(res_band[1])),
        lower=low,
        upper=up,
        residual=misfit,
    )


def _rank_one_shapes(residues: CArray) -> tuple[CArray, CArray]:
    """Each mode's residue matrix (p, q) as its rank-one shape (largest entry 1) times participation."""
    n, p, q = residues.shape
    shapes = np.zeros((p, n), dtype=complex)
    part = np.zeros((q, n), dtype=complex)
    for k in range(n):
        left, sv, right = np.linalg.svd(residues[k])
        a = left[:, 0] * sv[0]
        b = right[0]
        big = a[np.argmax(np.abs(a))]
        shapes[:, k], part[:, k] = a / big, b * big
    return shapes, part


def _scale_rigid(
    freq: Array,
    h: CArray,
    lam: CArray,
    residues: CArray,
    geometry: tuple[Array, Array, Array, Array],
    shapes: CArray,
    part: CArray,
    structured: bool,
    res_band: tuple[float, float],
) -> bool:
    """Scale the first six modes by the force as rigid-body modes (unity modal A), in place in `shapes`, `part`.

    `geometry` is (sensor positions, directions, reference positions, directions). False (nothing scaled)
    when the layout determines no rigid body.
    """
    pos, dirs, rpos, rdirs = geometry
    n, p, q = residues.shape
    try:
        origin, span, t = scaled_frame(pos, dirs)
    except IdentificationError:
        pass
    else:
        tf = sensor_matrix((rpos - origin) / span, rdirs)
        u = _rigid_modes(residues[:6], t, tf)[0]
        rigid_noise = None
        if structured:
            others = h
            if n > 6:  # the other modes of the band as their residues give them
                w_all = 2.0 * np.pi * freq
                g_all = _design(w_all, lam[6:], False, False)[0]  # (f, 2 (n - 6))
                coef = np.stack([residues[6:].real, residues[6:].imag], axis=1).reshape(2 * (n - 6), p, q)
                others = h - np.einsum("fc,cpq->pqf", g_all, coef)
            u, rigid_noise = refine_rigid_modes(freq, others, lam[:6], u, t, tf, band=res_band)
        # the projection discards the shapes' non-rigid part, the measure of their noise: keep it
        shapes[:, :6] = with_nonrigid_residual(t @ u, shapes[:, :6], pos, dirs, rigid_noise)
        part[:, :6] = tf @ u
        return True
    return False
