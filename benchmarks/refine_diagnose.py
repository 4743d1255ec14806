"""Diagnose the record refit's convergence (issue 11): start at the truth and at the structured
answer, print the cost trace, the final normalised cost, evaluations and errors.

Run: ``python benchmarks/refine_diagnose.py [--seeds 0 1 2] [--noise 0.05] [--budget 240] [--impacts 1]
[--golub-pereyra]``
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import rigidid.core.timedomain.refine as rf
from records_scenario import BODY, CG, IMPACTS, INERTIA, MASS, layout
from rigidid.core.identify import identify
from rigidid.core.simulate import system_matrices
from rigidid.core.timedomain import estimate_modes, impulse_records

TRACE: list[float] = []
_orig = rf._evaluate


def _traced(theta, data, pos, dirs, omega, jac):  # type: ignore[no-untyped-def]
    r, j = _orig(theta, data, pos, dirs, omega, jac)
    TRACE.append(float(r @ r))
    return r, j


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    p.add_argument("--noise", type=float, default=0.05)
    p.add_argument("--budget", type=int, default=240)
    p.add_argument("--duration", type=float, default=8.0)
    p.add_argument("--impacts", type=int, default=2)
    p.add_argument("--golub-pereyra", action="store_true", help="the full variable-projection Jacobian")
    a = p.parse_args()
    rf._GOLUB_PEREYRA = a.golub_pereyra
    warnings.simplefilter("ignore")
    rf._evaluate = _traced
    pos, dirs = layout(8)
    span = float(np.max(np.ptp(pos, axis=0)))
    jd = np.diag(INERTIA)
    _, k, c = system_matrices(BODY)
    for seed in a.seeds:
        recs = impulse_records(BODY, pos, dirs, IMPACTS[: a.impacts], sample_rate=512.0, duration=a.duration,
                               pretrigger=0.1, noise=a.noise, seed=seed)  # fmt: skip
        est = estimate_modes(recs, 1 / 512.0)
        ident = identify(pos, dirs, est.poles, est.shapes, mass=BODY.mass)
        common = dict(starts=[i.start for i in est.impacts], onsets=[i.onset for i in est.impacts],
                      decimation=est.decimation)  # fmt: skip
        starts = {"truth": (BODY.center_of_gravity, BODY.inertia_tensor / MASS, k / MASS, c / MASS),
                  "structured": (ident.center_of_gravity, ident.inertia_per_mass, ident.stiffness_per_mass,
                                 ident.damping_per_mass)}  # fmt: skip
        for name, (g, j, kk, cc) in starts.items():
            TRACE.clear()
            t0 = time.perf_counter()
            ref = rf.refine_body(recs, 1 / 512.0, pos, dirs, center_of_gravity=g, inertia_per_mass=j,
                                 stiffness_per_mass=kk, damping_per_mass=cc, max_evaluations=a.budget,
                                 **common)  # fmt: skip
            el = time.perf_counter() - t0
            n = ref.residuals
            tr = np.array(TRACE) * 2 / n
            best = np.minimum.accumulate(tr)
            idx = [0, 5, 10, 20, 30, 45, len(best) - 1]
            cg = 100 * np.linalg.norm(ref.center_of_gravity - CG) / span
            je = 100 * np.max(np.abs(np.diag(ref.inertia_per_mass) * MASS / jd - 1))
            print(f"seed {seed} {name:10s}: ncost {ref.normalised_cost:.5f} evals {ref.evaluations} "
                  f"converged {ref.converged} CG {cg:.4f} % J {je:.3f} % {el:.1f}s trace "
                  + " ".join(f"{i}:{best[min(i, len(best) - 1)]:.5f}" for i in idx), flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
