"""Is an FRF route's standard error the spread of its estimate? One body, many noise draws (issue 21).

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src .venv/bin/python benchmarks/frf_se_check.py
[--regime free|mounted|near] [--supports auto|exact|first_order] [--bodies 0:3] [--draws 60]``

The coverage of benchmarks/frf_coverage.py draws a new body every draw, so an interval that is too narrow
cannot be told from a biased estimate or from a few bodies where the linearisation fails. Here the body
is fixed (``frf_coverage``'s regimes: body ``b`` is draw ``b``'s, its noise drawn anew from seed
``10000 + draw``; ``near`` has one body, femtools' case 15) and per figure (mass, CG x, y, z, inertia
diagonal xx, yy, zz) this prints:

* ``spread/SE``: the standard deviation of the estimate over the draws over the mean reported SE (1 when
  the SE is the spread; its own relative SE is about ``1 / sqrt(2 draws)``);
* ``bias/SE``: the mean error over the mean SE (its SE about ``1 / sqrt(draws)``);
* ``RMS z``: of the error over each draw's own SE;
* ``SE cv``: how much the SE itself varies between draws (a linear fit's varies by a few %).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from femtools_compare import femtools_case
from frf_sim import add_elastic, make_rig
from rigidid.core.massline import mass_line

NAMES = ("mass", "CG x", "CG y", "CG z", "Jxx", "Jyy", "Jzz")


def draw(regime: str, body: int, seed: int) -> tuple[np.ndarray, tuple[Any, ...], tuple[float, float]]:
    """The truth (7 figures), the data and the band of body `body` with noise `seed`."""
    if regime == "near":
        c = femtools_case(2)
        rng = np.random.default_rng(seed)
        e = (rng.standard_normal(c["h"].shape) + 1j * rng.standard_normal(c["h"].shape)) / np.sqrt(2)
        b = c["body"]
        truth = np.r_[b.mass, b.center_of_gravity, np.diag(b.inertia_tensor)]
        return truth, (c["f"], c["h"] * (1.0 + 0.01 * e), c["pos"], c["dirs"], c["rpos"], c["rdirs"]), (6.0, 15.0)
    rng = np.random.default_rng(body)
    rig = make_rig(rng, free=regime == "free")
    if regime == "free":
        add_elastic(rig, rng, 1500.0)
        f, band = np.arange(20.0, 200.0, 1.0), (30.0, 150.0)
    else:
        top = float(rig.rigid_hz()[-1])
        f, band = np.arange(1.4 * top, 6.5 * top, 0.1), (1.5 * top, 6.0 * top)
    h = rig.frf(f, 0.005, np.random.default_rng(10_000 + seed), additive=0.005)
    truth = np.r_[rig.mass, rig.cg, np.diag(rig.inertia)]
    return truth, (f, h, rig.sensors, rig.sensor_dirs, rig.refs, rig.ref_dirs), band


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--regime", default="free")
    ap.add_argument("--supports", default="auto")
    ap.add_argument("--bodies", default="0:3")
    ap.add_argument("--draws", type=int, default=60)
    a = ap.parse_args()
    lo, hi = (int(v) for v in a.bodies.split(":"))
    print(f"{a.regime}, supports={a.supports}, {a.draws} noise draws per body; per figure: " + ", ".join(NAMES))
    for body in range(lo, hi if a.regime != "near" else lo + 1):
        est, se, models = [], [], set()
        truth = np.zeros(7)
        for seed in range(a.draws):
            truth, data, band = draw(a.regime, body, seed)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = mass_line(*data, band=band, supports=a.supports)
            iv = r.intervals
            assert iv is not None
            models.add(r.supports)
            est.append(np.r_[r.mass, r.center_of_gravity, np.diag(r.inertia_tensor)])
            se.append(np.r_[iv.mass.std, iv.center_of_gravity.std, np.diag(iv.inertia_tensor.std)])
        e, s = np.array(est), np.array(se)
        z = (e - truth) / s
        print(f"body {body} ({'/'.join(sorted(models))}):")
        for label, row in (
            ("spread/SE", e.std(axis=0, ddof=1) / s.mean(axis=0)),
            ("bias/SE", (e.mean(axis=0) - truth) / s.mean(axis=0)),
            ("RMS z", np.sqrt(np.mean(z**2, axis=0))),
            ("SE cv", s.std(axis=0) / s.mean(axis=0)),
        ):
            print(f"  {label:9s} " + " ".join(f"{v:+6.2f}" for v in row), flush=True)


if __name__ == "__main__":
    main()
