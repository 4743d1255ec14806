"""False-alarm rate of the refit's acceptance test on clean simulations (issue 23, item 3).

Run from the worktree root (a few seconds a draw; a minute or more with ``--evaluations 240``)::

    PYTHONPATH=src nice -n 10 python benchmarks/refit_acceptance.py [--draws 100] [--noise 0.01] [--evaluations 0]
        [--effects aa,hum]

Records from the chain matrix's own simulator (``benchmarks/chain_matrix.py``: zero-order-hold
state transition from scipy.linalg.expm, half-sine hammer; 150 kg on four inclined mounts, ten
accelerometers, three impacts, 2048 Hz, 6 s, 0.25 s pre-trigger, white noise of 1 % of each
channel's RMS), no chain effect: the refit's model is right. The refit
(:func:`rigidid.core.timedomain.refine.refine_body`, started at the truth; by default evaluated there
only, ``--evaluations 240`` fits as the records route does) is tested against each impact's pre-trigger
(:func:`rigidid.core.timedomain.acceptance.misfit_test`). Printed: the fraction of draws the test
rejects (the false-alarm rate, stated 0.01) with its binomial standard error, the p-values'
deciles (uniform when the test is calibrated), the misfit ratio's median and range, and how
often the old rule (normalised cost below 2) and the test disagree.

``--effects`` adds chain effects that leave the model right (the chain matrix's ``aa``: an anti-alias
filter, a delay common to every channel and the noise coloured; ``hum``: mains hum, which the refit
models): the test's rate must hold with them too (the pre-trigger's noise measured in the fit's band with
the hum out, :mod:`rigidid.core.timedomain.pretrigger`).
"""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path

import numpy as np


def _chain_matrix():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("chain_matrix", Path(__file__).with_name("chain_matrix.py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=100)
    parser.add_argument("--noise", type=float, default=0.01)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--effects", default="", help="chain matrix effects, comma-separated (aa, hum)")
    parser.add_argument(
        "--evaluations", type=int, default=0,
        help="the refit's evaluation budget (0: the test at the truth; the fit's minimum lowers the residual by "
        "about 51 of its 1.5e5 degrees of freedom, 0.03 of the test's standard deviation)",
    )  # fmt: skip
    args = parser.parse_args()
    from rigidid.core.timedomain.preprocess import find_impact
    from rigidid.core.timedomain.refine import refine_body

    cm = _chain_matrix()
    cm.NOISE = args.noise
    k6, c6 = cm.K6, cm.C6
    # at the CG, per mass: the body's K and C over the mass (translations) as the refit parameterises them
    km, cmass = k6 / cm.MASS, c6 / cm.MASS
    p_values, ratios, costs = [], [], []
    rng = np.random.default_rng(args.seed)
    effects = {e for e in args.effects.split(",") if e}
    for draw in range(args.draws):
        sensors = cm.sensor_errors(effects, rng)
        records = cm.simulate(effects, rng, sensors)
        dt = 1.0 / cm.RATE
        impacts = [find_impact(r, dt) for r in records]
        fit = refine_body(
            records, dt, cm.SENSORS, cm.AXES, starts=[i.start for i in impacts], onsets=[i.onset for i in impacts],
            decimation=8, center_of_gravity=cm.CG, inertia_per_mass=cm.INERTIA / cm.MASS,
            stiffness_per_mass=km, damping_per_mass=cmass, max_evaluations=args.evaluations,
        )  # fmt: skip
        assert fit.misfit is not None
        p_values.append(fit.misfit.p_value)
        ratios.append(fit.misfit.ratio)
        costs.append(fit.normalised_cost)
        if (draw + 1) % 10 == 0:
            print(f"  {draw + 1} draws: rejected {np.mean(np.array(p_values) < 0.01):.3f}", flush=True)
    p = np.array(p_values)
    rate = float(np.mean(p < 0.01))
    se = float(np.sqrt(max(rate * (1 - rate), 0.01 * 0.99) / p.size))
    print(f"{p.size} draws ({args.effects or 'clean'}), noise {args.noise:g} of RMS: "
          f"false-alarm rate {rate:.3f} +- {se:.3f} (stated 0.01)")  # fmt: skip
    print("p-value deciles: " + " ".join(f"{q:.2f}" for q in np.quantile(p, np.linspace(0.1, 0.9, 9))))
    old = float(np.mean(np.array(costs) >= 2))
    print(f"misfit ratio median {np.median(ratios):.4f} (range {np.min(ratios):.4f}-{np.max(ratios):.4f}); "
          f"normalised cost median {np.median(costs):.4f}; old rule (cost < 2) rejects {old:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
