"""Eq. (18) with the mass given, on modes fitted to FRFs: are the errors covered by identify()'s
own standard errors, and do better shapes or weights help?

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/frf_eq18.py [--trials N] [--draws D]``

The scenario of ``benchmarks/frf_accuracy.py`` (the issue's test: body on mounts as drawn,
8 sensors, 3 references, 1 % FRF noise, one elastic mode at 300 Hz). Per trial the six modes
are fitted as ``rigidid modes --frf`` fits them (pLSCF, refined poles, LSFD residues) and given
to eq. (18) (core.identify.identify, the true mass given) with
  * ``projected``: the shapes modes.csv carried before (each residue projected on rigid-body
    motion, ``T u_k``): their rigid-fit residual is zero, so identify()'s default noise estimate
    (core.noise.estimate_noise) cannot see their noise;
  * ``raw``: the rank-one left factor of each residue, not projected (its rigid-fit residual
    measures the shape noise);
  * ``written``: what modes.csv now carries (FrfModes.shapes): the six modes fitted to the FRFs
    with the rigid-body structure imposed, poles fixed (core.frfmodes.refine_rigid_modes; alone:
    ``structured``), plus a non-rigid part (core.frfmodes.with_nonrigid_residual) sized by that
    fit's covariance, so that identify()'s noise estimate reads the noise of these shapes;
  * ``--bound``: the Cramer-Rao bound of eq. (18)'s inertia from these FRFs with the poles known;
  * ``--pole-noise F D``: the Monte Carlo's frequency and damping noise (identify's defaults,
    0.1 % and 5 %, are far above a modal fit of FRFs: pole error 1e-4 here).
Measured (20 trials, 200 draws, 2026-11-23): projected J err 1.4 % median / 14 % worst with a std
of 0.05 % (error / std 43 median, 381 worst: not honest); written J err 0.41 % / 2.5 %, std 1.1 % /
4.4 %, error / std 0.39 / 1.5; bound 0.45 % / 2.0 %.
and identify()'s Monte Carlo standard error (core.uncertainty.propagate, the noise levels
identify --uncertainty would use) is compared with the actual error: ``z`` = error / std of
the worst inertia diagonal term. Printed per trial, then worst / median.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.frf_accuracy import _scenario_on_mounts


def raw_shapes(residues: np.ndarray) -> np.ndarray:
    """Rank-one left factors of the residues (p, n), each scaled by its singular value."""
    out = np.zeros((residues.shape[1], residues.shape[0]), dtype=complex)
    for k in range(residues.shape[0]):
        left, sv, _ = np.linalg.svd(residues[k])
        out[:, k] = left[:, 0] * sv[0]
    return out


def trial(seed: int, draws: int, base: object = None) -> dict[str, float]:
    from rigidid.core.frfmodes import body_from_scaled_modes, fit_frf_modes
    from rigidid.core.identify import identify
    from rigidid.core.noise import estimate_noise
    from rigidid.core.uncertainty import propagate

    body, pos, dirs, rpos, f, h = _scenario_on_mounts(seed)
    fitted = fit_frf_modes(f, h, pos, dirs, rpos, np.eye(3), n_modes=6)
    lam = fitted.poles
    d_true = np.diag(body.inertia_tensor)
    out: dict[str, float] = {}
    from rigidid.core.frfmodes import rigid_shapes

    projected = rigid_shapes(fitted.residues[:6], pos, dirs, rpos, np.eye(3))[0]
    variants = (("projected", projected), ("raw", raw_shapes(fitted.residues)), ("written", fitted.shapes))
    for name, shapes in variants:
        ident = identify(pos, dirs, lam, shapes, mass=body.mass, warn=False)
        d_est = np.diag(ident.inertia_per_mass) * body.mass
        err = d_est / d_true - 1.0
        levels = estimate_noise(pos, dirs, shapes) if base is None else estimate_noise(pos, dirs, shapes, base=base)
        unc = propagate(pos, dirs, lam, shapes, mass=body.mass, noise=levels, draws=draws, seed=seed)
        std = np.diag(unc.inertia.std) / d_true
        worst = int(np.argmax(np.abs(err)))
        out[f"{name}: J err"] = float(abs(err[worst]))
        out[f"{name}: J std"] = float(std[worst])
        out[f"{name}: z"] = float(abs(err[worst]) / std[worst])
        out[f"{name}: shape noise"] = float(levels.shape)
        out[f"{name}: z max"] = float(np.max(np.abs(err) / std))
        out["observability"] = float(ident.diagnostics.inertia_observability)
    from rigidid.core.frfmodes import _rigid_modes, refine_rigid_modes, scaled_frame
    from rigidid.core.geometry import sensor_matrix

    origin, span, t = scaled_frame(pos, dirs)
    tf = sensor_matrix((rpos - origin) / span, np.eye(3))
    u0 = _rigid_modes(fitted.residues[:6], t, tf)[0]
    u1 = refine_rigid_modes(f, h, lam, u0, t, tf, band=fitted.residue_band)[0]
    ident = identify(pos, dirs, lam, t @ u1, mass=body.mass, warn=False)
    out["structured: J err"] = float(np.max(np.abs(np.diag(ident.inertia_per_mass) * body.mass / d_true - 1.0)))
    sb = body_from_scaled_modes(lam, fitted.residues[:6], pos, dirs, rpos, np.eye(3))
    out["scaled: J err"] = float(np.max(np.abs(np.diag(sb.inertia_tensor) / d_true - 1.0)))
    return out


def bound(seed: int, noise: float = 0.01) -> dict[str, float]:
    """Cramer-Rao bound of eq. (18)'s inertia from these FRFs, with the poles known.

    The FRF model ``H = sum_k [R_k g_k + conj(R_k) h_k] + U (w / w_top)^2`` with
    ``R_k = T u_k u_k^T T_f^T`` (the rigid-body structure, unity modal A) and the
    upper residual ``U`` free per pair; Fisher information of the 72 real parameters of
    the six ``u_k`` (and the 2 p q of ``U``) for complex noise of `noise` relative to each
    value, at the fitted modes; propagated to eq. (18)'s inertia diagonal (the true mass
    given) by finite differences of identify(). No shape estimator using these FRFs
    with known poles does better (asymptotically, unbiased); the poles' own noise only
    adds to it.
    """
    from rigidid.core.frfmodes import _rigid_modes, fit_frf_modes, scaled_frame
    from rigidid.core.geometry import sensor_matrix
    from rigidid.core.identify import identify

    body, pos, dirs, rpos, f, h = _scenario_on_mounts(seed)
    fitted = fit_frf_modes(f, h, pos, dirs, rpos, np.eye(3), n_modes=6)
    lam = fitted.poles
    origin, span, t = scaled_frame(pos, dirs)
    tf = sensor_matrix((rpos - origin) / span, np.eye(3))
    u = _rigid_modes(fitted.residues[:6], t, tf)[0]
    lo, hi = fitted.residue_band
    sel = (f >= lo) & (f <= hi)
    w = 2.0 * np.pi * f[sel]
    g = -(w**2)[None, :] / (1j * w[None, :] - lam[:, None])  # (6, f)
    hh = -(w**2)[None, :] / (1j * w[None, :] - np.conj(lam)[:, None])
    model = np.zeros((pos.shape[0], 3, w.size), dtype=complex)
    for k in range(6):
        r = t @ np.outer(u[:, k], u[:, k]) @ tf.T
        model += r[:, :, None] * g[k] + np.conj(r)[:, :, None] * hh[k]
    sigma = noise * np.abs(model) / np.sqrt(2.0)  # per real and imaginary part
    cols = []
    for k in range(6):
        for a in range(6):
            e = np.zeros(6)
            e[a] = 1.0
            b = t @ (np.outer(e, u[:, k]) + np.outer(u[:, k], e)) @ tf.T
            cols.append(b[:, :, None] * g[k] + np.conj(b)[:, :, None] * hh[k])
            cols.append(1j * b[:, :, None] * g[k] - 1j * np.conj(b)[:, :, None] * hh[k])
    x = (w / w[-1]) ** 2
    for i in range(pos.shape[0]):
        for j in range(3):
            for unit in (1.0, 1j):
                c = np.zeros_like(model)
                c[i, j] = unit * x
                cols.append(c)
    jac = np.stack([np.concatenate([(c.real / sigma).ravel(), (c.imag / sigma).ravel()]) for c in cols], axis=1)
    fisher = jac.T @ jac
    cov = np.linalg.solve(fisher, np.eye(fisher.shape[0]))[:72, :72]
    d_true = np.diag(body.inertia_tensor)

    def inertia(uv: np.ndarray) -> np.ndarray:
        ident = identify(pos, dirs, lam, t @ uv, mass=body.mass, warn=False)
        return np.diag(ident.inertia_per_mass) * body.mass

    grad = np.zeros((3, 72))
    step = 1e-6 * float(np.abs(u).max())
    for n in range(72):
        k, rest = divmod(n, 12)
        a, imag = divmod(rest, 2)
        du = np.zeros_like(u)
        du[a, k] = step * (1j if imag else 1.0)
        grad[:, n] = (inertia(u + du) - inertia(u - du)) / (2.0 * step)
    std = np.sqrt(np.einsum("in,nm,im->i", grad, cov, grad)) / d_true
    shape_std = np.sqrt(np.diag(cov)).reshape(6, 12)
    rel_shape = float(np.median(shape_std.max(axis=1) / np.abs(u).max(axis=0)))
    return {"bound: J std worst diag": float(std.max()), "bound: u std rel": rel_shape}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--draws", type=int, default=200)
    parser.add_argument("--bound", action="store_true", help="Also the Cramer-Rao bound with the poles known.")
    parser.add_argument(
        "--pole-noise",
        nargs=2,
        type=float,
        metavar=("FREQUENCY", "DAMPING"),
        help="Relative frequency and damping noise of the Monte Carlo (default: identify's, 0.001 and 0.05).",
    )
    args = parser.parse_args()
    rows = []
    for seed in range(args.trials):
        t0 = time.perf_counter()
        base = None
        if args.pole_noise:
            from rigidid.core.noise import DEFAULT_NOISE

            base = dataclasses.replace(DEFAULT_NOISE, frequency=args.pole_noise[0], damping=args.pole_noise[1])
        r = trial(seed, args.draws, base)
        if args.bound:
            r.update(bound(seed))
        rows.append(r)
        print(f"seed {seed:2d} ({time.perf_counter() - t0:.1f} s): " + ", ".join(f"{k} {v:.4g}" for k, v in r.items()))
        sys.stdout.flush()
    for key in rows[0]:
        vals = np.array([r[key] for r in rows])
        print(f"  {key:22s} median {np.median(vals):.4g}  worst {vals.max():.4g}")


if __name__ == "__main__":
    main()
