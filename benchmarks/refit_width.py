"""Why are the records refit's intervals too wide in the clip30 and aa cells? Monte Carlo per cell (issue 23).

Run from the worktree root::

    PYTHONPATH=src OPENBLAS_NUM_THREADS=1 nice -n 10 python benchmarks/refit_width.py \
        [--cells clip30,clip80,aa,clean] [--draws 40] [--first-draw 0]

Each cell of :mod:`chain_matrix` without sensor errors (clean, clip80, clip30, aa, ac, hum, ...) is
simulated once noise-free (its own scipy matrix-exponential simulator); each draw adds the cell's noise
and chain (``chain_matrix._chain``: the noise, the filters, the clipping), writes the records and runs
``rigidid identify --records`` in process (:func:`rigidid.api.identify_records`, defaults, the layout
stating zero tolerances). A spy keeps the refit's internals. Printed per cell: per figure (CG x, y, z, the
inertia diagonal) the Monte Carlo std of the error over the mean reported std (1 when calibrated), the
mean error over the Monte Carlo std, coverage and RMS z; then what the refit saw: channels fitted, decay
samples per impact at the fit's rate, the fit's decimation, the remaining step's share of the reported
variance, the misfit statistic, and the residual's mean square per impact and channel over the noise level
the pre-trigger gives (1 when the residual is noise only); the coverage and RMS z with the noise std as main
(d98b50e) reported it (widened by the Birge ratio when the misfit test rejected a kept refit) and as the
sandwich gives it; what 20 draws read (20 resampled, the chain matrix's 20 seeds). ``--save``: each cell's
errors and std to an ``.npz`` (the same draw numbers give the same noise in every cell).

Measured (worktree s31-wide23 on main d98b50e; the cells have no sensor errors, their tolerances stated
zero, so the reported std is the noise's alone):

- clip30 and clip80, the same 6 draws: bit-identical answers (largest difference 0.0). Both leave s3 and s8
  out entirely; nothing of the clipped channels reaches the estimate, which is a function of the noise only.
  clip30, 80 draws (``--first-draw 100``): MC std / mean SE 0.91-1.03 per figure, coverage 0.956, RMS z
  0.974; residual over pre-trigger 0.99-1.02 on every impact and channel; the misfit test accepts. The
  chain matrix's clip30 1.00 (RMS z 0.71, seeds 0-19) was its 20 noise draws; seeds 100-119 read clip30
  0.96 and clip80 0.99 (both RMS z 0.92).
- aa on main, 40 draws: MC std / mean SE 0.74-0.92 (coverage 0.967, RMS z 0.835). The residual is
  1.23-1.29 times the pre-trigger's level on every impact and channel: the filtered noise's density in the
  fit's band over the white level the pre-trigger states is 1.251 (computed from the filter and the fit's
  FIR), not a model misfit. The sandwich takes that level from the residual; main then scaled the std by
  the Birge ratio (1.12-1.14, every draw) once more.
- aa with the std the sandwich's, 60 draws (``--first-draw 300``): MC std / mean SE 0.91-1.16 (the
  ratio's 95 % half-width 0.18), coverage 0.942, RMS z 1.029 (main's on the same draws 0.964, 0.920);
  40 more (``--cells clip30,aa --draws 40 --first-draw 400``): 0.983, RMS z 0.906 (main's 0.992, 0.807);
  the 100 pooled: coverage 0.958, RMS z 0.982; none silently wrong. clip30 on draws 400-439: 0.946, RMS z
  1.157 (with draws 100-179: 0.953, RMS z 1.04 over 120).
- What 20 seeds read of a calibrated cell: the figures of a draw move together (the six errors share the
  draw's noise), so 20 draws resampled from clip30's 40 give coverage 0.900-0.983 (5-95 %), above 0.97 in
  16 % of the sets and below 0.9 in 3 %; RMS z 0.97-1.35.
- ac, hum, skew, all (16 draws each): the misfit test rejected a kept refit (main widened it) in 2, 0, 0
  and 0 draws (ac: factor 1.03 at most).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import chain_matrix as cm

_Z95 = 1.959964
NAMES = ["x", "y", "z", "Jxx", "Jyy", "Jzz"]


def cell_effects(cell: str) -> set[str]:
    """The effects of a :mod:`chain_matrix` cell."""
    return set(cm.CELLS[1:-1]) - {"clip30"} if cell == "all" else {cell} - {"clean"}


def clean_acc(effects: set[str], rng: np.random.Generator | None = None) -> tuple[list[np.ndarray], np.ndarray]:
    """The noise-free accelerations before the chain (sensor errors drawn from `rng` when the effects have
    them, else exact sensors), and the time axis."""
    saved = cm._chain
    cm._chain = lambda acc, effects, rng, t: acc  # type: ignore[assignment]
    try:
        rng = rng if rng is not None else np.random.default_rng(7)
        recs = cm.simulate(effects, rng, cm.sensor_errors(effects, rng))
    finally:
        cm._chain = saved
    return recs, np.arange(recs[0].shape[0]) / cm.RATE


class Spy:
    """Keeps the last refinement, its data and the last parameter covariance of a run."""

    def __init__(self) -> None:
        self.seen: dict[str, Any] = {}

    def __enter__(self) -> Spy:
        from rigidid.core.timedomain import intervals
        from rigidid.core.timedomain import refine as rf

        self._saved = (rf.refine_prepared, intervals.parameter_covariance)
        prepared, cov = self._saved

        def prepared_spy(data: Any, *args: Any, **kwargs: Any) -> Any:
            out = prepared(data, *args, **kwargs)
            self.seen["data"], self.seen["refinement"] = data, out
            return out

        def cov_spy(*args: Any, **kwargs: Any) -> Any:
            out = cov(*args, **kwargs)
            self.seen["cov"], self.seen["cov_args"] = out, (args, kwargs)
            return out

        rf.refine_prepared, intervals.parameter_covariance = prepared_spy, cov_spy
        return self

    def __exit__(self, *exc: object) -> None:
        from rigidid.core.timedomain import intervals
        from rigidid.core.timedomain import refine as rf

        rf.refine_prepared, intervals.parameter_covariance = self._saved


def birge(refinement: Any) -> float:
    """The factor main (d98b50e) put on a kept refit's noise std when its misfit test rejected it."""
    from rigidid.core.timedomain.refine import good_fit

    test = refinement.misfit
    if test is None or test.accepted or not good_fit(refinement):
        return 1.0
    return math.sqrt(max(test.ratio, refinement.normalised_cost, 1.0))


