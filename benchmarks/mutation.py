"""Mutation run: plausible bugs planted one at a time in a copy of the source; does the suite notice?

Each mutant names a file under ``src/rigidid``, an exact snippet of its text (found exactly
once, or the run stops: the code moved and the list must follow), its replacement, why the
bug is plausible, and the test files that guard it. For each mutant the source tree is copied
to a temporary directory, the snippet replaced there, and pytest run on the guarding test
files with that copy first on ``PYTHONPATH`` (subprocess tests inherit it); the working tree
is never touched. A mutant is *caught* when pytest fails (exit 1), *survived* when it passes;
any other pytest exit (collection error, no tests) stops the run.

Usage, from the repository root::

    PYTHONPATH=src nice -n 10 python benchmarks/mutation.py            # all 35
    PYTHONPATH=src python benchmarks/mutation.py --only mounts-norm-axis frf-residual-dof
    python benchmarks/mutation.py --list
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"


@dataclass(frozen=True)
class Mutant:
    name: str
    file: str  # under src/rigidid
    original: str
    replacement: str
    why: str
    tests: tuple[str, ...]


MUTANTS: tuple[Mutant, ...] = (
    # --- the eight the issue found surviving (main c8b397c) ------------------------------------
    Mutant(
        "frf-residual-dof",
        "core/frfmodes.py",
        "np.sqrt(max(base.shape[0] - 6, 0)) * sigma[k] / size",
        "np.sqrt(max(base.shape[0], 0)) * sigma[k] / size",
        "forgetting that a rigid-body fit absorbs 6 of the p dimensions of the noise",
        ("tests/core/test_mutants.py::test_nonrigid_residual_reads_back_as_the_noise_put_in",),
    ),
    Mutant(
        "massline-elastic-sign",
        "core/massline.py",
        "cols_re.extend([x / (1.0 - x), u**2])",
        "cols_re.extend([x / (1.0 + x), u**2])",
        "sign slip in the quasi-static term of an elastic mode above the band",
        ("tests/core/test_mutants.py::test_mass_line_with_an_elastic_mode_above_the_band_is_exact",),
    ),
    Mutant(
        "mounts-norm-axis",
        "core/mounts.py",
        "norms = np.linalg.norm(u, axis=1, keepdims=True)",
        "norms = np.linalg.norm(u, axis=2, keepdims=True)",
        "rows for columns: the axes are the columns of axes[k]",
        ("tests/core/test_mutants.py::test_mount_rates_do_not_depend_on_the_length_of_the_axis_vectors",),
    ),
    Mutant(
        "mounts-output-damping-weight",
        "core/mounts.py",
        "/ max(self.zeta[i], 1e-4) / self.damp",
        "/ max(self.zeta[i], 1e-4)",
        "a noise weight dropped from one of the output-error terms",
        ("tests/core/test_mutants.py::test_output_error_is_in_units_of_the_stated_noise",),
    ),
    Mutant(
        "suspect-median-includes-suspect",
        "core/selection.py",
        "others = float(np.median(np.delete(r, k)))",
        "others = float(np.median(r))",
        "the robust reference taken over all modes, the suspect included",
        ("tests/core/test_mutants.py::test_an_elastic_suspect_does_not_raise_the_median_it_is_judged_by",),
    ),
    Mutant(
        "sensor-check-leverage",
        "core/checks.py",
        "misfit[checkable] = np.sqrt(np.mean(np.abs(residual[checkable] / (1.0 - lev)) ** 2, axis=1))",
        "misfit[checkable] = np.sqrt(np.mean(np.abs(residual[checkable]) ** 2, axis=1))",
        "the ordinary residual taken for the leave-one-out residual",
        ("tests/core/test_mutants.py::test_sensor_misfit_is_the_leave_one_out_prediction_error",),
    ),
    Mutant(
        "percent-damping-mean",
        "core/checks.py",
        "if z.size and float(np.median(z)) > threshold:",
        "if z.size and float(np.mean(z)) > threshold:",
        "the mean for the robust median: one heavily damped mode flags all as percentages",
        ("tests/core/test_mutants.py::test_one_heavily_damped_mode_does_not_look_like_percentages",),
    ),
    Mutant(
        "sensor-check-typical-median",
        "core/checks.py",
        "typical = float(np.median(misfit[checkable]))",
        "typical = float(np.median(misfit))",
        "the typical misfit over all sensors, the unchecked ones' zeros included",
        ("tests/core/test_mutants.py::test_typical_misfit_ignores_sensors_that_cannot_be_checked",),
    ),
    # --- twenty more ------------------------------------------------------------------------
    Mutant(
        "transfer-sign",
        "core/geometry.py",
        "g[:3, 3:] = -skew(offset)",
        "g[:3, 3:] = skew(offset)",
        "sign of the cross-product term of eq. (12)",
        ("tests/core/test_geometry.py",),
    ),
    Mutant(
        "sensor-row-cross-order",
        "core/geometry.py",
        "np.concatenate([n, np.cross(r, n)], axis=-1)",
        "np.concatenate([n, np.cross(n, r)], axis=-1)",
        "operand order of the cross product in eq. (3)",
        ("tests/core/test_geometry.py",),
    ),
    Mutant(
        "damping-ratio-small-angle",
        "core/statespace.py",
        "return w / (2.0 * np.pi), -lam.real / w",
        "return w / (2.0 * np.pi), -lam.real / lam.imag",
        "the light-damping approximation -Re/Im for -Re/|lambda|",
        ("tests/core/test_statespace.py",),
    ),
    Mutant(
        "shape-noise-dof",
        "core/noise.py",
        "np.sqrt(sensors / (sensors - 6.0) * np.mean(rho**2))",
        "np.sqrt(sensors / (sensors - 5.0) * np.mean(rho**2))",
        "off by one in the residual degrees of freedom",
        ("tests/core/test_mutants.py::test_shape_noise_read_from_residuals_is_the_noise_drawn",),
    ),
    Mutant(
        "draw-complex-noise-scale",
        "core/noise.py",
        "unit = (normals.shape[..., 0] + 1j * normals.shape[..., 1]) / np.sqrt(2.0)",
        "unit = normals.shape[..., 0] + 1j * normals.shape[..., 1]",
        "complex noise of unit variance per part instead of per value",
        ("tests/core/test_mutants.py::test_shape_noise_read_from_residuals_is_the_noise_drawn",),
    ),
    Mutant(
        "percentile-interval",
        "core/uncertainty.py",
        "np.percentile(samples, [2.5, 97.5], axis=0)",
        "np.percentile(samples, [5.0, 95.0], axis=0)",
        "a 90 % interval reported as the 95 % one",
        ("tests/core/test_mutants.py::test_percentile_interval_holds_95_percent_of_the_draws",),
    ),
    Mutant(
        "principal-axes-handedness",
        "core/identify.py",
        "v[:, 2] = np.cross(v[:, 0], v[:, 1])",
        "v[:, 2] = np.cross(v[:, 1], v[:, 0])",
        "a left-handed set of principal axes",
        ("tests/core/test_identify.py",),
    ),
    Mutant(
        "torque-roll-axis-inverse",
        "core/mounts.py",
        "w = np.linalg.solve(j, t)",
        "w = j @ t",
        "J t for J^-1 t: the torque roll axis is the rotation a torque causes",
        ("tests/core/test_mounts.py",),
    ),
    Mutant(
        "axis-angle-sign",
        "core/mounts.py",
        "math.atan2(float(np.linalg.norm(np.cross(a, b))), abs(float(a @ b)))",
        "math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b))",
        "the angle between axes (lines) taken as between vectors",
        ("tests/core/test_mutants.py::test_angle_to_a_principal_axis_ignores_its_sign",),
    ),
    Mutant(
        "third-difference-variance",
        "core/massline.py",
        "var = float(np.mean(d3**2)) / 20.0",
        "var = float(np.mean(d3**2)) / 6.0",
        "the variance gain of second differences (6) used for third differences (20)",
        ("tests/core/test_mutants.py::test_noise_residual_reads_white_noise_level",),
    ),
    Mutant(
        "rigid-mass-matrix-skew",
        "core/rigidfrf.py",
        "out[3:, :3] = skew(t[1:4])",
        "out[3:, :3] = -skew(t[1:4])",
        "sign of the m S(g) block: the mass matrix loses its symmetry",
        ("tests/core/test_mutants.py::test_mass_matrix_from_parameters_is_a_bodys",),
    ),
    Mutant(
        "plan-score-units",
        "core/plan.py",
        "np.linalg.norm(cg_std, axis=-1) / length",
        "np.linalg.norm(cg_std, axis=-1) * length",
        "a score that is not dimensionless: the choice of sensors would depend on the length unit",
        ("tests/core/test_mutants.py::test_plan_score_is_dimensionless",),
    ),
    Mutant(
        "refine-interval-z",
        "core/timedomain/refine.py",
        "IntervalEstimate(estimate, std, estimate - _Z95 * std, estimate + _Z95 * std)",
        "IntervalEstimate(estimate, std, estimate - std, estimate + std)",
        "a one-standard-error interval reported as 95 %",
        ("tests/core/test_mutants.py::test_refit_intervals_are_95_percent_normal_intervals",),
    ),
    Mutant(
        "segment-spread-sqrt",
        "core/record_spread.py",
        "std = np.std(np.stack(samples[key]), axis=0, ddof=1) / math.sqrt(segments)",
        "std = np.std(np.stack(samples[key]), axis=0, ddof=1)",
        "the spread of the segments reported as the error of their combination",
        ("tests/core/test_record_spread.py",),
    ),
    Mutant(
        "pretrigger-fir-gain",
        "core/timedomain/refine.py",
        "s = s * math.sqrt(float(np.sum(fir_taps(factor) ** 2)))",
        "s = s * float(np.sum(fir_taps(factor) ** 2))",
        "the noise-power gain of the decimation filter applied to an amplitude",
        ("tests/core/test_mutants.py::test_pretrigger_noise_after_decimation_is_the_decimated_noise",),
    ),
    Mutant(
        "varpro-cg-sign",
        "core/estimator.py",
        "xg11 = self.x11 - s @ self.x21",
        "xg11 = self.x11 + s @ self.x21",
        "sign of the change of reference point, eq. (12), in the CG search",
        ("tests/core/test_estimator.py",),
    ),
    Mutant(
        "era-pole-dt",
        "core/timedomain/era.py",
        "poles: CArray = np.log(z) / dt",
        "poles: CArray = np.log(z) * dt",
        "discrete to continuous poles: dividing by the sample interval",
        ("tests/core/test_timedomain.py",),
    ),
    Mutant(
        "layout-antiparallel",
        "core/layout_check.py",
        "cosang = np.abs(lay.directions @ lay.directions.T)",
        "cosang = lay.directions @ lay.directions.T",
        "a reversed sensor next to another taken for a different direction (axes are lines, not senses)",
        ("tests/core/test_mutants.py::test_a_reversed_sensor_next_to_another_is_as_redundant_as_a_parallel_one",),
    ),
    Mutant(
        "undamped-pole-frequency",
        "core/statespace.py",
        "result: CArray = w * (-z + 1j * np.sqrt(1.0 - z * z))",
        "result: CArray = w * (-z + 1j)",
        "the damped natural frequency taken for the undamped one",
        ("tests/core/test_statespace.py",),
    ),
    Mutant(
        "lm-unfloored-scaling",
        "core/optimize.py",
        "d = np.maximum(diag, 1e-12 * np.maximum(np.max(diag, axis=1, keepdims=True), 1e-300))",
        "d = diag",
        "Marquardt's scaling unfloored: a parameter the data do not determine makes the damped system singular",
        ("tests/core/test_optimize.py",),
    ),
    Mutant(
        "lm-no-rounding-floor",
        "core/optimize.py",
        "done = (dec <= floor[idx]) | (state.cost[idx] <= floor[idx])",
        "done = np.zeros(idx.size, dtype=bool)",
        "no zero-residual stop (the issue's fault: noise-free refits never say converged)",
        ("tests/core/test_optimize.py",),
    ),
    Mutant(
        "sensor-gate-inverted",
        "core/timedomain/refine.py",
        'estimate = test.flagged and data.noise_from == "pretrigger"',
        'estimate = not test.flagged and data.noise_from == "pretrigger"',
        "the sensor test's default inverted: sensors estimated when it does not flag (issue 23)",
        ("tests/core/test_sensor_refit.py",),
    ),
    Mutant(
        "massline-level-unwhitened-target",
        "core/massline.py",
        "x_w, y_w = design / np.sqrt(level)[:, None], target / np.sqrt(level)[:, None]",
        "x_w, y_w = design / np.sqrt(level)[:, None], target / level[:, None]",
        "the first-order mass line's data weighted by the level, its design by the level's root (issue 21)",
        ("tests/core/test_massline.py::test_first_order_mass_line_weights_each_line_by_its_noise_level",),
    ),
    Mutant(
        "sensor-positions-kept",
        "core/timedomain/refine.py",
        "x: Array = np.linalg.solve(system, rhs).astype(float)",
        "x: Array = np.where(np.arange(v.size) < v.size // 2, np.linalg.solve(system, rhs), 0.0).astype(float)",
        "the sensors' positions left at their prior again: the position cell's runs miss the target (issue 23)",
        ("tests/core/test_sensor_refit.py::test_a_sensor_off_its_stated_position_is_flagged_and_its_shift_estimated",),
    ),
    Mutant(
        "after-check-no-absorbed-noise",
        "core/timedomain/refine.py",
        "float(2.0 * np.trace(sq) - np.trace(sq @ sq))",
        "0.0",
        "the after-check forgets the noise the correction fits: corrections dropped too often (issue 23)",
        ("tests/core/test_after_check.py",),
    ),
    Mutant(
        "clip-pulse-counted",
        "core/timedomain/clipping.py",
        " & (self.last >= after)",
        "",
        "a channel clipped during the hammer's pulse only left out of the fit again (issue 23)",
        ("tests/test_clipping.py",),
    ),
    Mutant(
        "hum-decaying-line-kept",
        "core/timedomain/hum.py",
        "return late >= STEADY * early",
        "return True",
        "a mode's decaying misfit near 50/60 Hz declared hum (issue 23)",
        ("tests/core/test_hum.py",),
    ),
    Mutant(
        "band-noise-white",
        "core/timedomain/pretrigger.py",
        "z = decimate(r, factor) if factor > 1 else r",
        "z = decimate(r.std(axis=0) * np.random.default_rng(0).standard_normal(r.shape), factor) if factor > 1 else r",
        "the pre-trigger's noise taken as white, not measured in the fit's band (issue 23)",
        ("tests/core/test_pretrigger.py",),
    ),
    Mutant(
        "band-noise-hum-left",
        "core/timedomain/pretrigger.py",
        "basis = np.column_stack([np.ones(n), hum_columns(",
        "basis = np.ones((n, 1)); _lines = np.column_stack([np.ones(n), hum_columns(",
        "the hum left in the pre-trigger's noise (issue 23)",
        ("tests/core/test_pretrigger.py", "tests/core/test_chain.py"),
    ),
    Mutant(
        "skew-refit-unconfirmed-kept",
        "api/records.py",
        "abs(skewed.delays[i]) > _SKEW_Z * skewed.delays_std[i] for i, _ in late if i < len(skewed.delays)",
        "True for i, _ in late",
        "a skew refit whose fitted delays do not confirm the score kept (issue 23)",
        ("tests/test_skew_refit.py",),
    ),
    Mutant(
        "diverged-correction-raises",
        "core/timedomain/refine.py",
        "with contextlib.suppress(np.linalg.LinAlgError):",
        "with contextlib.suppress(KeyError):",
        "a sensor correction whose later pass diverges takes the whole refit down (issue 23)",
        ("tests/core/test_sensor_refit.py",),
    ),
    Mutant(
        "coupling-not-modelled",
        "core/timedomain/refine.py",
        "if coupling is None or not (estimate_highpass or (estimate_highpass is None and coupling.flagged)):",
        "if True:",
        "an AC coupling the score test flags left unmodelled by default (issue 23)",
        ("tests/core/test_coupling_refit.py",),
    ),
    Mutant(
        "coupling-corner-off-tangent",
        "core/timedomain/refine.py",
        "hz_per_rate=omega / (2.0 * math.pi), tangent=tangent,",
        "hz_per_rate=omega / (2.0 * math.pi), tangent=None,",
        "the AC corner found without projecting off the fit's Jacobian: biased by what the body absorbed (issue 23)",
        ("tests/core/test_coupling_refit.py",),
    ),
    Mutant(
        "coupling-modal-columns-ignored",
        "core/timedomain/coupling.py",
        "w = zz[:, None, None] * np.eye(p)[None] - b @ ginv @ b.transpose(0, 2, 1)",
        "w = zz[:, None, None] * np.eye(p)[None] + 0.0 * b[:, :, :1]",
        "the coupling's score not projected off the modal columns: the statistic too large (issue 23)",
        ("tests/core/test_coupling.py",),
    ),
    Mutant(
        "signatures-modal-projection-dropped",
        "core/timedomain/refine.py",
        "out: Array = own.reshape(kinds * p, kinds * p) - self.b.T @ self.inv @ self.b",
        "out: Array = own.reshape(kinds * p, kinds * p) - 0.0 * self.b.T @ self.inv @ self.b",
        "the sensors' signatures not projected off the modal columns in their Gram (issue 23's sensor test)",
        ("tests/core/test_signatures.py",),
    ),
    Mutant(
        "coupling-later-pass-ignored",
        "core/timedomain/refine.py",
        "and later is not None and later.flagged:\n        coupling = later",
        "and later is not None and later.flagged:\n        pass",
        "a coupling only the sensors' corrected pass finds left unmodelled (issue 23)",
        ("tests/core/test_coupling_sensors.py",),
    ),
    Mutant(
        "skew-refit-failure-drops-plain",
        "api/records.py",
        "return _accept_refinement(result, plain, tolerances, ids) if plain_kept else result",
        "return result",
        "a skew refit that fails takes a passed plain refit down to the answer from the modes (issue 23)",
        ("tests/test_skew_refit.py",),
    ),
    Mutant(
        "svd-no-fallback",
        "core/linalg.py",
        'u, s, vt = qr_iteration(a, full_matrices=full_matrices, lapack_driver="gesvd")',
        "raise",
        "an SVD that does not converge by divide and conquer not retried (chain_matrix all, seed 1005)",
        ("tests/core/test_linalg_svd.py",),
    ),
    Mutant(
        "chi2-tail-series-term",
        "core/chisquare.py",
        "        term *= x / ap",
        "        term *= x / (ap + 1.0)",
        "the chi-square tail's series wrong (the sensor and coupling tests' p-values)",
        ("tests/core/test_chisquare.py",),
    ),
)


def _apply(tree: Path, mutant: Mutant) -> None:
    path = tree / "rigidid" / mutant.file
    text = path.read_text(encoding="utf-8")
    count = text.count(mutant.original)
    if count != 1:
        raise SystemExit(f"mutant {mutant.name}: snippet found {count} times in src/rigidid/{mutant.file}")
    path.write_text(text.replace(mutant.original, mutant.replacement), encoding="utf-8")


def run(mutant: Mutant) -> tuple[bool, float]:
    """Apply `mutant` in a temporary copy of src/ and run its tests; (caught, seconds)."""
    with tempfile.TemporaryDirectory(prefix="rigidid-mutant-") as tmp:
        tree = Path(tmp) / "src"
        shutil.copytree(SRC, tree, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        _apply(tree, mutant)
        env = dict(os.environ, PYTHONPATH=str(tree), PYTHONDONTWRITEBYTECODE="1")
        cmd = [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "--no-header", "-n", "0"]
        cmd += mutant.tests
        start = time.perf_counter()
        out = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
        seconds = time.perf_counter() - start
    if out.returncode not in (0, 1):
        raise SystemExit(
            f"mutant {mutant.name}: pytest exited {out.returncode}\n{out.stdout[-2000:]}{out.stderr[-2000:]}"
        )
    return out.returncode == 1, seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", nargs="*", help="mutant names to run (default: all)")
    parser.add_argument("--list", action="store_true", help="list the mutants and exit")
    args = parser.parse_args()
    for m in MUTANTS:  # every snippet must still be in the tree, before anything runs
        text = (SRC / "rigidid" / m.file).read_text(encoding="utf-8")
        if text.count(m.original) != 1:
            raise SystemExit(f"mutant {m.name}: snippet not found exactly once in src/rigidid/{m.file}")
    chosen = [m for m in MUTANTS if not args.only or m.name in args.only]
    if args.list:
        for m in chosen:
            print(f"{m.name:34s} {m.file:28s} {m.why}")
        return
    print(f"{'mutant':34s} {'file':28s} {'result':9s} {'s':>6s}")
    survived = []
    for m in chosen:
        caught, seconds = run(m)
        print(f"{m.name:34s} {m.file:28s} {'caught' if caught else 'SURVIVED':9s} {seconds:6.1f}", flush=True)
        if not caught:
            survived.append(m.name)
    print(
        f"\n{len(chosen) - len(survived)} of {len(chosen)} caught"
        + (f"; survived: {', '.join(survived)}" if survived else "")
    )
    sys.exit(1 if survived else 0)


if __name__ == "__main__":
    main()
