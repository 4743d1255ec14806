"""The acquisition chain in the model: AC coupling, anti-alias filter and channel delay.

A channel's reading passes through linear, time-invariant stages: the sensor's or the
conditioner's AC coupling (a high-pass), the data acquisition's anti-alias filter (a low-pass)
and a delay (the converter's group delay, a skew between channels). Each has a transfer
function ``H_c(s)``; their product is the channel's chain.

The free decay through a chain
------------------------------
A free decay is a sum of damped exponentials, ``x(t) = sum_k a_k phi_k e^{s_k t}`` (eq. (19)
of [1]: the poles ``s_k`` of the state matrix). A linear filter with impulse response ``h``
and transfer ``H(s) = int_0^inf h(u) e^{-s u} du`` maps ``e^{s_k t}`` (for ``t`` after the
input became a free decay at ``t_0``) to::

    int_0^{t - t_0} h(u) e^{s_k (t - u)} du + (the part of h acting on the input before t_0)
      = H(s_k) e^{s_k t} - e^{s_k t} int_{t - t_0}^inf h(u) e^{-s_k u} du + ...

The remainder terms are sums of the filter's own natural modes ``e^{p_j (t - t_0)}`` (``p_j``
its poles; for a pure delay ``tau`` nothing after ``t_0 + tau``). So after the filter's
transient the filtered free decay is the same exponentials, each scaled by ``H(s_k)``::

    y_c(t) = sum_k a_k H_c(s_k) phi_ck e^{s_k t} + sum_j b_cj e^{p_j t}.

The refit (:mod:`rigidid.core.timedomain.refine`) uses this: each mode's contribution at the
sensors is multiplied by ``H_c(s_k)``. The anti-alias filter's natural modes decay within a few
of its time constants (milliseconds), so the fit starts :func:`ChainModel.settle_time` later;
the AC coupling's natural modes ``t^j e^{-w_c t}`` (``j`` below its order) are as slow as the
body's and are modelled: linear nuisance columns per channel, like the offsets. The modal
routes (ERA, AR) estimate ``H_c(s_k) phi_ck``: :func:`ChainModel.correct_shapes` divides it out.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["FILTER_TYPES", "AntiAlias", "ChainModel", "ChannelChain"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

FILTER_TYPES = ("butterworth", "bessel")
"""Analog anti-alias filters modelled (a linear-phase digital filter is a delay: ``delay_s``)."""

_SETTLE = 14.0  # time constants of the filter's slowest natural mode: e^-14 < 1e-6 of its start


def _bessel_coefficients(order: int) -> Array:
    """Reverse Bessel polynomial ``theta_n(x) = sum_k (2n-k)! / (2^(n-k) k! (n-k)!) x^k``, ascending powers."""
    n = order
    return np.array(
        [math.factorial(2 * n - k) / (2 ** (n - k) * math.factorial(k) * math.factorial(n - k)) for k in range(n + 1)]
    )


@dataclass(frozen=True)
class AntiAlias:
    """An analog low-pass anti-alias filter as data sheets state it.

    Attributes
    ----------
    kind : {"butterworth", "bessel"}
        The filter's type.
    order : int
        Its order (number of poles), 1 to 16.
    corner_hz : float
        Its -3 dB frequency (Hz).
    """

    kind: str
    order: int
    corner_hz: float

    def poles(self) -> CArray:
        """The filter's poles (rad/s), all in the left half-plane.

        Butterworth: ``w_c e^{i pi (2k + n + 1) / (2 n)}``. Bessel: the roots of the reverse
        Bessel polynomial ``theta_n(s / w_0)``, ``w_0`` such that ``|H(i w_c)| = 1 / sqrt(2)``.
        """
        wc = 2.0 * math.pi * self.corner_hz
        n = self.order
        if self.kind == "butterworth":
            k = np.arange(n)
            return np.asarray(wc * np.exp(1j * math.pi * (2 * k + n + 1) / (2 * n)), dtype=complex)
        coef = _bessel_coefficients(n)
        roots = np.roots(coef[::-1])
        return np.asarray(roots * self._bessel_w0(), dtype=complex)

    def _bessel_w0(self) -> float:
        """The scale ``w_0`` of a Bessel filter whose -3 dB frequency is the corner (bisection)."""
        coef = _bessel_coefficients(self.order)
        target = math.sqrt(2.0) * coef[0]
        lo, hi = 0.0, 1.0
        while abs(np.polyval(coef[::-1], 1j * hi)) < target:
            hi *= 2.0
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if abs(np.polyval(coef[::-1], 1j * mid)) < target else (lo, mid)
        return 2.0 * math.pi * self.corner_hz / (0.5 * (lo + hi))


@dataclass(frozen=True)
class ChannelChain:
    """One channel's chain: AC coupling, anti-alias filter and delay.

    Attributes
    ----------
    highpass_hz : float
        AC coupling's corner (Hz); 0 for DC coupling.
    highpass_order : int
        Number of first-order high-pass sections (``(s / (s + w_c))^n``: sensor and conditioner
        each AC-coupled by an RC stage).
    antialias : AntiAlias or None
        The anti-alias filter (None: none, or one flat and of linear phase, whose group delay is
        part of `delay`).
    delay : float
        The channel's delay (s): ``e^{-s tau}``.
    """

    highpass_hz: float = 0.0
    highpass_order: int = 1
    antialias: AntiAlias | None = None
    delay: float = 0.0

    def transfer(self, s: CArray) -> tuple[CArray, CArray]:
        """``H(s)`` and ``dH/ds`` at the complex frequencies `s` (rad/s).

        ``H(s) = (s / (s + w_h))^m prod_j (-p_j) / (s - p_j) e^{-s tau}``, ``p_j`` the anti-alias
        poles; ``dH/ds = H d(log H)/ds``.
        """
        s = np.asarray(s, dtype=complex)
        h = np.exp(-s * self.delay)
        dlog = np.full(s.shape, -self.delay, dtype=complex)
        if self.highpass_hz > 0.0:
            wh = 2.0 * math.pi * self.highpass_hz
            m = self.highpass_order
            h = h * (s / (s + wh)) ** m
            dlog = dlog + m * (1.0 / s - 1.0 / (s + wh))
        if self.antialias is not None:
            for p in self.antialias.poles():
                h = h * (-p / (s - p))
                dlog = dlog - 1.0 / (s - p)
        return h, h * dlog


@dataclass(frozen=True)
class ChainModel:
    """The chains of a test's channels, in the records' column order.

    Attributes
    ----------
    channels : tuple of ChannelChain
        One per channel.
    """

    channels: tuple[ChannelChain, ...]

    @property
    def identity(self) -> bool:
        """Whether every channel's chain is ``H = 1`` (nothing to model)."""
        return all(c == ChannelChain() for c in self.channels)

    def columns(self, kept: Sequence[int]) -> ChainModel:
        """The chains of the channels `kept` (e.g. clipped ones left out)."""
        return ChainModel(tuple(self.channels[c] for c in kept))

    def transfer(self, s: CArray, extra_delay: Array | None = None) -> tuple[CArray, CArray]:
        """``H_c(s_k)`` and ``dH_c/ds (s_k)``, shape (channels, poles).

        Parameters
        ----------
        s : ndarray of complex, shape (k,)
            Poles (rad/s).
        extra_delay : ndarray, shape (channels,), optional
            Delays (s) added to the stated ones (the refit's estimate).
        """
        s = np.asarray(s, dtype=complex)
        h = np.empty((len(self.channels), s.size), dtype=complex)
        dh = np.empty_like(h)
        for c, chain in enumerate(self.channels):
            h[c], dh[c] = chain.transfer(s)
            if extra_delay is not None and extra_delay[c] != 0.0:
                e = np.exp(-s * extra_delay[c])
                h[c], dh[c] = h[c] * e, dh[c] * e - extra_delay[c] * h[c] * e
        return h, dh

    def correct_shapes(self, poles: CArray, shapes: CArray) -> CArray:
        """Mode shapes with the chain divided out: ``phi_ck / H_c(s_k)``.

        Parameters
        ----------
        poles : ndarray of complex, shape (k,)
            The modes' poles (rad/s).
        shapes : ndarray of complex, shape (channels, k)
            The shapes the modal estimate found in the records (the chain included).

        Returns
        -------
        ndarray of complex, shape (channels, k)
        """
        h, _ = self.transfer(np.asarray(poles, dtype=complex))
        out: CArray = np.asarray(shapes, dtype=complex) / h
        return out

    def settle_time(self) -> float:
        """Time (s) after which every channel reads the free decay: delays passed, anti-alias transients below 1e-6.

        The largest delay (a delayed channel still reads the impact at the decay's start) plus
        :data:`_SETTLE` time constants of the slowest anti-alias pole (``1 / min |Re p_j|``); 0 without
        delays and anti-alias filters. The AC coupling's transient is modelled instead
        (:meth:`highpass_modes`).
        """
        slowest = [float(np.min(np.abs(c.antialias.poles().real))) for c in self.channels if c.antialias is not None]
        late = max(max(c.delay for c in self.channels), 0.0)
        return late + (_SETTLE / min(slowest) if slowest else 0.0)

    def highpass_modes(self) -> list[tuple[float, int, NDArray[np.bool_]]]:
        """The AC coupling's natural modes: ``(w_c, power j, channels)`` for ``t^j e^{-w_c t}``, ``j < order``."""
        out: list[tuple[float, int, NDArray[np.bool_]]] = []
        corners = sorted({(c.highpass_hz, c.highpass_order) for c in self.channels if c.highpass_hz > 0.0})
        for hz, order in corners:
            mask = np.array([(c.highpass_hz, c.highpass_order) == (hz, order) for c in self.channels])
            out += [(2.0 * math.pi * hz, j, mask) for j in range(order)]
        return out

    def nuisance(self, t: Array, omega: float) -> Array | None:
        """Columns of the AC coupling's transients, shape (n, channels, m), or None.

        Parameters
        ----------
        t : ndarray, shape (n,)
            Times from the decay's start, in the refit's units (s times `omega`).
        omega : float
            The refit's time scale (rad/s).
        """
        modes = self.highpass_modes()
        if not modes:
            return None
        out = np.zeros((t.size, len(self.channels), len(modes)))
        for m, (wc, j, mask) in enumerate(modes):
            out[:, mask, m] = ((t**j) * np.exp(-wc / omega * t))[:, None]
        return out

    def decimated_noise_ratio(self, dt: float, taps: Array) -> Array:
        """Per channel, the decimated noise's variance over what white noise of the pre-trigger's variance predicts.

        Noise that entered before the anti-alias filter is coloured by it: its variance is
        ``int |H|^2`` of the raw band, while the decimation filter ``h`` keeps ``int |H|^2 |H_d|^2``.
        The refit scales the pre-trigger's variance by ``sum h^2`` (white noise); this is the
        correction ``int |H|^2 |H_d|^2 / (int |H|^2 sum h^2)`` (about 1.6 for an 8th-order
        Butterworth at 0.4 fs and a decimation by 3; 1 without an anti-alias filter).

        Parameters
        ----------
        dt : float
            The raw sample interval (s).
        taps : ndarray
            The decimation filter's taps (:func:`rigidid.core.timedomain.preprocess.fir_taps`).
        """
        w = np.linspace(0.0, math.pi / dt, 4097)[1:]
        hd = np.abs(np.exp(-1j * np.outer(w * dt, np.arange(taps.size))) @ taps) ** 2
        white = float(np.sum(taps**2))
        out = np.ones(len(self.channels))
        for c, chain in enumerate(self.channels):
            if chain.antialias is not None:
                ha = np.abs(ChannelChain(antialias=chain.antialias).transfer((1j * w).astype(complex))[0]) ** 2
                out[c] = float(np.sum(ha * hd) / np.sum(ha)) / white
        return out