def run_draw(cell: str, acc: list[np.ndarray], t: np.ndarray, draw: int) -> dict[str, Any]:
    """One draw of `cell`: records through its chain, identified in process."""
    from rigidid.api import identify_records

    effects = cell_effects(cell)
    rng = np.random.default_rng(5000 + draw)
    if effects & cm.SENSOR_EFFECTS:  # the sensors' errors drawn anew each draw
        acc, t = clean_acc(effects, rng)
    recs = [cm._chain(a.copy(), effects, rng, t) for a in acc]
    row: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        paths = cm.write_case(folder, recs, "stamps" in effects, cm.stated_tolerances(effects))
        with Spy() as spy, warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            run = identify_records(folder / "layout.json", paths, mass=cm.MASS)
        row["warnings"] = [str(w.message)[:90] for w in caught]
    res = run.result
    rb = res.record_bound
    if rb is None:
        row["refit"] = False
        return row
    row["refit"] = True
    est = np.concatenate([rb.center_of_gravity.estimate, np.diag(rb.inertia.estimate)])
    sd = np.concatenate([rb.center_of_gravity.std, np.diag(rb.inertia.std)])
    row["err"], row["sd"] = est - np.concatenate([cm.CG, np.diag(cm.INERTIA)]), sd
    data, ref, cov = spy.seen["data"], spy.seen["refinement"], spy.seen["cov"]
    row["widen"] = birge(ref)
    sandwich = np.concatenate([ref.std["center_of_gravity"], cm.MASS * np.diag(ref.std["inertia_per_mass"])])
    if rb.sensor_budget is not None:  # the noise part as reported and the type-B rest
        noise = np.concatenate([rb.sensor_budget["noise"]["center_of_gravity"],
                                np.diag(rb.sensor_budget["noise"]["inertia_per_mass"])])  # fmt: skip
    else:
        noise = sd
    rest = np.maximum(sd**2 - noise**2, 0.0)
    row["noise_sd"] = sandwich
    row["sd_fixed"] = np.sqrt(rest + sandwich**2)  # the noise std the sandwich's, as this branch reports
    row["sd_main"] = np.sqrt(rest + (row["widen"] * sandwich) ** 2)  # widened by the Birge ratio, as main did
    row["channels"] = data.sigma.size
    row["lengths"] = [d.shape[0] for d in data.decays]
    row["dt"] = data.dt
    row["noise_from"] = data.noise_from
    row["misfit"] = None if ref.misfit is None else ref.misfit
    row["decrement"] = cov.decrement
    mat = cov.matrix
    row["step_share"] = float(
        np.max(np.diag(np.outer(cov.step, cov.step))[:51] / np.maximum(np.diag(mat)[:51], 1e-300))
    )
    args, _ = spy.seen["cov_args"]
    r, lengths, channels = args[1], args[2], args[3]
    ratios, first = [], 0
    for n in lengths:
        res_i = r[first * channels : (first + n) * channels].reshape(n, channels)
        first += n
        ratios.append(np.mean(res_i**2, axis=0))
    row["v"] = np.array(ratios)  # mean square of the weighted residual per impact and channel (1: the weight's)
    if data.pre_m2 is not None:
        from rigidid.core.timedomain.preprocess import fir_taps

        q = max(1, round(data.dt * cm.RATE))
        gain = float(np.sum(fir_taps(q) ** 2)) if q > 1 else 1.0
        counts = np.asarray(data.pre_counts, float)
        pre = data.pre_m2 / np.maximum(counts - 1, 1)[:, None] * gain / data.sigma[None, :] ** 2
        row["v_pre"] = row["v"] / pre
    return row


