"""The noise of FRFs, the misfit of a fit in noise units, and linearised intervals of the FRF routes.

The FRF routes (:func:`rigidid.core.massline.mass_line`,
:func:`rigidid.core.massline.mass_from_residues`) are linear least-squares fits of the
FRFs followed by a smooth map to mass, CG and inertia. Three things make their answers
trustworthy whatever the noise of a laboratory's FRFs:

* **the noise model from the data**: the variance of every FRF value is taken from the
  misfit of a first fit, averaged over the neighbouring lines of the same FRF (leaving the
  line itself out, so that a weight does not correlate with the noise it weights). Noise
  proportional to the FRF, a noise floor that dominates at the anti-resonances, or a mix:
  each gets its own weights, where ``1 / |H|`` is right for the first only;
* **the misfit in noise units**: the noise level is also estimated from the third
  differences of the misfit along frequency (white noise keeps its variance, 20 times, a
  lack of fit that varies smoothly with frequency almost vanishes); the ratio of the RMS
  misfit to it is about 1 for a model that fits and grows with a lack of fit;
* **intervals**: the estimate is a linear function ``a^T h`` of the data, its variance the
  sandwich ``sum a_l^2 e_l^2`` of the misfits ``e_l`` (heteroscedastic noise allowed, with
  the degrees of freedom of the fit), mapped to mass, CG and inertia by the linearisation
  of that map (delta method): 95 % intervals ``estimate -/+ 1.96 std``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.uncertainty import IntervalEstimate
from rigidid.errors import FrfMisfitWarning, IdentificationError, Notice

__all__ = [
    "MISFIT_REFUSE",
    "MISFIT_WARN",
    "BodyIntervals",
    "body_intervals",
    "local_noise",
    "misfit_units",
    "sandwich_variance",
    "verdict",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

NOISE_HALF_WINDOW = 8
"""Lines either side of a line whose misfits estimate its noise variance (16 complex values: the
weights scatter by about 18 %, which costs little efficiency)."""

MISFIT_WARN = 1.5
"""A fit whose misfit exceeds this many times the noise (third differences) is warned about: the
model does not explain the FRFs (a mode, a residual or the supports missing)."""

MISFIT_REFUSE = 5.0
"""A fit whose misfit exceeds this many times the noise is refused: its answer rests on a model the
data contradict."""

Z95 = 1.959963984540054


def local_noise(residual: NDArray[np.complexfloating] | Array, half: int = NOISE_HALF_WINDOW) -> Array:
    """Standard deviation of every complex value from its neighbours' misfits.

    Parameters
    ----------
    residual : ndarray of complex, shape (n, f)
        Misfit of a fit, per FRF (rows) and line (columns).
    half : int
        Lines either side used.

    Returns
    -------
    ndarray, shape (n, f)
        ``sqrt(mean |e|^2)`` over the ``2 half`` nearest lines of the same row, the line
        itself left out (fewer at the band edges), floored at ``1e-6`` of the row's median.
    """
    e2 = np.abs(np.asarray(residual)) ** 2
    n_f = e2.shape[1]
    c = np.concatenate([np.zeros((e2.shape[0], 1)), np.cumsum(e2, axis=1)], axis=1)
    idx = np.arange(n_f)
    lo = np.maximum(idx - half, 0)
    hi = np.minimum(idx + half + 1, n_f)
    total = c[:, hi] - c[:, lo] - e2
    count = (hi - lo - 1).astype(float)
    var = total / np.maximum(count, 1.0)
    floor = 1e-12 * np.median(var, axis=1, keepdims=True) + np.finfo(float).tiny
    result: Array = np.sqrt(np.maximum(var, floor))
    return result


def misfit_units(residual: Array, n_params: int = 0) -> tuple[float, NDArray[np.float64]]:
    """The RMS misfit over the noise seen in its third differences along frequency.

    Parameters
    ----------
    residual : ndarray, shape (m, f)
        Real misfits (real and imaginary parts as separate rows), weighted as fitted,
        along frequency (columns).
    n_params : int
        Parameters fitted per row (the misfit's degrees of freedom are ``f - n_params``).

    Returns
    -------
    units : float
        ``sqrt(mean e^2 f / (f - n_params)) / sqrt(mean (d^3 e)^2 / 20)``: about 1 when the
        model fits to the noise.
    per_row : ndarray, shape (m,)
        The same ratio per row (where the lack of fit is).

    Notes
    -----
    White noise of variance ``s^2`` has third differences of variance ``20 s^2``; a lack of fit
    that varies slowly over four lines almost vanishes in them.
    """
    r = np.asarray(residual, dtype=float)
    n_f = r.shape[1]
    if n_f < 8:
        return 1.0, np.ones(r.shape[0])
    dof = max(n_f - n_params, 1) / n_f
    ms = np.mean(r**2, axis=1) / dof
    noise = np.mean(np.diff(r, n=3, axis=1) ** 2, axis=1) / 20.0
    tiny = np.finfo(float).tiny
    per_row = np.sqrt(ms / np.maximum(noise, tiny))
    units = float(np.sqrt(np.mean(ms) / max(float(np.mean(noise)), tiny)))
    return units, per_row


def sandwich_variance(a: Array, residual: Array, n_params: int) -> Array:
    """Variance of the linear estimates ``a^T h`` from the misfits (heteroscedastic noise allowed).

    Parameters
    ----------
    a : ndarray, shape (..., n)
        The weights of each estimate on the (real) data values.
    residual : ndarray, shape (..., n)
        The misfits of those values.
    n_params : int
        Parameters of the fit the misfits come from.

    Returns
    -------
    ndarray, shape (...)
        ``sum a^2 e^2 n / (n - n_params)``.
    """
    n = residual.shape[-1]
    result: Array = np.sum(a**2 * residual**2, axis=-1) * n / max(n - n_params, 1)
    return result


@dataclass(frozen=True)
class BodyIntervals:
    """Linearised 95 % intervals of mass, CG and inertia (``estimate -/+ 1.96 std``).

    Attributes
    ----------
    mass, center_of_gravity, inertia_tensor : rigidid.core.uncertainty.IntervalEstimate
        Shapes (), (3,) and (3, 3).
    method : str
        How they were found (one line).
    """

    mass: IntervalEstimate
    center_of_gravity: IntervalEstimate
    inertia_tensor: IntervalEstimate
    method: str


def _interval(estimate: Array, std: Array) -> IntervalEstimate:
    est = np.asarray(estimate, dtype=float)
    sd = np.asarray(std, dtype=float)
    return IntervalEstimate(est, sd, est - Z95 * sd, est + Z95 * sd)


def body_intervals(
    extract: Callable[[Array], tuple[float, Array, Array]],
    y0: Array,
    covariance: Array,
    method: str,
) -> BodyIntervals:
    """Mass, CG and inertia intervals from the covariance of what they are extracted from.

    Parameters
    ----------
    extract : callable
        ``y0 -> (mass, cg (3,), inertia (3, 3))`` (e.g. from ``M^-1 T_f^T``).
    y0 : ndarray
        The estimate it is applied to (any shape; flattened).
    covariance : ndarray, shape (y0.size, y0.size)
        Covariance of ``y0.ravel()``.
    method : str
        Recorded in the result.

    Returns
    -------
    BodyIntervals

    Notes
    -----
    Delta method: the Jacobian of ``extract`` by central differences (steps of ``1e-6`` of
    ``y0``'s largest value), ``cov = J C J^T``.
    """
    y = np.asarray(y0, dtype=float)
    flat = y.reshape(-1)

    def vec(v: Array) -> Array:
        m, cg, inertia = extract(v.reshape(y.shape))
        return np.concatenate([[m], cg, np.asarray(inertia).reshape(-1)])

    base = vec(flat)
    step = 1e-6 * float(np.max(np.abs(flat)))
    jac = np.empty((base.size, flat.size))
    for k in range(flat.size):
        d = np.zeros_like(flat)
        d[k] = step
        jac[:, k] = (vec(flat + d) - vec(flat - d)) / (2.0 * step)
    var = np.maximum(np.einsum("ik,kl,il->i", jac, covariance, jac), 0.0)
    sd = np.sqrt(var)
    return BodyIntervals(
        mass=_interval(base[0], sd[0]),
        center_of_gravity=_interval(base[1:4], sd[1:4]),
        inertia_tensor=_interval(base[4:].reshape(3, 3), sd[4:].reshape(3, 3)),
        method=method,
    )


EXACT_MISFIT = 1e-8
"""A relative misfit below this is exact data (rounding only): no verdict in noise units."""


def verdict(inertia: Array, residual: float, units: float | None, where: str, route: str) -> Notice | None:
    """The verdict on an FRF route's answer: refused, warned about, or accepted.

    Parameters
    ----------
    inertia : ndarray, shape (3, 3)
        The inertia tensor about the CG it gives.
    residual : float
        Its relative misfit.
    units : float or None
        Its misfit in noise units (:func:`misfit_units`; None: not measured).
    where : str
        Where the misfit is worst (for the message).
    route : str
        The route's name (for the message).

    Returns
    -------
    Notice or None
        A :class:`~rigidid.errors.FrfMisfitWarning` when the misfit exceeds :data:`MISFIT_WARN`
        noise units.

    Raises
    ------
    IdentificationError
        If the misfit exceeds :data:`MISFIT_REFUSE` noise units, or the inertia tensor is not
        a body's (principal moments positive, each at most the sum of the other two).
    """
    moments = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
    tol = 1e-9 * float(np.max(np.abs(moments)))
    if moments[0] <= 0.0 or moments[2] > moments[0] + moments[1] + tol:
        raise IdentificationError(
            f"the {route} gives principal moments of inertia {', '.join(f'{v:.4g}' for v in moments)}: not a body "
            f"(misfit {residual:.2g}; the FRFs in this band do not fit the model)"
        )
    if units is None or residual < EXACT_MISFIT:
        return None
    text = (
        f"the {route} misfits the FRFs by {units:.3g} times their noise (worst: {where}): "
        "a mode, a residual or the supports the model leaves out"
    )
    if units > MISFIT_REFUSE:
        raise IdentificationError(text + "; give the band, or the modes (MODES.csv)")
    if units > MISFIT_WARN:
        return Notice(FrfMisfitWarning, text + "; its intervals may be too narrow")
    return None
