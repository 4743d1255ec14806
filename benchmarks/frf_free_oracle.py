"""The free-free mass line's intervals against the true noise's, on the same draws (issue 21).

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src .venv/bin/python benchmarks/frf_free_oracle.py
[--draws 1000] [--first-seed 0] [--fresh 0]``

The draws are benchmarks/frf_coverage.py's ``free`` regime (seed ``s``: its body and its noise), answered by
``mass_line`` with its automatic mount model (the first-order mass line, where the supports are not seen).
The simulator (benchmarks/frf_sim.py) knows each FRF's noise: complex, circular, standard deviation
``0.005 |H| + 0.005 RMS(H)``. The first-order mass line's constants are linear in the FRFs, so their true
covariance is that noise propagated exactly (``sum_l a_l^2 T^+ diag(sigma_l^2 / 2) T^+T`` per reference), and
the true standard error of mass, CG and inertia is its delta-method image with the Jacobian at the noise-free
constants. Per figure (mass, CG x, y, z, inertia diagonal) this prints the coverage of ``+-1.96`` SE with the
reported SE and with the true SE, on the same draws, their mean and RMS ``z``, the draws beyond 4 SE, and the
reported SE over the true one (mean and coefficient of variation). The true SE's coverage is what any honest
interval can reach on these draws: where it falls short of 0.95 the draws, not the interval, are the cause.
``--fresh R`` also draws ``R`` new noise vectors per body straight from that covariance (the linearised ``z``,
exactly normal): the coverage the true SE has over many more draws.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from frf_coverage import binomial
from frf_sim import add_elastic, make_rig
from rigidid.core.frfmodes import scaled_frame
from rigidid.core.geometry import sensor_matrix
from rigidid.core.massline import _body_from_inverse_mass, _correction_design, mass_line

Z95 = 1.959963984540054
NAMES = ("mass", "CG x", "CG y", "CG z", "Jxx", "Jyy", "Jzz")
BAND = (30.0, 150.0)


def figures(m: float, cg: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """The seven figures."""
    return np.r_[m, cg, np.diag(inertia)]


def one_draw(seed: int, fresh: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, str]:
    """Error, reported SE and true SE of the seven figures on draw `seed`, `fresh` linearised z, the mount model."""
    rng = np.random.default_rng(seed)
    rig = make_rig(rng, free=True)
    add_elastic(rig, rng, 1500.0)
    f = np.arange(20.0, 200.0, 1.0)
    h = rig.frf(f, 0.005, rng, additive=0.005)
    h0 = rig.frf(f)
    sigma = 0.005 * np.abs(h0) + 0.005 * np.sqrt(np.mean(np.abs(h0) ** 2, axis=2, keepdims=True))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = mass_line(f, h, rig.sensors, rig.sensor_dirs, rig.refs, rig.ref_dirs, band=BAND)
    assert r.intervals is not None
    iv = r.intervals
    truth = figures(rig.mass, rig.cg, rig.inertia)
    error = figures(r.mass, r.center_of_gravity, r.inertia_tensor) - truth
    se = figures(iv.mass.std, iv.center_of_gravity.std, iv.inertia_tensor.std)
    # the true covariance of the constants y0 (6, q), flattened row-major, and its image
    sel = (f >= BAND[0]) & (f <= BAND[1])
    q = rig.refs.shape[0]
    origin, span, t = scaled_frame(rig.sensors, rig.sensor_dirs)
    tf = sensor_matrix((rig.refs - origin) / span, rig.ref_dirs)
    design = _correction_design(2.0 * np.pi * f[sel], ("stiffness", "damping", "upper_residual"), None)
    a = np.linalg.pinv(design)[0][: int(sel.sum())]  # the constant's weights on the real parts
    tp = np.linalg.pinv(t)
    y0 = np.tensordot(np.einsum("ip,pjl->ijl", tp, h0[:, :, sel]).real, a, axes=([2], [0])).reshape(-1)
    half_var = sigma[:, :, sel] ** 2 / 2.0  # (p, q, lines): variance of each real part
    cov = np.zeros((6 * q, 6 * q))
    for j in range(q):
        idx = np.arange(6) * q + j
        cov[np.ix_(idx, idx)] = np.einsum("l,ip,pl,kp->ik", a**2, tp, half_var[:, j, :], tp)

    def vec(v: np.ndarray) -> np.ndarray:
        return figures(*_body_from_inverse_mass(v.reshape(6, q), tf, origin, span))

    step = 1e-6 * float(np.max(np.abs(y0)))
    jac = np.stack([(vec(y0 + step * e) - vec(y0 - step * e)) / (2.0 * step) for e in np.eye(y0.size)], axis=1)
    true_se = np.sqrt(np.einsum("ik,kl,il->i", jac, cov, jac))
    g = np.random.default_rng(1_000_000 + seed)
    dy = np.einsum("l,ip,rpjl->rij", a, tp, g.standard_normal((fresh, *half_var.shape)) * np.sqrt(half_var)[None])
    return error, se, true_se, (dy.reshape(fresh, y0.size) @ jac.T) / true_se, r.supports


def report(label: str, z: np.ndarray) -> None:
    """Coverage, mean and RMS z per figure, pooled coverage and the draws beyond 4."""
    za = np.abs(z)
    print(
        f"{label}: coverage "
        + ", ".join(f"{n} {binomial(float(c), len(z))}" for n, c in zip(NAMES, np.mean(za < Z95, axis=0), strict=True))
    )
    print(
        "    mean z / RMS z: "
        + ", ".join(
            f"{n} {m:+.2f}/{r:.2f}"
            for n, m, r in zip(NAMES, z.mean(axis=0), np.sqrt(np.mean(z**2, axis=0)), strict=True)
        )
    )
    print(
        f"    pooled {binomial(float(np.mean(za < Z95)), len(z))}, RMS z {float(np.sqrt(np.mean(z**2))):.3f}; "
        f"draws beyond 4 SE: {int(np.count_nonzero(za.max(axis=1) > 4.0))} (worst {float(za.max()):.2f})"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--fresh", type=int, default=0, help="new noise vectors per body for the linearised z")
    a = ap.parse_args()
    seeds = range(a.first_seed, a.first_seed + a.draws)
    out = [one_draw(s, a.fresh) for s in seeds]
    error = np.array([o[0] for o in out])
    se, true_se = np.array([o[1] for o in out]), np.array([o[2] for o in out])
    models = [o[4] for o in out]
    print(
        f"free-free, seeds {seeds[0]}-{seeds[-1]}: mount model "
        + ", ".join(f"{m} {models.count(m)}" for m in sorted(set(models)))
    )
    report("reported SE", error / se)
    report("true SE    ", error / true_se)
    ratio = se / true_se
    print(
        "reported SE / true SE: mean "
        + " ".join(f"{v:.3f}" for v in ratio.mean(axis=0))
        + ", cv "
        + " ".join(f"{v:.3f}" for v in ratio.std(axis=0) / ratio.mean(axis=0))
    )
    worst = np.argsort(-np.max(np.abs(error / se), axis=1))[:3]
    for k in worst:
        print(
            f"    seed {seeds[k]}: z {np.round(error[k] / se[k], 2)}, "
            f"with the true SE {np.round(error[k] / true_se[k], 2)}"
        )
    if a.fresh:
        report(
            f"linearised z, {a.fresh} fresh noise draws per body (exactly normal)", np.concatenate([o[3] for o in out])
        )


if __name__ == "__main__":
    main()
