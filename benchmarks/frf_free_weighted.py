"""The first-order mass line weighted by each line's noise level, against the unweighted fit and a true-noise oracle.

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src .venv/bin/python benchmarks/frf_free_weighted.py
[--draws 200] [--first-seed 0] [--regimes free,free_slope_low,free_slope_high] [--second-order 0]``

The draws are benchmarks/frf_coverage.py's free-free regimes (seed ``s``: its body and its noise). Three
estimators of the mass line's constants, each then mapped to mass, CG and inertia the same way
(``massline._body_from_inverse_mass``):

* ``unweighted``: ordinary least squares over the band (the first-order route before issue 21's s31 stop), its
  intervals from ``massline._first_order_intervals`` on the unweighted misfit;
* ``weighted``: what ``mass_line(..., supports="first_order")`` answers now: each line weighted by its noise
  level estimated from the misfit (``massline._level_weighted``, a feasible generalised least squares);
* ``oracle``: least squares weighted by the true noise level of each line (the simulator's variance averaged
  over the FRFs of the line): what the weighted fit would be with the level known.

Per regime and figure (mass, CG x, y, z, inertia diagonal): the RMS error over the draws (mass relative, CG over
the body's largest half-size, inertia over the trace / 3) of each estimator, the ratios weighted / unweighted
and weighted / oracle, and the coverage, mean and RMS ``z`` of the unweighted and weighted intervals.

``--second-order R`` (``free`` only) also prints the delta method's second-order bias of the map from the
constants to the seven figures: ``E[g(y0 + e)] - g(y0)`` at the noise-free constants ``y0``, ``e`` drawn ``R``
times (antithetic) from the unweighted constants' true covariance, in units of the figure's standard deviation
over those draws (issue 21: the free-free J xx mean z of +0.2 on seeds 0-199).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from frf_coverage import SLOPE, binomial
from frf_sim import add_elastic, make_rig
from rigidid.core.frfmodes import scaled_frame
from rigidid.core.geometry import sensor_matrix
from rigidid.core.massline import _body_from_inverse_mass, _correction_design, _first_order_intervals, mass_line

Z95 = 1.959963984540054
NAMES = ("mass", "CG x", "CG y", "CG z", "Jxx", "Jyy", "Jzz")
BAND = (30.0, 150.0)
EXTRA = ("stiffness", "damping", "upper_residual")


def draw(seed: int, regime: str) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray]:
    """The rig, lines, noisy FRFs and the true noise's standard deviation per value, as frf_coverage.py draws."""
    rng = np.random.default_rng(seed)
    rig = make_rig(rng, free=True)
    add_elastic(rig, rng, 1500.0)
    f = np.arange(20.0, 200.0, 1.0)
    h0 = rig.frf(f)
    e = (rng.standard_normal(h0.shape) + 1j * rng.standard_normal(h0.shape)) / np.sqrt(2.0)
    t = np.log(f / BAND[0]) / np.log(BAND[1] / BAND[0])
    ramp = {"free": np.ones_like(f), "free_slope_low": np.sqrt(SLOPE) ** (1.0 - 2.0 * t)}.get(
        regime, np.sqrt(SLOPE) ** (2.0 * t - 1.0)
    )
    sigma = (0.005 * np.abs(h0) + 0.005 * np.sqrt(np.mean(np.abs(h0) ** 2, axis=2, keepdims=True))) * ramp
    return rig, f, h0 + sigma * e, sigma


