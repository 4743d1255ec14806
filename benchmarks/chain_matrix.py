"""Impact records through a real acquisition chain: one effect at a time, then all together (issue 23).

Run from the worktree root (a few minutes; each cell runs ``rigidid identify --records`` with defaults)::

    PYTHONPATH=src nice -n 10 python benchmarks/chain_matrix.py [--seeds 3] [--cells clean,clip80,...] [--runs]
        [--floor-draws 200] [--estimate-sensors] [--stated] [--first-seed 0] [--clean-bound]

A cell may combine effects (``--cells sens+orient+skew``) or take some out of ``all`` (``all-position``).

The test, simulated here with a forward model that shares no code with rigidid (6-DOF body on
mounts written afresh, zero-order-hold state transition from scipy.linalg.expm, half-sine hammer):
a 150 kg body on four inclined mounts (six modes 8.8-22.6 Hz, damping 3.9-5.1 %), ten
single-axis accelerometers, three impacts, 2048 Hz, 6 s, 0.25 s pre-trigger, white noise of
1 % of each channel's RMS (rigidid simulate's convention). Effects (each alone, then ``all``):

- ``sens``: sensitivity errors, uniform +-3 %;      ``orient``: direction errors, 2-3 degrees;
- ``transverse``: transverse sensitivity 3 %;        ``position``: positions +-3 mm per axis;
- ``clip80`` / ``clip30``: two channels clipped at 80 % / 30 % of their peak;
- ``double``: a second hit 60 ms after the first, 40 % of its amplitude;
- ``offset``: DC offset 5 % and a linear drift of 2 % of each channel's peak over the record;
- ``skew``: one channel one sample late;             ``ac``: 2 Hz first-order high-pass (AC coupling);
- ``stamps``: time columns starting elsewhere, written with 7 decimals;
- ``aa``: an analog 8th-order Butterworth anti-alias filter at 0.4 fs (its state space discretised with a
  first-order hold, so the samples carry no hold delay); the noise (1 % of the RMS in the filter's band)
  through the filter's magnitude (a bilinear Butterworth, |H|^2 as the analog one's below 0.4 fs);
- ``hum``: a 50 Hz sinusoid of 2 % of each channel's peak, random phase per channel.

``--first-seed N`` starts the seeds at N; ``--default-tolerances`` writes no ``tolerances`` block (rigidid's
defaults then hold: the realistic null of the sensor test on clean records); ``--option OPT`` passes OPT to
``identify`` (e.g. ``--no-estimate-sensors``); ``--plain-bound`` judges the target of runs whose sensors were
estimated against the same records' plain refit's noise std (the clean case's bound). Each run's ``sensor_test``
(its statistic, dof, p-value, whether the sensors were estimated) is printed with ``--runs``, and per cell the
count estimated and of p-values below 0.01, 0.05 and 0.5.

``--paired`` also runs each draw's clean twin (the same noise, no effect) and prints its errors and the
largest ratio of the cell's errors to its twin's (1: the effect costs nothing). ``--metadata`` states the
chain in the layout's ``chain`` block (AC corner, anti-alias filter, the skewed
channel's delay); ``--estimate-delays`` passes that option (the delays then fitted, not stated).

``--first-seed`` starts the seeds there (seeds not developed on). ``--clean-bound`` also runs each draw's clean
twin with defaults and judges the target against its noise std (the clean case's bound, literally) as well as
against the run's own ``sensor_budget.noise`` (which, with ``--estimate-sensors``, holds the noise that the
sensors' correction adds): printed as ``target(clean) N``.

``--state-all-tolerances`` states the ``all`` cell's tolerances (3 %, 3 degrees, 3 %, 3 mm) in every cell's
layout, whatever its sensors' true errors (e.g. exact sensors in ``clean``: what ``--estimate-sensors`` costs there).

``--stated`` draws the orientation and transverse errors from the stated distribution (uniform within the
tolerance: +-3 degrees per normal axis, transverse magnitude up to 3 % in a uniform direction) instead of at
the bound (tilts of 2-3 degrees, transverse exactly 3 %); sensitivity and position draws are the stated
distribution in both.

Printed per cell: runs finished (exit 0) of all; the median and worst CG error (% of the sensor
span, largest coordinate) and inertia error (largest relative error of the diagonal, %); runs
whose refit was accepted; coverage of the reported 95 % intervals (CG and inertia diagonal: the
fraction of the 6 quantities x runs whose interval holds the truth); runs "silently wrong" (exit 0,
no warning, some error beyond 4 reported standard errors); ``target``: runs whose CG and inertia errors are
within 1.25 times the floor plus 6 standard errors of the noise alone (the clean case's bound, the run's own
``sensor_budget.noise``); the layout states the sensor tolerances
the errors were drawn within (zero in the cells without sensor errors). ``floor``: the same errors from the
exact modes read through the same erroneous sensors (``rigidid.api.identify`` on perfect modal
data), the floor the chain's sensor errors leave. With two runs or more, the note adds the cell's RMS error
over the floor's RMS on the same draws (CG, J), the RMS of the z scores (error over the reported std; 1 when
calibrated), and the coverage and RMS z the same runs would have with the modal kernel's type-B std at the
exact modes (``sensor_budget``, what ``plan`` predicts) in place of the reported one.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

MASS = 150.0
CG = np.array([0.04, -0.03, 0.11])
INERTIA = np.array([[9.0, 0.4, -0.3], [0.4, 12.0, 0.5], [-0.3, 0.5, 14.0]])
RATE, DURATION, PRE = 2048.0, 6.0, 0.25
NOISE = 0.01

# four mounts below the body, not symmetric, axes inclined 35 degrees towards the centre (m, N/m)
_MOUNT_XY = np.array([[0.5, 0.3], [-0.35, 0.4], [-0.45, -0.25], [0.3, -0.4]])
_MOUNT_SCALE = (1.6, 0.5, 1.3, 0.6)
_MOUNT_Z = -0.25
_K_AXIAL, _K_SHEAR, _INCLINE = 6e5, 8e4, 35.0

SENSORS = np.array([
    [0.5, 0.4, 0.25], [-0.5, 0.4, 0.25], [-0.5, -0.4, 0.25], [0.5, -0.4, 0.25], [0.5, 0.4, -0.15],
    [-0.5, 0.4, -0.15], [-0.5, -0.4, -0.15], [0.5, -0.4, -0.15], [0.0, 0.4, 0.05], [0.0, -0.4, 0.25],
])  # fmt: skip
AXES = np.array([
    [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 1, 0], [1, 0, 0], [1, 0, 0],
], dtype=float)  # fmt: skip
IMPACTS = [
    ((0.5, 0.4, 0.25), (-0.4, -0.3, -1.0)),
    ((-0.5, -0.1, 0.1), (1.0, 0.5, 0.2)),
    ((0.2, -0.4, 0.0), (0.3, 1.0, -0.4)),
]
CELLS = ["clean", "sens", "orient", "transverse", "position", "clip80", "clip30", "double", "offset", "skew", "ac",
         "stamps", "aa", "hum", "all"]  # fmt: skip
AA_ORDER, AA_CORNER = 8, 0.4 * RATE
HP_CORNER = 2.0
SKEWED = 4  # the channel one sample late
SENSOR_EFFECTS = {"sens", "orient", "transverse", "position"}
ALL_TOLERANCES = False
"""``--state-all-tolerances``: every layout states the ``all`` cell's tolerances."""
PLAIN_BOUND = False
"""``--plain-bound``: where the sensors were estimated, the target's noise std is the same records' plain refit's
(``--no-estimate-sensors``), the clean case's bound, rather than the corrected answer's own (which includes the
correction's noise); ``target`` counts the runs within it."""
STATED_DRAWS = False
"""``--stated``: orientation and transverse errors drawn from the stated distribution (uniform within the
tolerance) rather than at its bound (tilts of 2-3 degrees, transverse sensitivity exactly 3 %)."""


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _point(r: np.ndarray) -> np.ndarray:
    """Motion of a point at `r` (from the CG) from the body's 6 coordinates: u + theta x r."""
    return np.hstack([np.eye(3), -_skew(r)])


