"""Accuracy read run by run in the sensor-error cells: what any estimator can reach (issue 23).

Run from the worktree root (a few minutes for the maps, then seconds; ``--candidate`` adds ~5 s per run)::

    PYTHONPATH=src OPENBLAS_NUM_THREADS=1 nice -n 10 python benchmarks/per_run_floor.py [--draws 20000]
        [--cache /tmp/per_run_maps.npz] [--candidate 20]

The body, sensors, impacts and simulator of ``benchmarks/chain_matrix.py`` (its own scipy expm model).
The issue's per-run target: a run's error (CG: largest coordinate, % of the sensor span; J: largest
relative error of the diagonal, %) within 1.25 x the floor (the modal kernel, rigidid's modes route,
on the exact modes read through the same sensors) plus 6 of the clean case's standard errors.

1. **The two linear maps** of the 60 sensor errors (per sensor: gain, the reading axis turned towards
   its two normals, the position shifted along x, y, z) to the six figures (CG % span, J/m diagonal %):

   - ``R``, the records refit's (``refine_body`` on noise-free records, one error at a time, started at
     the truth; the refit is linear in the sensor errors, benchmarks/sensor_sensitivity.py ``--linear``);
   - ``K``, the kernel's on the exact modes (the floor's map), by central differences.

   To first order every estimator efficient for the noise has the refit's map (a sensor error is a data
   perturbation, and an efficient estimator's linear map of the data is unique), so ``R``'s miss rate is
   every efficient estimator's.
2. **Monte Carlo over the stated tolerance draws** (the cells' rectangular distributions, as
   ``chain_matrix --stated``) with the refit's noise (Gaussian, its clean-case std per figure): per cell,
   the probability a run misses the per-run target, for the maps ``E_w = K + w (R - K)`` (w = 1: the refit;
   w = 0: the kernel's own map, what a kernel fed with noise-free modal data would reach), the RMS of
   each class's largest error over the refit's, and the minimum-variance combination per figure
   (weights from the maps' joint covariance under the stated distribution).
3. **The invisible errors and the bound**: the sensor errors no records can tell from a change of the body
   (first order, from the modal model written afresh here: the change of the read shapes is a body's change
   whose poles stay, plus a complex scale per mode). On them every consistent estimator's map is the same (the refit's
   and the kernel's agree there: printed as a check); elsewhere an estimator that uses the redundancy can
   take any value. Printed: the least RMS any consistent linear map reaches (noise-free), and the least RMS
   of one passing the per-run target on every one of ``--qp-draws`` draws (a quadratic programme per figure),
   with its pass rate on all draws. Near 0: the per-run target is reachable in principle, by estimating the
   visible sensor errors; the price is noise, measured in 4.
4. ``--candidate N``: estimators measured on N simulated runs per cell (1 % noise), run by run against the
   run's own floor and the refit's noise std (``--candidate-cells``):

   - ``refit``: ``refine_body`` started at the truth (no sensor parameters: the efficient map ``R``);
   - ``candidate``: the mode shapes by linear least squares at the refit's poles (each channel's and
     impact's complex residues given the poles, then per mode the rank-one fit across impacts, weighted by
     the channels' pre-trigger noise), then the kernel (``oracle poles``: the same at the true poles);
   - ``mix``: per figure, the minimum-variance combination of refit and candidate (weights from their joint
     covariance: noise from the clean runs, sensors from ``R``, ``K`` over the cell's stated distribution);
   - ``sensors estimated``: the refit with the sensors' gains, axes and positions estimated jointly, the stated
     tolerances as their prior (``refine_body(..., estimate_sensors=True)``, what ``--estimate-sensors``
     does; the positions were an experiment, ``--free-positions``, until rigidid estimated them);
     ``--clean-default-tolerances``: in the clean cell it states rigidid's default tolerances (exact sensors:
     what estimating them costs when there is nothing to correct).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import chain_matrix as cm
import sensor_sensitivity as ss

N_SENSORS = cm.SENSORS.shape[0]
KINDS = ("gain", "axis e1", "axis e2", "shift x", "shift y", "shift z")
STEPS = (0.01, 0.01, 0.01, 0.001, 0.001, 0.001)  # relative, rad, m
CELLS = ("sens", "orient", "transverse", "position", "all")
MEASURED = {"sens": 14, "orient": 12, "transverse": 9, "position": 14, "all": 10}
"""Runs of 20 within the per-run target on main d30dbf8 (chain_matrix --seeds 20 --stated, issue 23's note)."""


def _errors(j: int, h: float) -> dict[str, np.ndarray]:
    """Sensor errors with parameter `j` (sensor j // 6, kind j % 6) set to `h`, the rest zero."""
    err = {"gain": np.zeros(N_SENSORS), "tilt": np.zeros((N_SENSORS, 2)), "trans": np.zeros((N_SENSORS, 2)),
           "shift": np.zeros((N_SENSORS, 3))}  # fmt: skip
    i, kind = divmod(j, 6)
    if kind == 0:
        err["gain"][i] = h
    elif kind < 3:
        err["trans"][i, kind - 1] = h  # the reading vector turned towards a normal (first order: tilt alike)
    else:
        err["shift"][i, kind - 3] = h
    return err


def refit_at_truth(records: object, **options: object) -> Any:
    """The records refit of `records` (chain_matrix's test: three impacts, decimation 8), started at the truth;
    `options` go to ``refine_body``."""
    from rigidid.core.timedomain.refine import refine_body

    onset = int(cm.PRE * cm.RATE)
    return refine_body(
        records, 1.0 / cm.RATE, cm.SENSORS, cm.AXES, starts=[onset + 16] * 3, onsets=[onset] * 3, decimation=8,
        center_of_gravity=cm.CG, inertia_per_mass=cm.INERTIA / cm.MASS, stiffness_per_mass=cm.K6 / cm.MASS,
        damping_per_mass=cm.C6 / cm.MASS, **options,
    )  # fmt: skip


def refit_figures(true: dict[str, np.ndarray], noise: float, seed: int) -> tuple[np.ndarray, np.ndarray, object]:
    """The refit's figures (% vector), its noise std (% vector) and the Refinement, started at the truth."""
    recs = ss.records(true, noise, False, np.random.default_rng(seed))
    ref = refit_at_truth(recs)
    return ss._vector(ref.center_of_gravity, ref.inertia_per_mass), ss._std_vector(ref.std), ref


def kernel_figures(true: dict[str, np.ndarray]) -> np.ndarray:
    """The kernel's figures on the exact modes read through the sensors `true`."""
    from rigidid.core.estimator import estimate

    freq, zeta, q = cm.modes()
    lam = -zeta * 2 * np.pi * freq + 1j * 2 * np.pi * freq * np.sqrt(1 - zeta**2)
    read = np.array([r @ cm._point(p - cm.CG) for r, p in zip(true["reading"], true["position"], strict=True)])
    est = estimate(cm.SENSORS[None], cm.AXES[None], lam[None], (read @ q)[None])
    return ss._vector(est.center_of_gravity[0], est.inertia_per_mass[0])


def linear_maps(progress: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``R`` and ``K`` (6 x 60, % per unit error) and the refit's noise std at 1 % noise (6,)."""
    base, _, _ = refit_figures(ss.sensors(_errors(0, 0.0)), 1e-6, 0)
    r_map, k_map = np.zeros((6, 6 * N_SENSORS)), np.zeros((6, 6 * N_SENSORS))
    for j in range(6 * N_SENSORS):
        h = STEPS[j % 6]
        moved, _, _ = refit_figures(ss.sensors(_errors(j, h)), 1e-6, 0)
        r_map[:, j] = (moved - base) / h
        hk = 1e-3 * h
        k_map[:, j] = (kernel_figures(ss.sensors(_errors(j, hk))) - kernel_figures(ss.sensors(_errors(j, -hk)))) / (
            2 * hk
        )
        if progress and j % 6 == 5:
            print(f"  maps: sensor {j // 6 + 1} of {N_SENSORS}", file=sys.stderr, flush=True)
    stds = np.array([refit_figures(ss.sensors(_errors(0, 0.0)), cm.NOISE, s)[1] for s in range(3)])
    return r_map, k_map, np.sqrt(np.mean(stds**2, axis=0))


def draws(cell: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """`n` draws (n x 60) of the cell's sensor errors from the stated (rectangular) distribution."""
    s = np.zeros((n, N_SENSORS, 6))
    if cell in ("sens", "all"):
        s[:, :, 0] = rng.uniform(-0.03, 0.03, (n, N_SENSORS))
    if cell in ("orient", "all"):
        s[:, :, 1:3] += rng.uniform(-np.radians(3.0), np.radians(3.0), (n, N_SENSORS, 2))
    if cell in ("transverse", "all"):
        tau, phase = rng.uniform(0.0, 0.03, (n, N_SENSORS)), rng.uniform(0.0, 2 * np.pi, (n, N_SENSORS))
        s[:, :, 1] += tau * np.cos(phase)
        s[:, :, 2] += tau * np.sin(phase)
    if cell in ("position", "all"):
        s[:, :, 3:] = rng.uniform(-0.003, 0.003, (n, N_SENSORS, 3))
    return s.reshape(n, -1)


def per_class(e: np.ndarray) -> np.ndarray:
    """Largest |figure| of each class (CG, J) per run: (n, 2)."""
    return np.column_stack([np.abs(e[:, :3]).max(axis=1), np.abs(e[:, 3:]).max(axis=1)])


def passes(e: np.ndarray, floor: np.ndarray, se: np.ndarray) -> np.ndarray:
    """Runs within 1.25 x the floor plus 6 clean standard errors, both classes."""
    return np.all(per_class(e) <= 1.25 * per_class(floor) + 6 * se, axis=1)


def rms(e: np.ndarray) -> np.ndarray:
    """RMS over runs of each class's largest error (chain_matrix's statistic)."""
    return np.sqrt(np.mean(per_class(e) ** 2, axis=0))


def min_variance_weights(r_map: np.ndarray, k_map: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Per figure, the weight w of ``K + w (R - K)`` minimising the sensor error's variance over draws `s`."""
    er, ek = s @ r_map.T, s @ k_map.T
    d = er - ek
    return np.clip(-np.sum(ek * d, axis=0) / np.sum(d * d, axis=0), 0.0, 1.0)


def _modal(theta: np.ndarray, reading: np.ndarray, position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poles and the shapes the sensors read (each mode scaled to 1 at the truth's largest DOF) of body `theta`.

    `theta`: CG (3), the inertia's upper triangle (6), K and C at the CG (21 each): written afresh here.
    """
    _, _, q0 = cm.modes()
    ref = np.argmax(np.abs(q0), axis=0)
    m6 = np.diag([cm.MASS] * 3 + [0.0] * 3)
    m6[3:, 3:] = _sym(theta[3:9], 3)
    k6, c6 = _sym(theta[9:30], 6), _sym(theta[30:51], 6)
    a = np.block([[np.zeros((6, 6)), np.eye(6)], [-np.linalg.solve(m6, k6), -np.linalg.solve(m6, c6)]])
    lam, vec = np.linalg.eig(a)
    up = lam.imag > 0
    lam, vec = lam[up], vec[:, up]
    order = np.argsort(np.abs(lam))
    lam, vec = lam[order], vec[:6, order]
    rows = np.array([r @ cm._point(p - theta[:3]) for r, p in zip(reading, position, strict=True)])
    return lam, rows @ (vec / vec[ref, np.arange(6)])


def _sym(v: np.ndarray, n: int) -> np.ndarray:
    m = np.zeros((n, n))
    m[np.triu_indices(n)] = v
    return m + np.triu(m, 1).T


def invisible_basis() -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal bases (rows) of the sensor errors no records can tell from a change of the body, and the rest.

    First order at the truth: the records' free decays are the modes read through the sensors with free
    amplitudes per mode and impact, so a sensor error ``s`` is invisible when its change of the read shapes is
    a change of some body's shapes (CG, J, K, C) whose poles do not move, plus a complex scale per mode.
    Every consistent estimator's map takes the same value on these (the kernel's and the refit's agree there).
    """
    theta = np.concatenate([cm.CG, cm.INERTIA[np.triu_indices(3)], cm.K6[np.triu_indices(6)],
                            cm.C6[np.triu_indices(6)]])  # fmt: skip
    base = ss.sensors(_errors(0, 0.0))
    _, phi = _modal(theta, base["reading"], base["position"])

    def flat(z: np.ndarray) -> np.ndarray:
        return np.concatenate([z.real.ravel(), z.imag.ravel()])

    body, poles = [], []
    for j in range(theta.size):
        step = 1e-6 * max(1.0, abs(theta[j]))
        up, down = theta.copy(), theta.copy()
        up[j] += step
        down[j] -= step
        (lu, pu), (ld, pd) = (_modal(t, base["reading"], base["position"]) for t in (up, down))
        body.append(flat(pu - pd) / (2 * step))
        poles.append(flat(lu - ld) / (2 * step))
    one = np.eye(6, dtype=bool)
    scale = [flat(np.where(one[r], phi, 0)) for r in range(6)] + [flat(np.where(one[r], 1j * phi, 0)) for r in range(6)]
    fit = np.block([[np.array(body).T, np.array(scale).T], [np.array(poles).T, np.zeros((12, 12))]])
    u, sv, _ = np.linalg.svd(fit / np.linalg.norm(fit, axis=0), full_matrices=False)
    u = u[:, sv > 1e-8 * sv[0]]
    sig = []
    for j in range(6 * N_SENSORS):
        (_, pu), (_, pd) = (_modal(theta, *_true(_errors(j, h)).values()) for h in (1e-6, -1e-6))
        sig.append(np.concatenate([flat(pu - pd) / 2e-6, np.zeros(12)]))
    g = np.array(sig).T
    _, sg, vt = np.linalg.svd(g - u @ (u.T @ g))
    seen = int(np.sum(sg > 1e-6 * sg[0]))
    return vt[seen:], vt[:seen]


def _true(err: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    out = ss.sensors(err)
    return {"reading": out["reading"], "position": out["position"]}


def qp_bound(r_map: np.ndarray, k_map: np.ndarray, bases: tuple[np.ndarray, np.ndarray], s: np.ndarray,
             se: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:  # fmt: skip
    """The least-variance consistent linear maps: unconstrained, and passing the per-run target on every draw.

    A consistent estimator's map is the refit's on the invisible errors (``bases[0]``) and free on the rest
    (``bases[1]``): ``E = R N^T N + X V``. Per figure, minimise the variance of ``E s`` over the draws `s`:
    without constraint (the least any estimator can reach, noise-free: every visible error estimated), and
    keeping ``|E_i s_d| <= 1.25 max_class |K s_d| + 6 se_class`` on every draw (SLSQP from the kernel's map,
    feasible). Returns both maps (6 x 60) and the largest constraint violation (should be ~0).
    """
    from scipy.optimize import minimize

    null, seen = bases
    fixed = r_map @ null.T @ null
    floor = per_class(s @ k_map.T)
    sv, sf = s @ seen.T, s @ fixed.T  # draws x visible, draws x figures
    free, held = np.zeros_like(k_map), np.zeros_like(k_map)
    worst = 0.0
    for i in range(6):
        c = 1.25 * floor[:, 0 if i < 3 else 1] + 6 * se[0 if i < 3 else 1]
        x_free = -np.linalg.lstsq(sv, sf[:, i], rcond=None)[0]
        free[i] = fixed[i] + x_free @ seen
        cons = [
            {
                "type": "ineq",
                "jac": lambda x: np.vstack([-sv, sv]),
                "fun": lambda x, c=c, i=i: np.concatenate([c - sf[:, i] - sv @ x, c + sf[:, i] + sv @ x]),
            }
        ]
        res = minimize(lambda x, i=i: np.mean((sf[:, i] + sv @ x) ** 2), seen @ k_map[i],
                       jac=lambda x, i=i: 2 * sv.T @ (sf[:, i] + sv @ x) / len(sv), constraints=cons,
                       method="SLSQP", options={"maxiter": 500, "ftol": 1e-14})  # fmt: skip
        held[i] = fixed[i] + res.x @ seen
        worst = max(worst, float(np.max(np.abs(sf[:, i] + sv @ res.x) - c)))
    return free, held, worst


def ls_shapes(records: list[np.ndarray], poles: np.ndarray, start: int, pre: int) -> np.ndarray:
    """Mode shapes (p x 6) by linear least squares at fixed `poles` (rad/s), rank one across impacts.

    Per record: the free decay from sample `start`, a constant and each mode's ``Re, Im e^(lambda t)`` per
    channel (the residues given the poles: linear); per mode, the channels-by-impacts residue matrix,
    weighted by each channel's pre-trigger noise (samples before `pre`), fitted by its leading singular
    vector (the shape; each impact's participation the other factor).
    """
    dt = 1.0 / cm.RATE
    residues = []
    sigma = np.sqrt(np.mean([np.var(r[:pre], axis=0) for r in records], axis=0))
    for rec in records:
        y = rec[start:]
        ex = np.exp(np.outer(np.arange(y.shape[0]) * dt, poles))
        design = np.column_stack([ex.real, ex.imag, np.ones(y.shape[0])])
        coef = np.linalg.lstsq(design, y, rcond=None)[0]
        residues.append((coef[:6] - 1j * coef[6:12]).T)  # (p, 6): y = Re(c e^(lambda t))
    shapes = np.zeros((records[0].shape[1], 6), dtype=complex)
    for r in range(6):
        m = np.column_stack([res[:, r] for res in residues]) / sigma[:, None]
        u = np.linalg.svd(m)[0][:, 0]
        shapes[:, r] = sigma * u
    return shapes


CLEAN_DEFAULT = False
"""``--clean-default-tolerances``: the clean cell's 'sensors estimated' states rigidid's default tolerances (exact
sensors, tolerances stated: what estimating them costs when there is nothing to correct)."""


def stated_bounds(effects: set[str]) -> object:
    """The cell's stated tolerances (chain_matrix's bounds; zero for the sources not drawn)."""
    from rigidid.core.sensor_budget import DEFAULT_BOUNDS, SensorBounds

    if not effects and CLEAN_DEFAULT:
        return DEFAULT_BOUNDS
    return SensorBounds(**cm.stated_tolerances(effects))


def candidate_run(cell: str, seed: int) -> dict[str, np.ndarray]:
    """One run of chain_matrix's draw for `cell` (its sensor effects only): refit, candidate, floor, noise std.

    The same draw as ``chain_matrix.run_cell(cell, seed)`` with ``--stated`` (``all``: its four sensor
    sources, none of the chain's effects). The refit is started at the truth (the API's default start
    converges to the same minimum on these records).
    """
    from rigidid.core.estimator import estimate

    cm.STATED_DRAWS = True
    effects = {"sens", "orient", "transverse", "position"} if cell == "all" else set() if cell == "clean" else {cell}
    rng = np.random.default_rng(1000 * seed + cm.CELLS.index(cell))
    sensors = cm.sensor_errors(effects, rng)
    records = cm.simulate(effects, rng, sensors)
    ref = refit_at_truth(records)
    onset = int(cm.PRE * cm.RATE)
    freq, zeta, _ = cm.modes()
    true_poles = -zeta * 2 * np.pi * freq + 1j * 2 * np.pi * freq * np.sqrt(1 - zeta**2)
    out = {"refit": ss._vector(ref.center_of_gravity, ref.inertia_per_mass), "std": ss._std_vector(ref.std)}
    for name, poles in (("candidate", np.sort_complex(ref.poles)), ("oracle poles", true_poles)):
        shapes = ls_shapes(records, np.asarray(poles), onset + 16, onset)
        est = estimate(cm.SENSORS[None], cm.AXES[None], np.asarray(poles)[None], shapes[None])
        out[name] = ss._vector(est.center_of_gravity[0], est.inertia_per_mass[0])
    sensed = refit_at_truth(records, sensor_bounds=stated_bounds(effects), estimate_sensors=True)
    out["sensors estimated"] = ss._vector(sensed.center_of_gravity, sensed.inertia_per_mass)
    out["floor"] = kernel_figures({"reading": sensors["reading"], "position": sensors["position"]})
    return out


def candidate_table(
    runs: int, r_map: np.ndarray, k_map: np.ndarray, cells: tuple[str, ...] = ("clean", *CELLS)
) -> None:
    """The candidate (LS shapes at the refit's poles, then the kernel) against the refit, run by run.

    Per cell, over `runs` draws: runs within the per-run target (the run's own floor and clean std), the
    RMS of each class's largest error over the refit's, and the largest |error| / the refit's noise std in
    the clean cell. ``mix``: per figure, the minimum-variance combination of refit and candidate, its weight
    from their joint covariance (noise: the clean runs' errors; sensors: the maps ``R``, ``K`` over the cell's
    stated distribution).
    """
    names = ("refit", "candidate", "oracle poles", "mix", "sensors estimated")
    print(f"\ncandidate over {runs} runs per cell (1 % noise; 'all': its four sensor sources, no chain effects)")
    print(f"{'cell':<11} " + " ".join(f"{n + ' pass, RMS CG/J':>28}" for n in names))
    rng = np.random.default_rng(5)
    noise_err: dict[str, np.ndarray] = {}
    if cells[0] != "clean":
        raise SystemExit("--candidate-cells: clean first (the mix's noise covariance comes from its runs)")
    for cell in cells:
        rows = [candidate_run(cell, seed) for seed in range(runs)]
        got = {n: np.array([r[n] for r in rows]) for n in (*names[:3], names[4], "floor", "std")}
        if cell == "clean":
            noise_err = {"refit": got["refit"], "candidate": got["candidate"]}
        s = draws(cell, 20000, rng)
        er, ek = s @ r_map.T, s @ k_map.T
        nr, nk = noise_err["refit"], noise_err["candidate"]
        var_d = np.var(ek - er, axis=0) + np.mean((nk - nr) ** 2, axis=0)
        cov_kd = np.mean(ek * (ek - er), axis=0) + np.mean(nk * (nk - nr), axis=0)
        w = np.clip(cov_kd / var_d, 0.0, 1.0)  # weight of the refit: candidate - w (candidate - refit)
        got["mix"] = got["candidate"] - w * (got["candidate"] - got["refit"])
        se = np.column_stack([got["std"][:, :3].max(axis=1), got["std"][:, 3:].max(axis=1)])
        base = rms(got["refit"]) if cell != "clean" else np.ones(2)
        line = f"{cell:<11} "
        for n in names:
            ok = np.all(per_class(got[n]) <= 1.25 * per_class(got["floor"]) + 6 * se, axis=1)
            ratio = rms(got[n]) / base
            line += f"{int(ok.sum()):>12}/{runs:<3} {ratio[0]:>6.3f}/{ratio[1]:<6.3f}"
        print(line, flush=True)
        if cell == "clean":
            z = {n: np.abs(got[n]) / got["std"] for n in names}
            print("  clean, RMS |error| / refit's noise std per figure (CG x y z, J xx yy zz): "
                  + "; ".join(f"{n} " + " ".join(f"{v:.2f}" for v in np.sqrt(np.mean(z[n] ** 2, axis=0)))
                              for n in names))  # fmt: skip
        else:
            print("  mix weight of the refit per figure: " + " ".join(f"{v:.2f}" for v in w))


def cell_table(r_map: np.ndarray, k_map: np.ndarray, std: np.ndarray, n: int, qp_draws: int) -> None:
    bases = invisible_basis()
    agree = np.linalg.norm((r_map - k_map) @ bases[0].T) / np.linalg.norm(r_map @ bases[0].T)
    print(f"invisible sensor errors: {bases[0].shape[0]} of {6 * N_SENSORS} dimensions; there |R - K| / |R| = "
          f"{agree:.3f} (every consistent estimator agrees there), |R N| / |R| = "
          f"{np.linalg.norm(r_map @ bases[0].T) / np.linalg.norm(r_map):.2f}")  # fmt: skip
    """Per cell: miss rates and RMS (over the refit's) of E_w, the min-variance mix and the QP bound."""
    se = np.array([std[:3].max(), std[3:].max()])
    ws = (1.0, 0.75, 0.5, 0.25, 0.1, 0.0)
    print(f"refit's clean std (1 % noise): CG {se[0]:.4f} % span, J {se[1]:.3f} %;  per-run target: within "
          f"1.25 x floor + 6 std;  {n} draws per cell")  # fmt: skip
    print("pass = fraction of runs within target (20-run expectation in brackets); RMS = the class's RMS largest "
          "error over the refit's (CG/J)")  # fmt: skip
    head = " ".join(f"{'w=' + str(w):>17}" for w in ws)
    print(
        f"{'cell':<11} {'measured':>8} {head} {'min-var mix':>17} "
        f"{'least RMS: any | passing (pass, RMS)':>30} {'viol':>6}"
    )
    rng = np.random.default_rng(23)
    for cell in CELLS:
        s = draws(cell, n, rng)
        noise = std * rng.standard_normal((n, 6))
        er, ek = s @ r_map.T, s @ k_map.T
        base = rms(er)
        cells = []
        for w in ws:
            e = ek + w * (er - ek) + noise
            ok = passes(e, ek, se)
            ratio = rms(e - noise) / base
            cells.append(f"{ok.mean():.2f}({20 * ok.mean():4.1f}) {ratio[0]:.2f}/{ratio[1]:.2f}")
        wmv = min_variance_weights(r_map, k_map, s)
        e = ek + wmv * (er - ek) + noise
        ratio = rms(e - noise) / base
        mix = f"{passes(e, ek, se).mean():.2f} {ratio[0]:.2f}/{ratio[1]:.2f}"
        free, held, viol = qp_bound(r_map, k_map, bases, s[:qp_draws], se)
        ratio, held_ratio = rms(s @ free.T) / base, rms(s @ held.T) / base
        ok = passes(s @ held.T + noise, ek, se).mean()
        qp = f"{ratio[0]:.2f}/{ratio[1]:.2f} {ok:.3f} {held_ratio[0]:.2f}/{held_ratio[1]:.2f}"
        print(f"{cell:<11} {MEASURED[cell]:>5}/20 " + " ".join(f"{c:>17}" for c in cells) + f" {mix:>17} {qp:>30} "
              f"{viol:>6.0e}", flush=True)  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=20000, help="Monte Carlo draws per cell (0: no table)")
    parser.add_argument("--qp-draws", type=int, default=1000)
    parser.add_argument("--cache", type=Path, help="npz of the maps: read if present, else written")
    parser.add_argument("--candidate", type=int, default=0, help="runs per cell of the LS-shapes candidate")
    parser.add_argument("--candidate-cells", default="clean," + ",".join(CELLS))
    parser.add_argument("--clean-default-tolerances", action="store_true", help="the clean cell's 'sensors "
                        "estimated' states the default tolerances")  # fmt: skip
    args = parser.parse_args()
    if args.cache is not None and args.cache.exists():
        saved = np.load(args.cache)
        r_map, k_map, std = saved["r_map"], saved["k_map"], saved["std"]
    else:
        r_map, k_map, std = linear_maps()
        if args.cache is not None:
            np.savez(args.cache, r_map=r_map, k_map=k_map, std=std)
    if args.draws:
        cell_table(r_map, k_map, std, args.draws, args.qp_draws)
    global CLEAN_DEFAULT
    CLEAN_DEFAULT = args.clean_default_tolerances
    if args.candidate:
        candidate_table(args.candidate, r_map, k_map, tuple(args.candidate_cells.split(",")))


if __name__ == "__main__":
    main()
