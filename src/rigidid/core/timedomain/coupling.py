"""An AC coupling nobody stated: its score test in a refit's residual and its corner.

A first-order high-pass (a sensor's or a conditioner's AC coupling, corner ``w_c``) passes each mode
of a free decay scaled by ``H(s_k) = s_k / (s_k + w_c)``, and adds its own natural mode
``b_c e^{-w_c t}`` on every channel (:mod:`rigidid.core.timedomain.chain`). When every channel has
the same corner, the scaling is common to the channels and the refit's free modal amplitudes
absorb it; the transient is what an unmodelled coupling leaves in the residual, and what biases the
body (chain_matrix.py's ``ac`` cell: a 2 Hz corner, inertia entries up to 3.4 standard errors off).

The test adds one column per channel and impact, ``e^{-a t}`` in that channel only, to the refit's
linear columns (the modal amplitudes, each channel's offset, drift and hum), for each decay rate
``a`` of a grid. At the fit's minimum the residual ``r`` is orthogonal to those columns, so the
columns' score statistic is::

    T(a) = sum_i s_i^T W_i^+ s_i / s2,   s_i = Z~_i^T r_i,   W_i = Z~_i^T P Z~_i

(``Z~`` the columns with the per-channel columns projected out, ``P`` the projector off the modal
columns; the model's tangent in the body's parameters is not projected out, which only lowers
``T``: the test errs on the side of no coupling). For a fixed ``a`` and Gaussian noise ``T`` is
``chi2`` with ``rank W`` degrees of freedom (channels times impacts); the largest over the grid is
judged with a Bonferroni factor, the grid's size. Everything is formed from per-impact sums over
time (the modal columns are ``e^{s_k t}`` times a shape across the channels), never from the
design itself.

The corner is where ``T`` peaks: on the grid, then on a finer grid between the peak's neighbours,
refined by a parabola in ``log a``; its standard error is the profile's: ``T`` falls by 1 at one
standard error (``sqrt(2 / -T'')`` in ``log a``).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.chisquare import chi2_sf
from rigidid.core.linalg import pseudo_inverse

__all__ = ["COUPLING_FALSE_ALARM", "CouplingScore", "coupling_score", "coupling_statistic", "modal_gram"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

_Columns = tuple[Sequence[Array], Sequence[Array], Sequence[CArray], Sequence[Array], CArray]

COUPLING_FALSE_ALARM = 1e-9
"""The test's false-alarm rate (Bonferroni over the grid: conservative, the grid's rates overlap). Small because
what flags it without a coupling is not noise but the misfit of other effects: on chain_matrix.py's seeds
1000-1019 a sensor correction's remainder (sens, seed 1007: p 2.5e-7) and a clipped channel (clip80, seed 1010:
p 3e-4) peaked inside the rates; real couplings read p 1e-14 or below (chain_regimes.py's ac cells, 5 % noise
included)."""

_GRID = 30  # decay rates, log-spaced
_FINE = 17  # rates between the coarse peak's neighbours
_LOWEST_SHARE = 1e-4  # a column this much of itself left after the offsets and drifts: the local columns hold it


@dataclass(frozen=True)
class CouplingScore:
    """The score test for an unstated AC coupling (module notes).

    Attributes
    ----------
    corner_hz : float
        The corner where the statistic peaks (Hz).
    corner_std_hz : float
        Its standard error from the profile's curvature (Hz; inf at the grid's edge).
    statistic : float
        ``T`` at the peak (chi-square units).
    dof : int
        Its degrees of freedom (channels times impacts, less any the local columns hold).
    p_value : float
        Bonferroni-corrected over the grid.
    false_alarm : float
        The rate it is judged at.
    modelled : bool
        Whether the refit reported models a coupling at `corner_hz`.
    interior : bool
        Whether the statistic peaks inside the rates tried: at the fastest, the misfit decays faster than
        any coupling tried (sensor errors leave a misfit largest at the decay's start: chain_matrix.py's
        ``sens`` cell peaked there in 20 of 20 runs, p below 1e-300); at the slowest, it is a drift's.
    """

    corner_hz: float
    corner_std_hz: float
    statistic: float
    dof: int
    p_value: float
    false_alarm: float = COUPLING_FALSE_ALARM
    modelled: bool = False
    interior: bool = True

    @property
    def flagged(self) -> bool:
        """Whether the residual shows the transient beyond the false-alarm rate, peaking inside the rates tried."""
        return self.p_value < self.false_alarm and self.interior


def coupling_statistic(
    residuals: Sequence[Array],
    times: Sequence[Array],
    exponentials: Sequence[CArray],
    local: Sequence[Array],
    shapes: CArray,
    rates: Array,
    tangent: Sequence[Array] | None = None,
) -> tuple[Array, Array]:
    """``T(a) s2`` and its degrees of freedom for each decay rate (module notes).

    Parameters
    ----------
    residuals : sequence of ndarray, shape (n_i, p)
        Per impact, the fit's weighted residual (orthogonal to the linear columns).
    times : sequence of ndarray, shape (n_i,)
        Its times, in the units `rates` are in.
    exponentials : sequence of ndarray of complex, shape (n_i, k)
        The modes' ``e^{s_k t}``.
    local : sequence of ndarray, shape (n_i, q)
        The columns each channel has its own copy of (offset, drift, hum).
    shapes : ndarray of complex, shape (p, k)
        The modes' weighted shapes at the channels (the chain's transfer in them).
    rates : ndarray, shape (g,)
        The decay rates ``a`` tried (1 / the units of `times`).
    tangent : sequence of ndarray, shape (n_i, p, m), optional
        Per impact, the fit's projected Jacobian in its nonlinear parameters (orthogonal to the linear
        columns, as the residual): the columns are projected off it too, so that ``T(a)`` is the drop in
        the residual of a refit with the columns (to first order in the parameters' move) and peaks at the
        transient's rate, where without it the parameters' absorbed share of the transient biases the peak
        (a 2 Hz corner read 1.66 Hz). Its cost is the columns' products with it.

    Returns
    -------
    statistic : ndarray, shape (g,)
        ``sum_i s_i^T W_i^+ s_i`` (divide by the residual's variance for ``T``).
    dof : ndarray of int, shape (g,)
        ``sum_i rank W_i``.
    """
    g = rates.size
    columns: _Columns = (residuals, times, exponentials, local, shapes)
    if tangent is not None:
        return _with_tangent(columns, rates, tangent)
    stat, dof = np.zeros(g), np.zeros(g, dtype=int)
    for s, w, keep, _ in _per_impact(columns, rates):
        for j in np.flatnonzero(keep):
            winv, rank = pseudo_inverse(w[j], symmetric=True)
            stat[j] += float(s[j] @ winv @ s[j])
            dof[j] += rank
    return stat, dof


def _per_impact(columns: _Columns, rates: Array) -> Iterator[tuple[Array, Array, NDArray[np.bool_], Array]]:
    """Per impact (`columns` as :func:`coupling_statistic`'s first five arguments): the scores ``s`` (g, p),
    ``W`` (g, p, p), the rates whose columns the local ones do not hold (g,) and the columns off the local
    ones, ``Z~`` (n, g)."""
    residuals, times, exponentials, local, shapes = columns
    p = shapes.shape[0]
    for r, t, ex, loc in zip(residuals, times, exponentials, local, strict=True):
        q, _ = np.linalg.qr(loc)
        e = ex - q @ (q.T @ ex)  # the modes' columns off the local ones, (n, k)
        ginv = pseudo_inverse(modal_gram(e, shapes), symmetric=True)[0]
        z = np.exp(-np.outer(t, rates))  # (n, g)
        zt = z - q @ (q.T @ z)
        zz = np.einsum("ng,ng->g", zt, zt)
        keep = zz > _LOWEST_SHARE * np.einsum("ng,ng->g", z, z)
        a = (zt.T @ e)[:, None, :] * shapes[None]  # (g, p, k): the columns' products with e^{s_k t} phi_k
        b = np.concatenate([a.real, -a.imag], axis=2)  # with the modal columns [Re, -Im]
        w = zz[:, None, None] * np.eye(p)[None] - b @ ginv @ b.transpose(0, 2, 1)
        yield zt.T @ r, w, keep, zt


def _with_tangent(columns: _Columns, rates: Array, tangent: Sequence[Array]) -> tuple[Array, Array]:
    """:func:`coupling_statistic` with the columns projected off the fit's Jacobian too: the impacts share the
    parameters, so ``W`` is block-diagonal over the impacts less ``C (J^T J)^+ C^T``, ``C = Z~^T J``."""
    g, p = rates.size, columns[4].shape[0]
    jtj = sum(jac.reshape(-1, jac.shape[2]).T @ jac.reshape(-1, jac.shape[2]) for jac in tangent)
    jinv = pseudo_inverse(np.asarray(jtj), symmetric=True)[0]
    scores, blocks, cross, kept = [], [], [], []
    for (s, w, keep, zt), jac in zip(_per_impact(columns, rates), tangent, strict=True):
        n, _, m = jac.shape
        cross.append((zt.T @ jac.reshape(n, p * m)).reshape(g, p, m))
        scores.append(s)
        blocks.append(w)
        kept.append(keep)
    stat, dof = np.zeros(g), np.zeros(g, dtype=int)
    for j in range(g):
        use = [i for i in range(len(scores)) if kept[i][j]]
        if not use:
            continue
        c = np.concatenate([cross[i][j] for i in use])  # (p u, m)
        w = np.zeros((p * len(use), p * len(use)))
        for k, i in enumerate(use):
            w[k * p : (k + 1) * p, k * p : (k + 1) * p] = blocks[i][j]
        s = np.concatenate([scores[i][j] for i in use])
        winv, rank = pseudo_inverse(w - c @ jinv @ c.T, symmetric=True)
        stat[j], dof[j] = float(s @ winv @ s), rank
    return stat, dof


def modal_gram(e: CArray, shapes: CArray) -> Array:
    """The modal columns' Gram matrix (2k, 2k): columns ``Re(e_k phi_k)`` and ``-Im(e_k phi_k)`` over time and channels.

    With ``a_k = e_k phi_k``: ``sum a_k a_l = (e^T e)_kl (phi^T phi)_kl`` and ``sum a_k conj(a_l)`` likewise,
    and ``Re a Re b = Re(ab + a conj b) / 2``, ``Im a Im b = Re(a conj b - ab) / 2``,
    ``Re a Im b = Im(ab - a conj b) / 2``.
    """
    one = (e.T @ e) * (shapes.T @ shapes)
    two = (e.T @ e.conj()) * (shapes.T @ shapes.conj())
    rr = 0.5 * (one + two).real
    ii = 0.5 * (two - one).real
    ri = -0.5 * (one - two).imag  # Re(a_k) * (-Im(a_l))
    out: Array = np.block([[rr, ri], [ri.T, ii]])
    return out


def coupling_score(
    residuals: Sequence[Array],
    times: Sequence[Array],
    exponentials: Sequence[CArray],
    local: Sequence[Array],
    shapes: CArray,
    *,
    variance: float,
    rate_range: tuple[float, float],
    hz_per_rate: float,
    tangent: Sequence[Array] | None = None,
) -> CouplingScore | None:
    """The score test for an unstated AC coupling and its corner (module notes).

    Parameters
    ----------
    residuals, times, exponentials, local, shapes, tangent
        As for :func:`coupling_statistic`. The test is the statistic without `tangent` (cheap, and only
        lower); when it flags, the corner is found with `tangent` (the statistic's peak then the transient's
        rate, not biased by what the fit's parameters absorbed of it).
    variance : float
        The weighted residual's variance (``s2``; 1 at a fit the noise explains).
    rate_range : (float, float)
        The lowest and highest decay rate tried (log-spaced, in 1 / the units of `times`); a peak at either
        is not a coupling (``interior`` False, not flagged).
    hz_per_rate : float
        A rate's corner in Hz per unit rate (``omega / (2 pi)`` for times in units of ``1 / omega``).

    Returns
    -------
    CouplingScore or None
        None when no rate leaves a column the local ones do not hold.
    """
    columns: _Columns = (residuals, times, exponentials, local, shapes)
    lo, hi = rate_range
    logs = np.linspace(math.log(lo), math.log(hi), _GRID)
    stat, dof = coupling_statistic(*columns, np.exp(logs))
    if not np.any(dof > 0):
        return None
    scale = 1.0 / max(variance, np.finfo(float).tiny)
    j = int(np.argmax(np.where(dof > 0, stat, -np.inf)))
    peak, peak_dof = float(stat[j] * scale), int(dof[j])
    p = min(1.0, _GRID * chi2_sf(peak, peak_dof))
    x, std, interior = float(logs[j]), math.inf, 0 < j < _GRID - 1
    if p < COUPLING_FALSE_ALARM and interior and tangent is not None:  # the corner off the tangent too
        wide = np.linspace(logs[max(j - 3, 0)], logs[min(j + 3, _GRID - 1)], 13)
        x, std = _peak(columns, wide, scale, tangent)
    elif interior:
        x, std = _peak(columns, np.linspace(logs[j - 1], logs[j + 1], _FINE), scale, None)
    corner = math.exp(x) * hz_per_rate
    return CouplingScore(corner, corner * std, peak, peak_dof, p, interior=interior)


def _peak(columns: _Columns, logs: Array, scale: float, tangent: Sequence[Array] | None) -> tuple[float, float]:
    """Where the statistic peaks among the log rates `logs` and below it on a finer grid between the peak's
    neighbours, by a parabola; and its standard error in ``log a`` (inf at the edge or without a curvature)."""
    for fine in (False, True):
        tt, dof = coupling_statistic(*columns, np.exp(logs), tangent)
        tt = np.where(dof > 0, tt * scale, -np.inf)
        i = int(np.argmax(tt))
        if not (0 < i < logs.size - 1 and np.isfinite(tt[i - 1]) and np.isfinite(tt[i + 1])):
            return float(logs[i]), math.inf
        if not fine:
            logs = np.linspace(logs[i - 1], logs[i + 1], _FINE)
    h = float(logs[1] - logs[0])
    curve = (tt[i + 1] - 2.0 * tt[i] + tt[i - 1]) / h**2
    if curve >= 0.0:
        return float(logs[i]), math.inf
    step = float(np.clip(-0.5 * (tt[i + 1] - tt[i - 1]) / (h * curve), -h, h))
    return float(logs[i]) + step, math.sqrt(2.0 / -curve)