def _mount_matrices() -> tuple[np.ndarray, np.ndarray]:
    k6, c6 = np.zeros((6, 6)), np.zeros((6, 6))
    for (x, y), factor in zip(_MOUNT_XY, _MOUNT_SCALE, strict=True):
        axis = np.array([-x, -y, 0.0]) * np.tan(np.radians(_INCLINE)) / np.hypot(x, y) + [0, 0, 1]
        axis /= np.linalg.norm(axis)
        k3 = factor * (_K_SHEAR * np.eye(3) + (_K_AXIAL - _K_SHEAR) * np.outer(axis, axis))
        t = _point(np.array([x, y, _MOUNT_Z]) - CG)
        k6 += t.T @ k3 @ t
    m6 = np.diag([MASS] * 3 + [0.0] * 3)
    m6[3:, 3:] = INERTIA
    # damping 4-6 % by a mix of mass- and stiffness-proportional parts
    c6 = 2.5 * m6 + 6e-4 * k6
    return k6, c6


K6, C6 = _mount_matrices()
M6 = np.diag([MASS] * 3 + [0.0] * 3)
M6[3:, 3:] = INERTIA


def modes() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frequencies (Hz), damping ratios and poles of the truth."""
    a = np.block([[np.zeros((6, 6)), np.eye(6)], [-np.linalg.solve(M6, K6), -np.linalg.solve(M6, C6)]])
    lam, vec = np.linalg.eig(a)
    up = lam.imag > 0
    lam, vec = lam[up], vec[:, up]
    order = np.argsort(np.abs(lam))
    lam, vec = lam[order], vec[:, order]
    return np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam), np.asarray(vec[:6])  # displacement shapes


def sensor_errors(effects: set[str], rng: np.random.Generator) -> dict[str, np.ndarray]:
    """The true sensors given the stated ones: gains, directions (with transverse part) and positions."""
    n = SENSORS.shape[0]
    gain = 1.0 + (rng.uniform(-0.03, 0.03, n) if "sens" in effects else np.zeros(n))
    axes = AXES.copy()
    if "orient" in effects and STATED_DRAWS:  # the stated distribution: uniform +-3 degrees per normal axis
        e1, e2 = _normals()
        tilt = np.radians(rng.uniform(-3.0, 3.0, (n, 2)))
        axes = AXES + tilt[:, :1] * e1 + tilt[:, 1:] * e2
        axes /= np.linalg.norm(axes, axis=1)[:, None]
    elif "orient" in effects:
        tilt = np.radians(rng.uniform(2.0, 3.0, n))
        for i in range(n):
            perp = np.cross(AXES[i], rng.standard_normal(3))
            perp /= np.linalg.norm(perp)
            axes[i] = np.cos(tilt[i]) * AXES[i] + np.sin(tilt[i]) * perp
    reading = axes.copy()
    if "transverse" in effects and STATED_DRAWS:  # stated: magnitude uniform up to 3 %, direction uniform
        e1, e2 = _normals()
        tau, phase = rng.uniform(0.0, 0.03, (n, 1)), rng.uniform(0.0, 2 * np.pi, (n, 1))
        reading = axes + tau * (np.cos(phase) * e1 + np.sin(phase) * e2)
    elif "transverse" in effects:
        for i in range(n):
            perp = np.cross(AXES[i], rng.standard_normal(3))
            reading[i] = axes[i] + 0.03 * perp / np.linalg.norm(perp)
    pos = SENSORS + (rng.uniform(-0.003, 0.003, SENSORS.shape) if "position" in effects else 0.0)
    return {"gain": gain, "reading": reading * gain[:, None], "position": pos}


def _normals() -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors normal to each stated axis and to each other."""
    helper = np.where(np.abs(AXES[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(AXES, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return e1, np.cross(AXES, e1)


def simulate(effects: set[str], rng: np.random.Generator, sensors: dict[str, np.ndarray]) -> list[np.ndarray]:
    """Records (samples x sensors, accelerations as the chain delivers them), one per impact."""
    from scipy.linalg import expm

    dt = 1.0 / RATE
    a = np.block([[np.zeros((6, 6)), np.eye(6)], [-np.linalg.solve(M6, K6), -np.linalg.solve(M6, C6)]])
    big = expm(np.block([[a, np.eye(12)], [np.zeros((12, 24))]]) * dt)
    phi, gamma = big[:12, :12], big[:12, 12:]
    out_map = np.array([r @ _point(p - CG) for r, p in zip(sensors["reading"], sensors["position"], strict=True)])
    n = int(DURATION * RATE)
    t = np.arange(n) * dt
    records = []
    for k, (where, direction) in enumerate(IMPACTS):
        d = np.asarray(direction, float) / np.linalg.norm(direction)
        gen = _point(np.asarray(where) - CG).T @ d  # generalised force per newton
        force = 500.0 * _pulse(t - PRE, 0.003)
        if "double" in effects:
            force += 200.0 * _pulse(t - PRE - 0.06 - 0.01 * k, 0.003)
        b = np.concatenate([np.zeros(6), np.linalg.solve(M6, gen)])
        x = np.zeros(12)
        acc = np.empty((n, out_map.shape[0]))
        minv_k, minv_c = np.linalg.solve(M6, K6), np.linalg.solve(M6, C6)
        for i in range(n):
            qdd = -minv_k @ x[:6] - minv_c @ x[6:] + b[6:] * force[i]
            acc[i] = out_map @ qdd
            x = phi @ x + gamma @ (b * force[i])
        records.append(_chain(acc, effects, rng, t))
    return records


def _pulse(t: np.ndarray, width: float) -> np.ndarray:
    return np.where((t >= 0) & (t < width), np.sin(np.pi * np.clip(t, 0, width) / width), 0.0)


def _chain(acc: np.ndarray, effects: set[str], rng: np.random.Generator, t: np.ndarray) -> np.ndarray:
    peak = np.abs(acc).max(axis=0)
    rms = np.sqrt(np.mean(acc**2, axis=0))
    noise = NOISE * rms * rng.standard_normal(acc.shape)
    if "aa" in effects:  # the sensor's noise through the filter too (its spectrum |H|^2 of the analog filter)
        from scipy.signal import butter, sosfilt

        sos = butter(AA_ORDER, AA_CORNER, fs=RATE, output="sos")
        lead = NOISE * rms * rng.standard_normal((256, acc.shape[1]))  # the filter's start-up outside the record
        noise = sosfilt(sos, np.vstack([lead, noise]), axis=0)[256:] / np.sqrt(np.mean(np.abs(_gain(sos)) ** 2))
        acc = _antialias(acc)
    y = acc + noise
    if "ac" in effects:
        from scipy.signal import bilinear, lfilter

        b, a = bilinear([1.0, 0.0], [1.0, 2 * np.pi * 2.0], RATE)
        y = lfilter(b, a, y, axis=0)
    if "skew" in effects:
        y[1:, SKEWED] = y[:-1, SKEWED].copy()
    if "hum" in effects:
        phase = rng.uniform(0.0, 2 * np.pi, acc.shape[1])
        y = y + 0.02 * peak * np.sin(2 * np.pi * 50.0 * t[:, None] + phase)
    if "offset" in effects:
        y = y + peak * (0.05 + 0.02 * t[:, None] / t[-1])
    for level, cols in (("clip80", (2, 7)), ("clip30", (2, 7))):
        if level in effects:
            frac = 0.8 if level == "clip80" else 0.3
            for c in cols:
                lim = frac * peak[c]
                y[:, c] = np.clip(y[:, c], -lim, lim)
    return y


def _gain(sos: np.ndarray) -> np.ndarray:
    """The digital filter's response on a fine grid (its mean square: the filtered white noise's variance)."""
    from scipy.signal import sosfreqz

    return np.asarray(sosfreqz(sos, worN=8192)[1])


def _antialias(y: np.ndarray) -> np.ndarray:
    """The analog Butterworth anti-alias filter, exact for signals linear between samples (first-order hold)."""
    from scipy.signal import butter, cont2discrete, dlsim, zpk2ss

    a, b, c, d = zpk2ss(*butter(AA_ORDER, 2 * np.pi * AA_CORNER, analog=True, output="zpk"))
    ad, bd, cd, dd, _ = cont2discrete((a, b, c, d), 1.0 / RATE, method="foh")
    return np.column_stack([dlsim((ad, bd, cd, dd, 1.0 / RATE), y[:, i])[1][:, 0] for i in range(y.shape[1])])


def stated_chain(effects: set[str]) -> dict[str, object] | None:
    """The layout's ``chain`` block stating the simulated chain (None when there is none to state)."""
    block: dict[str, object] = {}
    if "ac" in effects:
        block["highpass_hz"] = HP_CORNER
    if "aa" in effects:
        block["antialias"] = {"type": "butterworth", "order": AA_ORDER, "corner_hz": AA_CORNER}
    if "skew" in effects:
        block["sensors"] = {f"s{SKEWED + 1}": {"delay_s": 1.0 / RATE}}
    return block or None


def stated_tolerances(effects: set[str]) -> dict[str, float]:
    """The layout's tolerances: the bounds the simulated sensor errors were drawn within (zero without them)."""
    return {
        "sensitivity": 0.03 if "sens" in effects else 0.0,
        "orientation_deg": 3.0 if "orient" in effects else 0.0,
        "transverse": 0.03 if "transverse" in effects else 0.0,
        "position": 0.003 if "position" in effects else 0.0,
    }


def write_case(
    folder: Path,
    records: list[np.ndarray],
    stamps: bool,
    tolerances: dict[str, float] | None = None,
    chain: dict[str, object] | None = None,
) -> list[Path]:
    layout: dict[str, object] = {
        "name": "150 kg body, ten single-axis accelerometers (chain_matrix benchmark)",
        "units": {"length": "m", "mass": "kg"},
        "mass": MASS,
        "sensors": [
            {"id": f"s{i + 1}", "position": SENSORS[i].tolist(), "direction": AXES[i].tolist()}
            for i in range(SENSORS.shape[0])
        ],
    }
    if tolerances is not None:
        layout["tolerances"] = tolerances
    if chain is not None:
        layout["chain"] = chain
    (folder / "layout.json").write_text(json.dumps(layout))
    paths = []
    header = "time," + ",".join(f"s{i + 1}" for i in range(SENSORS.shape[0]))
    for k, rec in enumerate(records):
        n = rec.shape[0]
        if stamps:
            start = [0.0, 101.00000004321, 12.34567891234][k % 3]
            time_col = np.array([float(f"{v:.7f}") for v in start + np.arange(n) / RATE])
        else:
            time_col = np.arange(n) / RATE
        path = folder / f"record-{k + 1}.csv"
        fmt = ["%.7f" if stamps else "%.10g"] + ["%.8g"] * rec.shape[1]
        np.savetxt(path, np.column_stack([time_col, rec]), delimiter=",", header=header, comments="", fmt=fmt)
        paths.append(path)
    return paths


def errors(cg: np.ndarray, inertia: np.ndarray) -> tuple[float, float]:
    span = float(np.max(np.ptp(SENSORS, axis=0)))
    cg_err = 100 * float(np.max(np.abs(cg - CG))) / span
    j_err = 100 * float(np.max(np.abs(np.diag(inertia) - np.diag(INERTIA)) / np.diag(INERTIA)))
    return cg_err, j_err


def floor(sensors: dict[str, np.ndarray]) -> tuple[float, float]:
    """Errors of the identification kernel on the exact modes read through the erroneous sensors."""
    from rigidid.core.estimator import estimate

    freq, zeta, q = modes()
    lam = -zeta * 2 * np.pi * freq + 1j * 2 * np.pi * freq * np.sqrt(1 - zeta**2)
    read = np.array([r @ _point(p - CG) for r, p in zip(sensors["reading"], sensors["position"], strict=True)])
    est = estimate(SENSORS[None], AXES[None], lam[None], (read @ q)[None])
    return errors(est.center_of_gravity[0], MASS * est.inertia_per_mass[0])


def kernel_budget(effects: set[str]) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's type-B std of the CG and the inertia diagonal at the exact modes, the cell's stated bounds."""
    from rigidid.core.sensor_budget import SensorBounds, sensor_budget

    freq, zeta, q = modes()
    lam = -zeta * 2 * np.pi * freq + 1j * 2 * np.pi * freq * np.sqrt(1 - zeta**2)
    shapes = np.array([r @ _point(p - CG) for r, p in zip(AXES, SENSORS, strict=True)]) @ q
    budget = sensor_budget(SENSORS, AXES, lam, shapes, SensorBounds(**stated_tolerances(effects)))
    return budget.total["center_of_gravity"], MASS * np.diag(budget.total["inertia_per_mass"])


def floor_coverage(effect: str, draws: int, seed: int = 0) -> tuple[float, float, float]:
    """Coverage of the type-B intervals on perfect modal data when the stated bounds are the true ones.

    Sensor errors drawn from rectangular distributions of the bounds (sensitivity 3 %, orientation
    3 degrees per normal axis, transverse 3 % in a uniform direction, position 3 mm per axis), the exact
    modes read through them, the body identified by the kernel with the stated layout; the budget of
    :func:`rigidid.core.sensor_budget.sensor_budget` at the measured modes gives +-1.96 std intervals.
    Returns the coverage (CG and inertia diagonal), the median |error| / std, the median inertia error (%).
    """
    from rigidid.core.estimator import estimate
    from rigidid.core.sensor_budget import SensorBounds, sensor_budget

    bounds = SensorBounds(
        sensitivity=0.03 if effect in ("sens", "all") else 0.0,
        orientation_deg=3.0 if effect in ("orient", "all") else 0.0,
        transverse=0.03 if effect in ("transverse", "all") else 0.0,
        position=0.003 if effect in ("position", "all") else 0.0,
    )
    rng = np.random.default_rng(seed)
    freq, zeta, q = modes()
    lam = -zeta * 2 * np.pi * freq + 1j * 2 * np.pi * freq * np.sqrt(1 - zeta**2)
    hits, ratios, j_errs = [], [], []
    n = SENSORS.shape[0]
    helper = np.where(np.abs(AXES[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(AXES, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(AXES, e1)
    for _ in range(draws):
        a = np.radians(bounds.orientation_deg)
        axes = AXES + rng.uniform(-a, a, (n, 1)) * e1 + rng.uniform(-a, a, (n, 1)) * e2
        phase = rng.uniform(0, 2 * np.pi, (n, 1))
        tau = rng.uniform(0, bounds.transverse, (n, 1))
        reading = axes + tau * (np.cos(phase) * e1 + np.sin(phase) * e2)
        reading *= (1 + rng.uniform(-bounds.sensitivity, bounds.sensitivity, n))[:, None]
        pos = SENSORS + rng.uniform(-bounds.position, bounds.position, (n, 3))
        shapes = np.array([r @ _point(p - CG) for r, p in zip(reading, pos, strict=True)]) @ q
        est = estimate(SENSORS[None], AXES[None], lam[None], shapes[None])
        budget = sensor_budget(SENSORS, AXES, lam, shapes, bounds)
        err = np.concatenate([est.center_of_gravity[0] - CG, np.diag(est.inertia_per_mass[0] - INERTIA / MASS)])
        std = np.concatenate([budget.total["center_of_gravity"], np.diag(budget.total["inertia_per_mass"])])
        z = np.abs(err) / std
        hits.append(z <= 1.959964)
        ratios.append(np.median(z))
        j_errs.append(100 * np.max(np.abs(err[3:]) / np.diag(INERTIA / MASS)))
    return float(np.mean(hits)), float(np.median(ratios)), float(np.median(j_errs))


def cell_effects(cell: str) -> set[str]:
    """A cell's effects: one of :data:`CELLS`; a combination ``sens+orient+skew``; or ``all`` less some,
    ``all-position-hum`` (a combination draws its noise as ``all`` does, from the seed)."""
    every = set(CELLS[1:-1]) - {"clip30"}
    if cell.startswith("all"):
        return every - set(cell.split("-")[1:])
    parts = set(cell.split("+"))
    unknown = parts - set(CELLS)
    if unknown:
        raise SystemExit(f"chain_matrix: unknown effect(s) {sorted(unknown)} in cell {cell!r}")
    return parts


def run_cell(
    cell: str,
    seed: int,
    metadata: bool = False,
    estimate_delays: bool = False,
    twin: bool = False,
    options: tuple[str, ...] = (),
    default_tolerances: bool = False,
) -> dict[str, object]:
    """One run of `cell`; `twin`: the same draw (the same noise) with no effect at all, the cell's clean twin.

    `options`: more options of ``rigidid identify`` (e.g. ``--estimate-sensors``); `default_tolerances`: the
    layout states no tolerances (rigidid's defaults then hold) rather than the cell's."""
    effects = set() if twin else cell_effects(cell)
    rng = np.random.default_rng(1000 * seed + CELLS.index(cell if cell in CELLS else "all"))
    sensors = sensor_errors(effects, rng)
    records = simulate(effects, rng, sensors)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        chain = stated_chain(effects) if metadata else None
        told = (
            None
            if default_tolerances
            else stated_tolerances(SENSOR_EFFECTS if ALL_TOLERANCES and not twin else effects)
        )
        paths = write_case(folder, records, "stamps" in effects, told, chain)
        env = dict(os.environ)
        extra = ["--estimate-delays"] if estimate_delays else []
        extra += list(options)
        command = [sys.executable, "-m", "rigidid", "identify", str(folder / "layout.json"), "--records",
                   *map(str, paths), "--mass", str(MASS), "--json", "-"]  # fmt: skip
        out = subprocess.run([*command, *extra], capture_output=True, text=True, env=env, check=False)
        plain = None
        if PLAIN_BOUND and out.returncode == 0 and '"sensors_estimated": true' in out.stdout:
            # the clean case's bound: the same records' plain refit (the sensors not estimated), its noise std
            again = subprocess.run([*command, "--no-estimate-sensors"], capture_output=True, text=True, env=env,
                                   check=False)  # fmt: skip
            crb_plain = json.loads(again.stdout).get("uncertainty_records_crb") if again.returncode == 0 else None
            plain = ((crb_plain or {}).get("sensor_budget") or {}).get("noise")  # None: no plain refit kept
    row: dict[str, object] = {"cell": cell, "seed": seed, "exit": out.returncode, "floor": floor(sensors)}
    warned = [line for line in out.stderr.splitlines() if "warning" in line]
    row["warnings"] = warned
    if out.returncode != 0:
        row["error"] = out.stderr.strip().splitlines()[-1] if out.stderr.strip() else ""
        return row
    data = json.loads(out.stdout)
    cg, inertia = np.array(data["center_of_gravity"]), np.array(data["inertia_tensor"])
    row["errors"] = errors(cg, inertia)
    crb = data.get("uncertainty_records_crb")
    row["refit"] = crb is not None
    if crb is not None:
        cg_sd = np.array(crb["center_of_gravity"]["std"])
        j_sd = np.diag(np.array(crb["inertia_tensor"]["std"]))
        z = np.concatenate([(cg - CG) / cg_sd, (np.diag(inertia) - np.diag(INERTIA)) / j_sd])
        row["covered"] = int(np.sum(np.abs(z) <= 1.959964))
        row["z"] = z
        budget = crb.get("sensor_budget")
        if budget is not None:  # the alternative: the kernel's type-B std at the exact modes (what plan predicts)
            kcg, kj = kernel_budget(effects)
            ncg = np.array(budget["noise"]["center_of_gravity"])
            nj = np.diag(np.array(budget["noise"]["inertia_tensor"]))
            z_k = np.concatenate([(cg - CG) / np.hypot(ncg, kcg),
                                  (np.diag(inertia) - np.diag(INERTIA)) / np.hypot(nj, kj)])  # fmt: skip
            row["covered_kernel"] = int(np.sum(np.abs(z_k) <= 1.959964))
            row["z_kernel"] = z_k
        row["silent"] = bool(np.max(np.abs(z)) > 4 and not warned)
        row["sensor_test"] = crb.get("sensor_test")
        row["ac_coupling"] = crb.get("ac_coupling")
        noise = (crb.get("sensor_budget") or {}).get("noise")
        if noise is not None:  # the target: within 1.25 x the floor plus 6 of the noise's (clean bound's) std
            row["target"] = _within(row, noise)
            row["noise_se"] = _noise_se(noise)
            row["target_plain"] = row["target"] if plain is None else _within(row, plain)
            row["plain_kept"] = plain is not None or not PLAIN_BOUND or '"sensors_estimated": true' not in out.stdout
    return row


def _noise_se(noise: dict[str, list[float]]) -> tuple[float, float]:
    """A sensor_budget entry's largest CG std (% of span) and inertia diagonal std (% of the truth's)."""
    span = float(np.max(np.ptp(SENSORS, axis=0)))
    return (100 * float(np.max(noise["center_of_gravity"])) / span,
            100 * float(np.max(np.diag(np.array(noise["inertia_tensor"])) / np.diag(INERTIA))))  # fmt: skip


def _within(row: dict[str, object], noise: dict[str, list[float]]) -> bool:
    """Whether the run's errors are within 1.25 x the floor plus 6 of `noise`'s std (a sensor_budget entry)."""
    se = _noise_se(noise)
    return all(e <= 1.25 * f + 6 * u for e, f, u in zip(row["errors"], row["floor"], se, strict=True))  # type: ignore[call-overload]


def clean_target(row: dict[str, object], twin: dict[str, object]) -> bool:
    """Whether `row`'s errors are within 1.25 times its floor plus 6 of its clean twin's noise std (CG, J)."""
    if row["exit"] != 0 or "noise_se" not in twin or "errors" not in row:
        return False
    return all(e <= 1.25 * f + 6 * u for e, f, u in zip(row["errors"], row["floor"], twin["noise_se"], strict=True))  # type: ignore[call-overload]


def _coupling_text(found: object) -> str:
    """A run's unstated AC coupling test (``ac_coupling``): its corner, p-value and whether it was modelled."""
    if not isinstance(found, dict):
        return ""
    return (f" ac corner {found['corner_hz']:.3g} Hz (std {found['corner_std_hz']}) p {found['p_value']:.2g} "
            f"interior {found.get('interior')} modelled {found['modelled']}")  # fmt: skip


def _print_sensor_tests(rows: list[dict[str, object]]) -> None:
    """The sensor test over the cell's runs: how many estimated the sensors, and the p-values' spread."""
    tests = [r["sensor_test"] for r in rows if r.get("sensor_test")]
    if not tests:
        return
    p = np.array([t["p_value"] for t in tests])  # type: ignore[index]
    est = sum(bool(t["sensors_estimated"]) for t in tests)  # type: ignore[index]
    print(f"    sensor test: {len(tests)} runs, estimated {est}, p < 0.01: {np.sum(p < 0.01)}, p < 0.05: "
          f"{np.sum(p < 0.05)}, p < 0.5: {np.sum(p < 0.5)}, mean T/dof "
          f"{np.mean([t['statistic'] / max(t['dof'], 1) for t in tests]):.2f}, KS of the p-values against uniform "
          f"{_ks_uniform(p):.2f}", flush=True)  # type: ignore[index]  # fmt: skip


def _ks_uniform(p: np.ndarray) -> float:
    """The Kolmogorov-Smirnov test's p-value of `p` against the uniform law (the sensor test's null)."""
    from scipy.stats import kstest

    return float(kstest(p, "uniform").pvalue)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--first-seed", type=int, default=0, help="the first seed (seeds FIRST .. FIRST + SEEDS - 1)")
    parser.add_argument("--cells", default=",".join(CELLS))
    parser.add_argument("--floor-draws", type=int, default=200, help="draws of the type-B coverage table (0: none)")
    parser.add_argument("--metadata", action="store_true", help="state the chain in the layout's chain block")
    parser.add_argument("--estimate-delays", action="store_true", help="pass --estimate-delays")
    parser.add_argument("--paired", action="store_true", help="also run each draw's clean twin (same noise)")
    parser.add_argument("--runs", action="store_true", help="print each run's errors, floor and noise std")
    parser.add_argument("--estimate-sensors", action="store_true", help="run identify with --estimate-sensors")
    parser.add_argument("--state-all-tolerances", action="store_true", help="state the all cell's tolerances in "
                        "every cell")  # fmt: skip
    parser.add_argument("--clean-bound", action="store_true", help="also judge the target on the clean twin's "
                        "noise std")  # fmt: skip
    parser.add_argument("--default-tolerances", action="store_true",
                        help="the layout states no tolerances (rigidid's defaults)")  # fmt: skip
    parser.add_argument("--plain-bound", action="store_true", help="target against the plain refit's noise std")
    parser.add_argument("--option", action="append", default=[], help="an option for identify (repeatable)")
    parser.add_argument("--stated", action="store_true", help="draw orientation and transverse errors from the "
                        "stated distribution (uniform within the tolerance), not at its bound")  # fmt: skip
    args = parser.parse_args()
    global STATED_DRAWS, ALL_TOLERANCES, PLAIN_BOUND
    STATED_DRAWS, ALL_TOLERANCES, PLAIN_BOUND = args.stated, args.state_all_tolerances, args.plain_bound
    if args.floor_draws:
        print(f"type-B intervals on perfect modal data, stated bounds true ({args.floor_draws} draws):")
        print(f"{'effect':<11} {'coverage':>8} {'median |err|/std':>16} {'median J err %':>14}")
        for effect in ("sens", "orient", "transverse", "position", "all"):
            cover, ratio, j_err = floor_coverage(effect, args.floor_draws)
            print(f"{effect:<11} {cover:>8.3f} {ratio:>16.2f} {j_err:>14.2f}", flush=True)
    freq, zeta, _ = modes()
    print("truth: modes " + " ".join(f"{f:.2f}" for f in freq) + " Hz, damping "
          + " ".join(f"{100 * z:.1f}" for z in zeta) + " %")  # fmt: skip
    print(f"{'cell':<11} {'finished':>8} {'CG % span med/max':>18} {'J % med/max':>13} {'floor CG/J':>12} "
          f"{'refit':>5} {'cover':>6} {'silent':>6} {'target':>6}  first warning or error")  # fmt: skip
    for cell in args.cells.split(","):
        sensors_option = (("--estimate-sensors",) if args.estimate_sensors else ()) + tuple(args.option)
        rows, clean = [], []
        for s in range(args.first_seed, args.first_seed + args.seeds):  # each run printed as it ends
            r = run_cell(cell, s, args.metadata, args.estimate_delays, options=sensors_option,
                         default_tolerances=args.default_tolerances)  # fmt: skip
            rows.append(r)
            if args.clean_bound:
                twin = run_cell(cell, s, twin=True)
                clean.append(clean_target(r, twin))
                r["twin_se"] = twin.get("noise_se")
            if args.runs:
                test = r.get("sensor_test") or {}
                print(f"    seed {r['seed']}: exit {r['exit']} errors {r.get('errors')} floor {r['floor']} "
                      f"covered {r.get('covered')}/6 target {r.get('target')}/{r.get('target_plain')} "
                      f"plain kept {r.get('plain_kept')} noise se {r.get('noise_se')} "
                      f"z {np.round(r['z'], 2).tolist() if 'z' in r else None} sensor test T {test.get('statistic')} "
                      f"dof {test.get('dof')} p {test.get('p_value')} estimated {test.get('sensors_estimated')} "
                      f"p after {test.get('correction_misfit_p_value')}" + _coupling_text(r.get("ac_coupling"))
                      + (f" target(clean) {clean[-1]} clean se {r.get('twin_se')}" if clean else ""), flush=True)  # type: ignore[union-attr]  # fmt: skip
        _print_sensor_tests(rows)
        found = [r["ac_coupling"] for r in rows if isinstance(r.get("ac_coupling"), dict)]
        if found:
            print(f"    ac coupling test: {len(found)} runs, flagged "
                  f"{sum(f['p_value'] < f['false_alarm_rate'] and f.get('interior', True) for f in found)}, "  # type: ignore[index, union-attr]
                  f"modelled "
                  f"{sum(bool(f['modelled']) for f in found)}", flush=True)  # type: ignore[index]  # fmt: skip
        done = [r for r in rows if r["exit"] == 0]
        errs = np.array([r["errors"] for r in done]) if done else np.full((1, 2), np.nan)
        fl = np.array([r["floor"] for r in rows])
        fitted = [r for r in done if r.get("refit")]
        cover = sum(int(r["covered"]) for r in fitted) / (6 * len(fitted)) if fitted else float("nan")  # type: ignore[call-overload]
        silent = sum(bool(r.get("silent")) for r in done)
        met = sum(bool(r.get("target_plain" if PLAIN_BOUND else "target")) for r in done)
        note = next((str(r.get("error") or (r["warnings"][0] if r["warnings"] else "")) for r in rows  # type: ignore[index]
                     if r.get("error") or r["warnings"]), "")  # fmt: skip
        note = note.replace("rigidid: ", "")[:110]
        if clean:
            note = f"target(clean) {sum(clean)}  " + note
        if args.paired:
            twins = [run_cell(cell, s, twin=True) for s in range(args.first_seed, args.first_seed + args.seeds)]
            ratio = [np.array(r["errors"]) / np.array(t["errors"]) for r, t in zip(rows, twins, strict=True)
                     if r["exit"] == 0 and t["exit"] == 0]  # fmt: skip
            twin_errs = np.array([t["errors"] for t in twins if t["exit"] == 0])
            top = np.max(ratio, axis=0)
            note = (f"clean twin CG/J med {np.median(twin_errs[:, 0]):.3f}/{np.median(twin_errs[:, 1]):.2f}, "
                    f"cell/twin max {top[0]:.2f}/{top[1]:.2f}  " + note)[:150]  # fmt: skip
        med, worst = np.median(errs, axis=0), np.max(errs, axis=0)
        if len(done) > 1 and np.all(fl > 0):  # the cell's RMS error against the floor's over the same draws
            rms = np.sqrt(np.mean(errs**2, axis=0)) / np.sqrt(np.mean(fl[[r["exit"] == 0 for r in rows]] ** 2, axis=0))
            z_all = np.concatenate([r["z"] for r in fitted]) if fitted else np.zeros(0)
            zk = [r for r in fitted if "z_kernel" in r]
            z_k = np.concatenate([r["z_kernel"] for r in zk]) if zk else np.full(1, np.nan)
            cover_k = sum(int(r["covered_kernel"]) for r in zk) / (6 * len(zk)) if zk else float("nan")
            note = (f"RMS err/floor CG {rms[0]:.2f} J {rms[1]:.2f}, RMS z {np.sqrt(np.mean(z_all**2)):.2f}; "
                    f"kernel budget: cover {cover_k:.2f} RMS z {np.sqrt(np.mean(z_k**2)):.2f}  "
                    + note)[:170]  # fmt: skip
        print(f"{cell:<11} {len(done):>4}/{len(rows):<3} {med[0]:>8.3f}/{worst[0]:<8.3f} "
              f"{med[1]:>6.2f}/{worst[1]:<6.2f} "
              f"{np.max(fl[:, 0]):>5.2f}/{np.max(fl[:, 1]):<5.2f} {len(fitted):>5} {cover:>6.2f} {silent:>6} "
              f"{met:>6}  {note}",
              flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