def figures(m: float, cg: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """The seven figures."""
    return np.r_[m, cg, np.diag(inertia)]


def one(seed: int, regime: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Scaled errors of the unweighted, weighted and oracle fits; z of the unweighted and weighted intervals."""
    rig, f, h, sigma = draw(seed, regime)
    sel = (f >= BAND[0]) & (f <= BAND[1])
    n_f, q = int(sel.sum()), rig.refs.shape[0]
    origin, span, t = scaled_frame(rig.sensors, rig.sensor_dirs)
    tf = sensor_matrix((rig.refs - origin) / span, rig.ref_dirs)
    y = np.linalg.lstsq(t, h[:, :, sel].reshape(t.shape[0], -1), rcond=None)[0].reshape(6 * q, n_f)
    design = _correction_design(2.0 * np.pi * f[sel], EXTRA, None)
    target = np.concatenate([y.real, y.imag], axis=1).T
    coef = np.linalg.lstsq(design, target, rcond=None)[0]
    y_ols = coef[0].reshape(6, q)
    iv_ols = _first_order_intervals(design, design @ coef - target, y_ols, tf, origin, span)
    level = np.tile(np.mean(sigma[:, :, sel] ** 2, axis=(0, 1)), 2)[:, None]
    y_orc = np.linalg.lstsq(design / np.sqrt(level), target / np.sqrt(level), rcond=None)[0][0].reshape(6, q)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = mass_line(f, h, rig.sensors, rig.sensor_dirs, rig.refs, rig.ref_dirs, band=BAND, supports="first_order")
    assert r.intervals is not None
    truth = figures(rig.mass, rig.cg, rig.inertia)
    size = float(np.max(np.abs(rig.sensors - rig.cg)))
    scale = np.r_[rig.mass, size, size, size, np.full(3, np.trace(rig.inertia) / 3.0)]
    est_w = figures(r.mass, r.center_of_gravity, r.inertia_tensor)
    est_u = figures(*_body_from_inverse_mass(y_ols, tf, origin, span))
    est_o = figures(*_body_from_inverse_mass(y_orc, tf, origin, span))
    se_u = figures(iv_ols.mass.std, iv_ols.center_of_gravity.std, iv_ols.inertia_tensor.std)
    iv = r.intervals
    se_w = figures(iv.mass.std, iv.center_of_gravity.std, iv.inertia_tensor.std)
    return (
        (est_u - truth) / scale,
        (est_w - truth) / scale,
        (est_o - truth) / scale,
        (est_u - truth) / se_u,
        (est_w - truth) / se_w,
    )


def second_order(seed: int, repeats: int) -> np.ndarray:
    """The delta method's second-order bias of the seven figures on draw `seed` (``free``), in their SD."""
    rig, f, _, sigma = draw(seed, "free")
    sel = (f >= BAND[0]) & (f <= BAND[1])
    q = rig.refs.shape[0]
    origin, span, t = scaled_frame(rig.sensors, rig.sensor_dirs)
    tf = sensor_matrix((rig.refs - origin) / span, rig.ref_dirs)
    a = np.linalg.pinv(_correction_design(2.0 * np.pi * f[sel], EXTRA, None))[0][: int(sel.sum())]
    tp = np.linalg.pinv(t)
    h0 = rig.frf(f)
    y0 = np.tensordot(np.einsum("ip,pjl->ijl", tp, h0[:, :, sel]).real, a, axes=([2], [0])).reshape(-1)
    half_var = sigma[:, :, sel] ** 2 / 2.0
    cov = np.zeros((6 * q, 6 * q))
    for j in range(q):
        idx = np.arange(6) * q + j
        cov[np.ix_(idx, idx)] = np.einsum("l,ip,pl,kp->ik", a**2, tp, half_var[:, j, :], tp)
    e = np.random.default_rng(10**6 + seed).standard_normal((repeats, y0.size)) @ np.linalg.cholesky(cov).T
    vals = np.array(
        [figures(*_body_from_inverse_mass((y0 + s * d).reshape(6, q), tf, origin, span)) for d in e for s in (1, -1)]
    )
    base = figures(*_body_from_inverse_mass(y0.reshape(6, q), tf, origin, span))
    out: np.ndarray = (vals.mean(axis=0) - base) / vals.std(axis=0)
    return out


def calibration(label: str, z: np.ndarray) -> str:
    """Coverage, mean and RMS z per figure."""
    za = np.abs(z)
    n = len(z)
    cells = ", ".join(
        f"{nm} {binomial(float(np.mean(za[:, j] < Z95)), n)} {z[:, j].mean():+.2f}/{np.sqrt(np.mean(z[:, j] ** 2)):.2f}"
        for j, nm in enumerate(NAMES)
    )
    pooled = binomial(float(np.mean(za < Z95)), n)
    return f"  {label}: coverage, mean z/RMS z: {cells}\n    pooled {pooled}, RMS z {np.sqrt(np.mean(z**2)):.3f}, " + (
        f"draws beyond 4 SE {int(np.sum(za.max(axis=1) > 4.0))} (worst {za.max():.2f})"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--regimes", default="free,free_slope_low,free_slope_high")
    ap.add_argument("--second-order", type=int, default=0, help="noise draws per body for the second-order bias")
    a = ap.parse_args()
    seeds = range(a.first_seed, a.first_seed + a.draws)
    for regime in filter(None, a.regimes.split(",")):
        out = [one(s, regime) for s in seeds]
        eu, ew, eo, zu, zw = (np.array([o[k] for o in out]) for k in range(5))
        rms = [np.sqrt(np.mean(e**2, axis=0)) for e in (eu, ew, eo)]
        print(f"{regime}, seeds {seeds[0]}-{seeds[-1]}:")
        print(
            "  RMS error weighted / unweighted: "
            + ", ".join(f"{n} {v:.3f}" for n, v in zip(NAMES, rms[1] / rms[0], strict=True))
        )
        print(
            "  RMS error weighted / oracle:     "
            + ", ".join(f"{n} {v:.3f}" for n, v in zip(NAMES, rms[1] / rms[2], strict=True))
        )
        print(calibration("unweighted", zu))
        print(calibration("weighted  ", zw), flush=True)
    if a.second_order:
        b = np.array([second_order(s, a.second_order) for s in seeds])
        print(
            f"second-order bias of the delta method (free, seeds {seeds[0]}-{seeds[-1]}, in SD): "
            + ", ".join(
                f"{n} {m:+.3f} (+-{s:.3f})"
                for n, m, s in zip(NAMES, b.mean(axis=0), b.std(axis=0) / np.sqrt(len(b)), strict=True)
            )
        )


if __name__ == "__main__":
    main()
