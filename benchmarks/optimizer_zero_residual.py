"""The optimiser at zero residual: evaluations, converged flag and |r|^2 at budgets 100/200/400.

Two problems: the decay-plus-cosine fit of tests/core/test_optimize.py from a far start
(exact data), through the refit's wrapper (geodesic acceleration); and the record refit of
samples/four-mounts on noise-free records (128 Hz, 1.5 s, two impacts) from a start 0.2-1 %
off the truth. Before the rounding floor (issue 20) every one of these said converged False
after using its whole budget.

Usage, from the repository root::

    PYTHONPATH=src OPENBLAS_NUM_THREADS=1 python benchmarks/optimizer_zero_residual.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rigidid.api import body_from_file
from rigidid.core.simulate import system_matrices
from rigidid.core.timedomain import impulse_records
from rigidid.core.timedomain.refine import _levenberg_marquardt, refine_body
from rigidid.io.files import layout_arrays, load_body, load_layout

SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "four-mounts"
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]
T = np.linspace(0.0, 4.0, 80)


def _model(p: np.ndarray) -> np.ndarray:
    return np.asarray(p[0] * np.exp(-p[1] * T) + p[2] * np.cos(p[3] * T))


def toy(budget: int) -> tuple[int, bool, float]:
    y = _model(np.array([2.0, 1.3, 0.5, 3.0]))

    def fun(p: np.ndarray) -> np.ndarray:
        return _model(p) - y

    def both(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        e = np.exp(-p[1] * T)
        jm = np.column_stack([e, -p[0] * T * e, np.cos(p[3] * T), -p[2] * T * np.sin(p[3] * T)])
        return fun(p), jm

    _, nfev, r, _, converged = _levenberg_marquardt(fun, both, np.array([1.0, 0.5, 1.0, 2.9]), budget, T.size)
    return nfev, converged, float(r @ r)


def records(budget: int) -> tuple[int, bool, float]:
    body = body_from_file(load_body(SAMPLE / "body.json"))
    _, pos, dirs = layout_arrays(load_layout(SAMPLE / "layout.json"))
    recs = impulse_records(body, pos, dirs, IMPACTS, sample_rate=128.0, duration=1.5, pretrigger=0.4, noise=0.0)
    _, k, c = system_matrices(body)
    j = body.inertia_tensor / body.mass
    ref = refine_body(
        recs, 1.0 / 128.0, pos, dirs, starts=[52, 52], onsets=[51, 51], decimation=1,
        center_of_gravity=body.center_of_gravity + 1e-3, inertia_per_mass=j * 1.002,
        stiffness_per_mass=k / body.mass * 1.002, damping_per_mass=c / body.mass * 1.01, max_evaluations=budget,
    )  # fmt: skip
    return ref.evaluations, ref.converged, float(np.max(np.abs(ref.center_of_gravity - body.center_of_gravity)))


def main() -> None:
    print(f"{'problem':28s} {'budget':>6s} {'evaluations':>11s} {'converged':>9s} {'|r|^2 or CG error':>18s}")
    for budget in (100, 200, 400):
        n, ok, r2 = toy(budget)
        print(f"{'decay + cosine, far start':28s} {budget:6d} {n:11d} {ok!s:>9s} {r2:18.2e}")
    for budget in (100, 200, 400):
        n, ok, err = records(budget)
        print(f"{'four-mounts exact records':28s} {budget:6d} {n:11d} {ok!s:>9s} {err:16.2e} m")


if __name__ == "__main__":
    main()
