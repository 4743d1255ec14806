"""The sensors' correction's after-check: its null and its power (issue 23).

Run from the worktree root (about 10 s a run)::

    PYTHONPATH=src OPENBLAS_NUM_THREADS=1 nice -n 10 python benchmarks/after_check.py [--seeds 15] [--first-seed 500]
        [--skew-seeds 8]

The records are benchmarks/chain_matrix.py's (its simulator: a scipy matrix exponential, no rigidid code).

- **Null**: the sens, orient and transverse cells, the errors drawn from the stated tolerances (``--stated``),
  the sensors estimated (``--estimate-sensors``): the corrected refit's ``correction_misfit_p_value`` should be
  uniform. Printed per cell and pooled: runs, the KS test's p against the uniform, the mean p-value, the counts
  below 0.05, 0.01 and the after-check's rate (``correction_false_alarm_rate``), the smallest.
- **Power**: the skew cell (one channel one sample late, unmodelled) with every tolerance stated
  (``--state-all-tolerances``) and defaults: the sensor test flags, the gains and tilts absorb the skew, and the
  after-check must find the corrected residual unexplained (the plain refit then kept). Printed: runs whose
  correction was dropped, the largest ``correction_misfit_p_value``, the largest CG and J errors of the answers.
"""

from __future__ import annotations

import argparse

import numpy as np

import chain_matrix as cm


def _null(cells: list[str], seeds: range) -> None:
    pooled: list[float] = []
    rate = float("nan")
    for cell in cells:
        p = []
        for seed in seeds:
            row = cm.run_cell(cell, seed, options=("--estimate-sensors",))
            test = row.get("sensor_test") or {}
            if test.get("correction_misfit_p_value") is not None:
                p.append(float(test["correction_misfit_p_value"]))  # type: ignore[index]
                rate = float(test.get("correction_false_alarm_rate") or rate)  # type: ignore[union-attr]
        pooled += p
        _print(cell, np.array(p), rate)
    _print("pooled", np.array(pooled), rate)


def _print(name: str, p: np.ndarray, rate: float) -> None:
    from scipy.stats import kstest

    if p.size == 0:
        print(f"{name:<11} no corrected runs")
        return
    print(f"{name:<11} {p.size:>4} {kstest(p, 'uniform').pvalue:>7.3f} {np.mean(p):>6.3f} {np.sum(p < 0.05):>5} "
          f"{np.sum(p < 0.01):>5} {np.sum(p < rate):>6} {np.min(p):>8.4f}", flush=True)  # fmt: skip


def _power(seeds: range) -> None:
    cm.ALL_TOLERANCES = True
    dropped, worst_p, errs = 0, 0.0, []
    for seed in seeds:
        row = cm.run_cell("skew", seed)
        test = row.get("sensor_test") or {}
        after = test.get("correction_misfit_p_value")
        if after is not None and not test.get("sensors_estimated"):
            dropped += 1
        worst_p = max(worst_p, float(after) if after is not None else 1.0)  # type: ignore[arg-type]
        errs.append(row.get("errors", (np.nan, np.nan)))
    cm.ALL_TOLERANCES = False
    e = np.max(np.array(errs, dtype=float), axis=0)
    print(f"skew (every tolerance stated, defaults): {len(seeds)} runs, correction dropped {dropped}, largest "
          f"after-check p {worst_p:.3g}, worst CG {e[0]:.3f} % of span, J {e[1]:.2f} %")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=15, help="seeds per null cell")
    parser.add_argument("--first-seed", type=int, default=500)
    parser.add_argument("--skew-seeds", type=int, default=8)
    parser.add_argument("--cells", default="sens,orient,transverse")
    args = parser.parse_args()
    cm.STATED_DRAWS = True
    print(f"{'null':<11} {'runs':>4} {'KS p':>7} {'mean':>6} {'<0.05':>5} {'<0.01':>5} {'<rate':>6} {'min p':>8}")
    _null(args.cells.split(","), range(args.first_seed, args.first_seed + args.seeds))
    if args.skew_seeds:
        _power(range(args.first_seed, args.first_seed + args.skew_seeds))


if __name__ == "__main__":
    main()