def summary(cell: str, rows: list[dict[str, Any]]) -> None:
    fitted = [r for r in rows if r.get("refit")]
    print(f"{cell}: {len(fitted)}/{len(rows)} refitted")
    if len(fitted) < 2:
        return
    e, s = np.array([r["err"] for r in fitted]), np.array([r["sd"] for r in fitted])
    z = e / s
    for i, name in enumerate(NAMES):
        mc = e[:, i].std(ddof=1)
        print(f"  {name:<4} MC std / mean SE {mc / s[:, i].mean():.3f}  bias/MC {e[:, i].mean() / mc:+.3f}  "
              f"cover {np.mean(np.abs(z[:, i]) <= _Z95):.3f}  RMS z {np.sqrt(np.mean(z[:, i] ** 2)):.3f}")  # fmt: skip
    z_fix = e / np.array([r["sd_fixed"] for r in fitted])
    z_main = e / np.array([r["sd_main"] for r in fitted])
    w = np.array([r["widen"] for r in fitted])
    share = np.array([np.median(r["noise_sd"] ** 2 / r["sd_fixed"] ** 2) for r in fitted])
    quiet = np.array([not r["warnings"] for r in fitted])
    print(
        f"  noise share of the variance: median {np.median(share):.2f}; misfit rejected, refit kept (main widened "
        f"by the Birge ratio) in {np.sum(w > 1)} draws (median factor {np.median(w):.3f}, max {w.max():.3f})"
    )
    for name, z in (("main (Birge)", z_main), ("sandwich only", z_fix)):
        silent = int(np.sum((np.max(np.abs(z), axis=1) > 4) & quiet))
        print(f"  {name:<13}: cover {np.mean(np.abs(z) <= _Z95):.3f}, RMS z {np.sqrt(np.mean(z**2)):.3f}, "
              f"silently wrong {silent}")  # fmt: skip
    if len(fitted) > 20:  # what 20 seeds of this estimator read: 20 of the draws resampled
        pick = np.random.default_rng(0).integers(0, len(fitted), (4000, 20))
        cover = np.mean(np.abs(z_fix[pick]) <= _Z95, axis=(1, 2))
        rms = np.sqrt(np.mean(z_fix[pick] ** 2, axis=(1, 2)))
        print(f"  20 draws resampled (sandwich only): cover 5-95 % {np.quantile(cover, 0.05):.3f}-"
              f"{np.quantile(cover, 0.95):.3f}, above 0.97 in {np.mean(cover > 0.97):.2f}, below 0.9 in "
              f"{np.mean(cover < 0.9):.2f}; RMS z 5-95 % {np.quantile(rms, 0.05):.2f}-"
              f"{np.quantile(rms, 0.95):.2f}")  # fmt: skip
    half = _Z95 / math.sqrt(2.0 * (len(fitted) - 1))
    print(f"  all six: cover {np.mean(np.abs(z) <= _Z95):.3f}, RMS z {np.sqrt(np.mean(z**2)):.3f} "
          f"(a ratio's 95 % half-width {half:.2f})")  # fmt: skip
    r0 = fitted[0]
    print(f"  channels {r0['channels']}, decay samples {r0['lengths']}, fit dt {r0['dt'] * 1e3:.3f} ms, "
          f"noise from {r0['noise_from']}")  # fmt: skip
    share = np.array([r["step_share"] for r in fitted])
    dec = np.array([r["decrement"] for r in fitted])
    print(f"  remaining step's share of the variance: median {np.median(share):.3f} max {share.max():.3f}; "
          f"decrement median {np.median(dec):.2f}")  # fmt: skip
    v = np.array([r["v"] for r in fitted])
    print("  residual mean square / weight^2, per impact (rows) and channel, mean over draws:")
    for row in v.mean(axis=0):
        print("    " + " ".join(f"{x:5.2f}" for x in row))
    if "v_pre" in r0:
        vp = np.array([r["v_pre"] for r in fitted])
        print("  residual mean square / its impact's pre-trigger variance, mean over draws:")
        for row in vp.mean(axis=0):
            print("    " + " ".join(f"{x:5.2f}" for x in row))
    mis = [r["misfit"] for r in fitted if r["misfit"] is not None]
    if mis:
        print(f"  misfit: {mis[0]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", default="clip30,clip80,aa,clean")
    parser.add_argument("--draws", type=int, default=40)
    parser.add_argument("--first-draw", type=int, default=0)
    parser.add_argument("--save", default="", help="save each cell's errors to SAVE_cell.npy (paired draws)")
    args = parser.parse_args()
    cm.STATED_DRAWS = True
    for cell in args.cells.split(","):
        acc, t = clean_acc(cell_effects(cell))
        rows = [run_draw(cell, acc, t, d) for d in range(args.first_draw, args.first_draw + args.draws)]
        summary(cell, rows)
        if args.save:
            fitted = [r for r in rows if r.get("refit")]
            np.savez(
                f"{args.save}_{cell}.npz",
                err=np.array([r["err"] for r in fitted]),
                sd=np.array([r["sd"] for r in fitted]),
                sd_fixed=np.array([r["sd_fixed"] for r in fitted]),
                sd_main=np.array([r["sd_main"] for r in fitted]),
                widen=np.array([r["widen"] for r in fitted]),
                warned=np.array([bool(r["warnings"]) for r in fitted]),
            )


if __name__ == "__main__":
    main()
