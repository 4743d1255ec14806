"""Modal estimates across sample rates: the factor chosen, frequency and damping errors, time (not a test).

The four-mounts sample body (modes 8.0-26.1 Hz, damping 0.3-6.9 %), 8 sensors, two impacts,
8 s records with 0.1 s pre-trigger and 1 % noise, sampled at rates from 256 Hz (10 times the
highest mode) to 51.2 kHz (2000 times), ``--seeds`` noise draws per rate. For each rate it prints
the decimation factor ``estimate_modes`` chose (median over seeds), the median and worst relative
frequency error and damping-ratio error of the six modes over all seeds, the worst shape MAC
against the true shapes, and the median time of one estimation. Run it with ``PYTHONPATH``
pointing at two versions of the package to compare them on the same draws.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/decimation_accuracy.py --seeds 10``
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from rigidid.api import body_from_file
from rigidid.core.simulate import body_modes
from rigidid.core.statespace import mac_matrix, modal_from_poles
from rigidid.core.timedomain import estimate_modes, impulse_records
from rigidid.io.files import layout_arrays, load_body, load_layout

SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "four-mounts"
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]
RATES = (256.0, 1024.0, 4096.0, 12_800.0, 51_200.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--duration", type=float, default=8.0)
    args = parser.parse_args()
    body = body_from_file(load_body(SAMPLE / "body.json"))
    _, pos, dirs = layout_arrays(load_layout(SAMPLE / "layout.json"))
    true = body_modes(body, pos, dirs)
    f_true, z_true = modal_from_poles(true.poles)
    print("| rate Hz | factor | frequency error median / worst | damping error median / worst | worst MAC | s |")
    print("|---|---|---|---|---|---|")
    for rate in RATES:
        factors, f_err, z_err, macs, times = [], [], [], [], []
        for seed in range(args.seeds):
            recs = impulse_records(body, pos, dirs, IMPACTS, sample_rate=rate, duration=args.duration,
                                   pretrigger=0.1, noise=0.01, seed=seed)  # fmt: skip
            start = time.perf_counter()
            est = estimate_modes(recs, 1.0 / rate)
            times.append(time.perf_counter() - start)
            factors.append(est.decimation)
            f_err.extend(np.abs(est.frequency_hz / f_true - 1.0))
            z_err.extend(np.abs(est.damping_ratio / z_true - 1.0))
            macs.append(float(np.min(np.diag(mac_matrix(est.shapes, true.shapes)))))
        print(f"| {rate:g} | {np.median(factors):g} | {100 * np.median(f_err):.4f} / {100 * np.max(f_err):.4f} % "
              f"| {100 * np.median(z_err):.2f} / {100 * np.max(z_err):.2f} % | {min(macs):.5f} "
              f"| {np.median(times):.3f} |")  # fmt: skip


if __name__ == "__main__":
    main()
