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
  * ``written``: what modes.csv now carries (FrfModes.shapes), the projected (scaled) shapes plus
    the part of the raw shapes that is not rigid-body motion (core.frfmodes.with_nonrigid_residual):
    eq. (18) and the scaled-mode mass as ``projected``, the shape noise visible to identify();
and identify()'s Monte Carlo standard error (core.uncertainty.propagate, the noise levels
identify --uncertainty would use) is compared with the actual error: ``z`` = error / std of
the worst inertia diagonal term. Printed per trial, then worst / median.
"""

from __future__ import annotations

import argparse
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


def trial(seed: int, draws: int) -> dict[str, float]:
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
        levels = estimate_noise(pos, dirs, shapes)
        unc = propagate(pos, dirs, lam, shapes, mass=body.mass, noise=levels, draws=draws, seed=seed)
        std = np.diag(unc.inertia.std) / d_true
        worst = int(np.argmax(np.abs(err)))
        out[f"{name}: J err"] = float(abs(err[worst]))
        out[f"{name}: J std"] = float(std[worst])
        out[f"{name}: z"] = float(abs(err[worst]) / std[worst])
        out[f"{name}: shape noise"] = float(levels.shape)
        out[f"{name}: z max"] = float(np.max(np.abs(err) / std))
        out["observability"] = float(ident.diagnostics.inertia_observability)
    sb = body_from_scaled_modes(lam, fitted.residues[:6], pos, dirs, rpos, np.eye(3))
    out["scaled: J err"] = float(np.max(np.abs(np.diag(sb.inertia_tensor) / d_true - 1.0)))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--draws", type=int, default=200)
    args = parser.parse_args()
    rows = []
    for seed in range(args.trials):
        t0 = time.perf_counter()
        r = trial(seed, args.draws)
        rows.append(r)
        print(f"seed {seed:2d} ({time.perf_counter() - t0:.1f} s): " + ", ".join(f"{k} {v:.4g}" for k, v in r.items()))
        sys.stdout.flush()
    for key in rows[0]:
        vals = np.array([r[key] for r in rows])
        print(f"  {key:22s} median {np.median(vals):.4g}  worst {vals.max():.4g}")


if __name__ == "__main__":
    main()
