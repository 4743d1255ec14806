"""Wall time and peak memory of modal estimation from an impact record (not a test; prints a table).

Each case writes one simulated record (8 or 32 channels, 10^4 to 10^6
samples, 20 s long, so 500 Hz to 50 kHz; 1 % noise, 0.1 s pre-trigger) as
CSV to a temporary folder, then times in a fresh subprocess ``read_record``
plus ``estimate_modes`` with the default method, and, in another subprocess,
the same read plus a plain numpy textbook ERA (block Hankel matrices ``H0``,
``H1`` of the undecimated record formed in full, 20 block rows, economy SVD of
``H0``, ``A = S^-1/2 U^T H1 V S^-1/2``). Peak memory is the subprocess's peak
resident set size (``ru_maxrss``) less its size after imports; the record
itself (samples x channels x 8 bytes) is part of it; on Linux the peak is reset
after the imports (``/proc/self/clear_refs``). The baseline is skipped
when it would need more than 4 GB (about five times ``H0``: ``H0``, ``H1``,
``V`` and the SVD workspace; measured 6.2 GB for 8 channels x 10^6 samples).
"err" is the largest relative frequency error of the six modes (for the
baseline, of the pole nearest each true mode).

Run: ``python benchmarks/modes_speed.py [--cases 8x10000,32x1000000] [--method era]``

``--floor [CHANNELSxSAMPLES,...]`` (default 32x1000000) instead times, per case, the whole
command ``rigidid modes LAYOUT RECORD -o modes.csv`` on the record written as CSV, ``.npy``
and ``.npz``, against a plain numpy floor run in the same way (a fresh Python that reads the
CSV with ``pandas.read_csv`` or the ``.npy`` with ``numpy.load``, decimates with the
FIR of scipy's ``decimate`` (polyphase numpy, frozen in this script) by
``decimation_for(40 Hz)``, projects onto the 12 leading principal directions, forms the
Gram matrix with ``lagged_gram`` (20 block rows) and
realises 12 states with ``era_basis``/``era_modes``) and against pyOMA2's SSI-cov
(``pyoma-2`` from PyPI, in its own virtual environment ``.pyoma-venv`` at the repository
root, never a project dependency: the same pandas/numpy read, ``decimate_data`` with the
floor's factor and scipy's FIR, 20 block rows, orders up to 24). Contenders run
interleaved, ``--repeat`` times (3); it prints medians of wall time (start-up included) and
of peak resident memory (the child's own ``VmHWM``, written at exit), their ratios to the
CSV floor, the estimation alone on the loaded record, whether the CSV, ``.npy`` and
``.npz`` modes agree to 1e-9, the load average (the machine is shared: ratios measured in
one run are the figures to compare) and how the CSV peak grows with the rows.
``--keep DIR`` writes the records there once and reuses them.

The estimation alone (record loaded from ``.npy``, no reading; in each fresh process a
warm call, then the best of three calls; the median over processes) is reported
against the floor's own steps (FIR decimation to the factor a 40 Hz band gives, 12
principal directions, Gram matrix of 20 block rows, ERA at 12 states: it is told the
band and fits the record from row 0) with three FIR decimations: scipy's
``decimate(ftype="fir")``, what a plain script calls and what the issue's floor
measured (0.42 s there); the floor's numpy polyphase FIR, frozen in this script at last
stop's rigidid ``decimate`` (the end-to-end floor uses it too); and rigidid's current
``decimate``. Then against the frozen floor plus the two steps rigidid cannot be
spared, done plainly in numpy (impact as the first sample above 1 % of the peak of the
summed squares; a Welch spectrum of 2^18 rows after it, no overlap): the like-for-like
ratio. ``estimate_modes`` also sweeps 24
model orders and stabilises them, which neither reference does. Both are printed twice:
with the BLAS threads the environment gives, and with ``OPENBLAS_NUM_THREADS=1`` for
floor and rigidid alike (on a shared 2-core machine threaded BLAS makes the many small
products of the sweep erratic).

Run: ``python benchmarks/modes_speed.py --floor 32x1000000,8x1000000,8x10000000 --keep /tmp/cases``
"""

from __future__ import annotations

import argparse
import contextlib
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

DURATION = 20.0
BLOCK_ROWS = 20
BASELINE_LIMIT = 4e9
DEFAULT_CASES = [(c, n) for c in (8, 32) for n in (10_000, 100_000, 1_000_000)]


def _status_mb(field: str) -> float:
    """A memory figure of this process from /proc/self/status (MB), or the rusage peak."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _reset_peak() -> None:
    """Reset the peak resident set size (Linux: write 5 to /proc/self/clear_refs)."""
    with contextlib.suppress(OSError):
        Path("/proc/self/clear_refs").write_text("5")


def _true_frequencies(channels: int) -> np.ndarray:
    from records_scenario import BODY, layout
    from rigidid.core.simulate import body_modes
    from rigidid.core.statespace import modal_from_poles

    pos, dirs = layout(channels)
    return modal_from_poles(body_modes(BODY, pos, dirs).poles)[0]


def _child(kind: str, path: str, channels: int, method: str) -> None:
    """Run one measurement and print a JSON line (in a subprocess)."""
    from rigidid.core.timedomain import estimate_modes
    from rigidid.io.records import read_record

    ids = [f"s{i + 1}" for i in range(channels)]
    _reset_peak()
    base = _status_mb("VmRSS")
    start = time.perf_counter()
    data, dt = read_record(path, ids)
    if kind == "ours":
        est = estimate_modes([data], dt, method=method)  # type: ignore[arg-type]
        freqs = est.frequency_hz
    else:
        freqs = _textbook_era(data, dt)
    wall = time.perf_counter() - start
    true_f = _true_frequencies(channels)
    err = max(float(np.min(np.abs(freqs / f - 1.0))) for f in true_f) if freqs.size else float("inf")
    peak = _status_mb("VmHWM")
    print(json.dumps({"wall": wall, "peak_mb": peak - base, "err": err}))


def _textbook_era(data: np.ndarray, dt: float, order: int = 12) -> np.ndarray:
    """Frequencies (Hz) of a plain ERA: full block Hankel matrices, SVD, realized A."""
    n, m = data.shape
    cols = n - BLOCK_ROWS
    h0 = np.empty((BLOCK_ROWS * m, cols))
    h1 = np.empty((BLOCK_ROWS * m, cols))
    for i in range(BLOCK_ROWS):
        h0[i * m : (i + 1) * m] = data[i : i + cols].T
        h1[i * m : (i + 1) * m] = data[i + 1 : i + 1 + cols].T
    u, s, vt = np.linalg.svd(h0, full_matrices=False)
    u, s, vt = u[:, :order], s[:order], vt[:order]
    root = 1.0 / np.sqrt(s)
    a = (root[:, None] * (u.T @ h1 @ vt.T)) * root[None, :]
    z = np.linalg.eigvals(a)
    z = z[z.imag > 0]
    result: np.ndarray = np.abs(np.log(z) / dt) / (2.0 * np.pi)
    return result


def _write_case(folder: Path, channels: int, samples: int) -> Path:
    from records_scenario import BODY, IMPACTS, layout
    from rigidid.core.timedomain import impulse_records, record_time
    from rigidid.io.records import write_record

    pos, dirs = layout(channels)
    rate = samples / DURATION
    pre = 0.1
    rec = impulse_records(
        BODY, pos, dirs, IMPACTS[:1], sample_rate=rate, duration=DURATION - pre, pretrigger=pre, noise=0.01, seed=1
    )[0]
    path = folder / f"record_{channels}x{samples}.csv"
    write_record(path, record_time(rec.shape[0], rate, pre), rec, [f"s{i + 1}" for i in range(channels)])
    return path


def _run(kind: str, path: Path, channels: int, method: str) -> dict[str, float]:
    cmd = [sys.executable, __file__, "--child", kind, str(path), str(channels), method]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True)
    result: dict[str, float] = json.loads(out.stdout.strip().splitlines()[-1])
    return result


PEAK_PREAMBLE = """
import atexit, os
def _peak():  # VmHWM: this process's own peak resident set (reset by exec, unlike ru_maxrss)
    with open("/proc/self/status") as fh, open(os.environ["RIGIDID_BENCH_PEAK"], "w") as out:
        out.write(next(line.split()[1] for line in fh if line.startswith("VmHWM:")))
atexit.register(_peak)
"""

CLI_CODE = (
    PEAK_PREAMBLE
    + """
import sys
from rigidid.cli import main
sys.argv = ["rigidid", *sys.argv[1:]]
main()
"""
)

FLOOR_FIR = """
def floor_decimate(x, q, half=10):
    # the floor's FIR decimation, frozen: scipy's decimate filter (firwin(20 q + 1, 1 / q, hamming)),
    # zero phase, evaluated at the kept samples only (polyphase, one product per phase and row block);
    # rigidid's own decimate was this code until it was made faster, so the floor stays where it was
    t = np.arange(-half * q, half * q + 1) / q
    taps = np.sinc(t) * np.hamming(2 * half * q + 1)
    padded = np.zeros((2 * half + 1) * q)
    padded[: 2 * half * q + 1] = taps / taps.sum()
    phases = padded.reshape(2 * half + 1, q)
    blocks = x.shape[0] // q
    cube = x[: blocks * q].reshape(blocks, q, x.shape[1])
    out = np.zeros((blocks - 2 * half - 1, x.shape[1]))
    step = max(8, (1 << 18) // (q * x.shape[1]))
    scratch = np.empty((min(step, out.shape[0]), x.shape[1]))
    for lo in range(0, out.shape[0], step):
        hi = min(out.shape[0], lo + step)
        rows, tmp = out[lo:hi], scratch[: hi - lo]
        for a in range(-half, half + 1):
            np.matmul(phases[a + half], cube[half + lo + a : half + hi + a], out=tmp)
            rows += tmp
    return out
"""

FLOOR_CODE = (
    PEAK_PREAMBLE
    + """
import sys, numpy as np, pandas as pd
from rigidid.core.timedomain.preprocess import decimation_for
from rigidid.core.timedomain.gram import lagged_gram
from rigidid.core.timedomain.era import era_basis, era_modes
"""
    + FLOOR_FIR
    + """
if sys.argv[1].endswith(".npz"):
    with np.load(sys.argv[1]) as npz:
        time, data = npz["time"], npz["data"]
elif sys.argv[1].endswith(".npy"):
    table = np.load(sys.argv[1])
    time, data = table[:, 0], table[:, 1:]
else:
    table = pd.read_csv(sys.argv[1], engine="c").to_numpy()
    time, data = table[:, 0], table[:, 1:]
    del table
dt = (time[-1] - time[0]) / (time.shape[0] - 1)
q = decimation_for(40.0, dt)
if sys.argv[2:] == ["scipy"]:  # the FIR decimation a plain script calls (the issue's floor)
    from scipy.signal import decimate as scipy_decimate

    low = scipy_decimate(data, q, ftype="fir", axis=0)
else:
    low = floor_decimate(data, q)
del data
_, _, vt = np.linalg.svd(low.T @ low)
fitted = low @ vt[:12].T  # the 12 leading principal directions, as rigidid fits at most 2 x 6 channels
gram, _ = lagged_gram([fitted], 20)
poles, _ = era_modes(era_basis(gram, fitted.shape[1]), 12, dt * q)
f = np.sort(np.abs(poles[poles.imag > 0]) / (2 * np.pi))
print(" ".join(f"{v:.3f}" for v in f))
"""
)


def _run_peak(cmd: list[str], folder: Path) -> tuple[float, float]:
    """Wall time (s) and peak resident memory (MB, the child's VmHWM) of a child process."""
    import os

    peak_file = folder / "peak.txt"
    start = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "RIGIDID_BENCH_PEAK": str(peak_file)})
    wall = time.perf_counter() - start
    if out.returncode:
        raise SystemExit(f"{' '.join(cmd[:3])}... failed with exit status {out.returncode}: {out.stderr.strip()}")
    return wall, float(peak_file.read_text()) / 1024.0


PYOMA_CODE = (
    PEAK_PREAMBLE
    + """
import logging, sys, numpy as np, pandas as pd
logging.disable(logging.INFO)
from pyoma2.setup import SingleSetup
from pyoma2.algorithms import SSI
if sys.argv[1].endswith(".npy"):
    table = np.load(sys.argv[1])
else:
    table = pd.read_csv(sys.argv[1], engine="c").to_numpy()
time, data = table[:, 0], np.ascontiguousarray(table[:, 1:])
del table
fs = (time.shape[0] - 1) / (time[-1] - time[0])
setup = SingleSetup(data, fs)
del data
setup.decimate_data(int(0.5 * fs / (4 * 40.0)), ftype="fir")  # the floor's factor, scipy's FIR
alg = SSI(name="ssicov", method="cov", br=20, ordmax=24)
setup.add_algorithms(alg)
setup.run_by_name("ssicov")
"""
)

ESTIMATION_CODE = (
    """
import json, sys, time, numpy as np
from rigidid.core.timedomain import estimate_modes
from rigidid.core.timedomain.preprocess import block_peaks, content_range, decimate, decimation_for, impact_from_blocks
from rigidid.core.timedomain.gram import lagged_gram
from rigidid.core.timedomain.era import era_basis, era_modes
"""
    + FLOOR_FIR
    + """
table = np.load(sys.argv[1])
time_, data = table[:, 0], np.ascontiguousarray(table[:, 1:])
del table
dt = (time_[-1] - time_[0]) / (time_.shape[0] - 1)
q = decimation_for(40.0, dt)


def _realise(low):
    _, _, vt = np.linalg.svd(low.T @ low)
    fitted = low @ vt[:12].T
    gram, _ = lagged_gram([fitted], 20)
    era_modes(era_basis(gram, fitted.shape[1]), 12, dt * q)


def floor():  # the floor's FIR (frozen), 12 principal directions, Gram, ERA at 12 states
    _realise(floor_decimate(data, q))


def floor_scipy():  # the same with the FIR decimation a plain script calls: scipy.signal.decimate(ftype="fir")
    from scipy.signal import decimate as scipy_decimate

    _realise(scipy_decimate(data, q, ftype="fir", axis=0))


def floor_rigidid_fir():  # the same with rigidid's own (faster) FIR decimation
    _realise(decimate(data, q))


def plain_automatic():
    # what a plain script needs when it is not told where the impact is and which band holds the modes
    energy = np.einsum("ij,ij->i", data, data)
    start = int(np.argmax(energy > 0.01 * energy.max())) + int(0.005 / dt)
    part = data[start : start + (1 << 18)]
    segments = part[: part.shape[0] // 4096 * 4096].reshape(-1, 4096, part.shape[1])
    segments = (segments - segments.mean(axis=1, keepdims=True)) * np.hanning(4096)[:, None]
    np.sum(np.abs(np.fft.rfft(segments, axis=1)) ** 2, axis=0)


def ours():
    estimate_modes([data], dt)


def steps():  # the two steps as estimate_modes runs them
    t0 = time.perf_counter()
    impact = impact_from_blocks(data, dt, *block_peaks(data))
    t1 = time.perf_counter()
    content_range([data[impact.start :]], dt)
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1


timed = {}
contenders = [floor, floor_scipy, floor_rigidid_fir, plain_automatic, ours]
order = contenders if int(sys.argv[2]) % 2 == 0 else contenders[::-1]
for f in order:
    f()  # warm: the first call of each pays page faults of fresh temporaries, FFT plans and imports
for _ in range(3):  # best of three interleaved calls: the machine may be shared
    for f in order:
        t0 = time.perf_counter()
        f()
        timed[f.__name__] = min(timed.get(f.__name__, float("inf")), time.perf_counter() - t0)
parts = [steps() for _ in range(3)]
timed["impact"], timed["content"] = min(p[0] for p in parts), min(p[1] for p in parts)
print(json.dumps(timed))
"""
)

PYOMA_PYTHON = Path(__file__).resolve().parents[1] / ".pyoma-venv" / "bin" / "python"


def _case_files(folder: Path, channels: int, samples: int) -> tuple[Path, Path, Path, Path]:
    """The record as CSV, .npy, .npz and the layout (written once; kept in `folder`)."""
    from records_scenario import layout
    from rigidid.io.records import read_record
    from rigidid.io.records.binary import write_binary

    ids = [f"s{i + 1}" for i in range(channels)]
    pos, dirs = layout(channels)
    sensors = [
        {"id": sid, "position": p.tolist(), "direction": d.tolist()} for sid, p, d in zip(ids, pos, dirs, strict=True)
    ]
    lay = folder / f"layout{channels}.json"
    lay.write_text(json.dumps({"units": {"length": "m", "mass": "kg"}, "sensors": sensors}))
    csv = folder / f"record_{channels}x{samples}.csv"
    npy, npz = csv.with_suffix(".npy"), csv.with_suffix(".npz")
    if not csv.exists():
        csv = _write_case(folder, channels, samples)
    if not (npy.exists() and npz.exists()):
        data, dt = read_record(csv, ids)
        time_ = np.arange(data.shape[0]) * dt
        write_binary(npz, time_, data, ids)
        np.save(npy, np.column_stack([time_, data]))
        del data
    return csv, npy, npz, lay


def floor_comparison(cases: list[tuple[int, int]], repeat: int, keep: str | None, pyoma: bool) -> None:
    """`rigidid modes` on CSV, .npy and .npz against the numpy floor and pyOMA2; medians of interleaved runs."""
    import os

    with contextlib.ExitStack() as stack:
        folder = Path(keep) if keep else Path(stack.enter_context(tempfile.TemporaryDirectory()))
        folder.mkdir(parents=True, exist_ok=True)
        load = os.getloadavg()
        print(f"load average at start: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f} ({os.cpu_count()} CPUs)")
        print(
            "contenders, each a fresh process (wall time includes Python start-up and imports; peak = its VmHWM):\n"
            "  floor: plain numpy, pandas.read_csv or np.load whole, a numpy polyphase FIR to a 40 Hz factor, "
            "Gram ERA\n"
            "  issue's floor: the same with scipy.signal.decimate(ftype='fir'), as a plain script decimates\n"
            "  rigidid modes: the command line, records streamed in blocks, impact and band found automatically\n"
            "  pyOMA2 SSI-cov: pandas/np.load whole, decimated to the floor's factor, 20 block rows, orders to 24"
        )
        peaks: dict[tuple[int, int], float] = {}
        for channels, samples in cases:
            t0 = time.perf_counter()
            csv, npy, npz, lay = _case_files(folder, channels, samples)
            print(f"\n{channels} channels x {samples} samples: CSV {csv.stat().st_size / 1e6:.0f} MB, "
                  f".npy {npy.stat().st_size / 1e6:.0f} MB (ready in {time.perf_counter() - t0:.0f} s); "
                  f"medians of {repeat} interleaved runs")  # fmt: skip
            cli = [sys.executable, "-c", CLI_CODE, "modes", str(lay)]
            commands = {
                "floor CSV (pandas + FIR + Gram ERA)": [sys.executable, "-c", FLOOR_CODE, str(csv)],
                "floor .npy (np.load)": [sys.executable, "-c", FLOOR_CODE, str(npy)],
                "issue's floor CSV (scipy's FIR)": [sys.executable, "-c", FLOOR_CODE, str(csv), "scipy"],
                "rigidid modes CSV": [*cli, str(csv), "-o", str(folder / "m1.csv")],
                "rigidid modes .npy": [*cli, str(npy), "-o", str(folder / "m2.csv")],
                "rigidid modes .npz": [*cli, str(npz), "-o", str(folder / "m3.csv")],
            }
            if pyoma:
                commands["pyOMA2 SSI-cov CSV (pandas)"] = [str(PYOMA_PYTHON), "-c", PYOMA_CODE, str(csv)]
                commands["pyOMA2 SSI-cov .npy"] = [str(PYOMA_PYTHON), "-c", PYOMA_CODE, str(npy)]
            runs: dict[str, list[tuple[float, float]]] = {name: [] for name in commands}
            for _ in range(repeat):
                for name, cmd in commands.items():
                    runs[name].append(_run_peak(cmd, folder))
            modes = [np.loadtxt(folder / f"m{k}.csv", delimiter=",", skiprows=1, usecols=(1, 2)) for k in (1, 2, 3)]
            same = all(np.allclose(m, modes[0], rtol=1e-9, atol=0) for m in modes[1:])
            floor = runs["floor CSV (pandas + FIR + Gram ERA)"]
            floor_wall = float(np.median([w for w, _ in floor]))
            floor_peak = float(np.median([m for _, m in floor]))
            print(f"{'contender':<34} {'wall s':>7} {'x floor':>8} {'peak MB':>8} {'x floor':>8}")
            for name, values in runs.items():
                wall = float(np.median([w for w, _ in values]))
                peak = float(np.median([m for _, m in values]))
                print(f"{name:<34} {wall:>7.2f} {wall / floor_wall:>8.2f} {peak:>8.0f} {peak / floor_peak:>8.2f}")
            peaks[(channels, samples)] = float(np.median([m for _, m in runs["rigidid modes CSV"]]))
            walls = {name: float(np.median([w for w, _ in values])) for name, values in runs.items()}
            npy_ratio = walls["rigidid modes .npy"] / walls["floor .npy (np.load)"]
            print(f"rigidid .npy against the .npy floor: {npy_ratio:.2f}x "
                  f"(target 1.5x); rigidid CSV against the CSV floor: {walls['rigidid modes CSV'] / floor_wall:.2f}x; "
                  f"rigidid CSV {walls['rigidid modes CSV']:.2f} s, {peaks[(channels, samples)]:.0f} MB")  # fmt: skip
            issue_floor, ours_csv = walls["issue's floor CSV (scipy's FIR)"], walls["rigidid modes CSV"]
            print(f"the issue's floor (pandas + scipy.signal.decimate FIR + Gram ERA) takes {issue_floor:.2f} s here "
                  f"(1.5-2 s on the machine the issue's 2.5 s target is set for): rigidid CSV "
                  f"{ours_csv:.2f} s = {ours_csv / issue_floor:.2f}x it")  # fmt: skip
            for threads in (None, "1"):
                _estimation_alone(npy, repeat, threads)
            freqs = " ".join(f"{f:.4f}" for f in np.unique(modes[0][:, 0]))
            print(f"record in memory: {channels * samples * 8 / 1e6:.0f} MB; frequencies: {freqs} Hz; "
                  f"CSV, .npy and .npz modes equal to 1e-9: {same}")  # fmt: skip
        load = os.getloadavg()
        busy = (
            " (near or above the CPU count: a shared machine, compare ratios within one run)"
            if max(load) > (0.5 * (os.cpu_count() or 1))
            else ""
        )
        print(f"\nload average at end: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}{busy}")  # fmt: skip
        for (c, n), peak in peaks.items():
            print(f"rigidid modes CSV peak, {c} channels x {n} rows: {peak:.0f} MB")
        by_channels: dict[int, list[tuple[int, float]]] = {}
        for (c, n), peak in sorted(peaks.items()):
            by_channels.setdefault(c, []).append((n, peak))
        for c, rows in by_channels.items():
            if len(rows) > 1:
                (n0, p0), (n1, p1) = rows[0], rows[-1]
                print(f"memory flatness, {c} channels: {n1 / n0:g}x the rows -> {p1 / p0:.2f}x the peak "
                      f"(target about 1.15x)")  # fmt: skip


def _estimation_alone(npy: Path, repeat: int, threads: str | None) -> None:
    """Print the estimation alone against the floor (see the module documentation); `threads`: OPENBLAS_NUM_THREADS."""
    import os

    env = {**os.environ, **({"OPENBLAS_NUM_THREADS": threads} if threads else {})}
    alone = [
        json.loads(subprocess.run(
            [sys.executable, "-c", ESTIMATION_CODE, str(npy), str(k)], capture_output=True, text=True, check=True,
            env=env,
        ).stdout)
        for k in range(repeat)
    ]  # fmt: skip
    est = {key: float(np.median([a[key] for a in alone])) for key in alone[0]}
    fair = est["floor"] + est["plain_automatic"]
    blas = f"OPENBLAS_NUM_THREADS={threads} for both" if threads else "BLAS threads as the environment sets them"
    print(f"estimation alone on the record loaded from .npy (no reading; after a warm call, best of 3 calls "
          f"in each of {repeat} processes, median; {blas}):")  # fmt: skip
    ours = est["ours"]
    print(f"  rigidid estimate_modes (impact found, content spectrum, factor chosen, 24 orders swept, "
          f"stabilised) {ours:.3f} s")  # fmt: skip
    print("  against the floor (FIR decimation to the 40 Hz factor, 12 principal directions, Gram, ERA at 12 "
          "states), with three FIR decimations:")  # fmt: skip
    for key, what in (
        ("floor_scipy", "scipy.signal.decimate(ftype='fir'), what a plain script calls (the issue's floor)"),
        ("floor", "the floor's numpy polyphase FIR (frozen at last stop's rigidid decimate)"),
        ("floor_rigidid_fir", "rigidid's current decimate"),
    ):
        print(f"    {what}: {est[key]:.3f} s -> rigidid at {ours / est[key]:.2f}x")
    print(f"    of rigidid's time, impact search {est['impact']:.3f} s and content spectrum {est['content']:.3f} s "
          f"are steps the floor is spared (it is told the band and fits from row 0)")  # fmt: skip
    plain = est["plain_automatic"]
    print(f"  the same two steps done plainly (energy argmax, Welch of 2^18 rows) {plain:.3f} s; "
          f"frozen floor + them {fair:.3f} s: rigidid at {ours / fair:.2f}x (like for like)")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", help="comma-separated CHANNELSxSAMPLES (default: 8 and 32 x 1e4, 1e5, 1e6)")
    parser.add_argument("--method", default=None, help="estimator (default: the package default)")
    parser.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    parser.add_argument(
        "--floor", nargs="?", const="32x1000000", help="CHANNELSxSAMPLES,...: rigidid modes against the floor"
    )
    parser.add_argument("--keep", help="--floor: folder to write the records to and reuse (default: a temporary one)")
    parser.add_argument("--no-pyoma", action="store_true", help="--floor: leave pyOMA2 out")
    parser.add_argument("--repeat", type=int, default=3, help="runs per contender for --floor (medians)")
    args = parser.parse_args()
    if args.floor:
        floor_cases = [(int(c), int(n)) for c, n in (item.split("x") for item in args.floor.split(","))]
        pyoma = not args.no_pyoma and PYOMA_PYTHON.exists()
        if not pyoma and not args.no_pyoma:
            print(f"pyOMA2 left out: no {PYOMA_PYTHON} (make it: python -m venv .pyoma-venv; "
                  ".pyoma-venv/bin/pip install pyoma-2)")  # fmt: skip
        floor_comparison(floor_cases, args.repeat, args.keep, pyoma)
        return
    if args.child:
        kind, path, channels, method = args.child
        _child(kind, path, int(channels), method)
        return
    from rigidid.core.timedomain import DEFAULT_METHOD

    method = args.method or DEFAULT_METHOD
    cases = DEFAULT_CASES
    if args.cases:
        cases = [(int(c), int(n)) for c, n in (item.split("x") for item in args.cases.split(","))]
    print(f"method {method!r}; one record per case, {DURATION:g} s, 1 % noise; times include reading the CSV")
    header = (
        f"{'channels':>8} {'samples':>9} {'record MB':>9} {'CSV MB':>7} | {'ours s':>7} {'peak MB':>8} {'x rec':>6}"
        f" {'err':>8} | {'textbook s':>10} {'peak MB':>8} {'err':>8}"
    )
    print(header)
    print("-" * len(header))
    with tempfile.TemporaryDirectory() as tmp:
        for channels, samples in cases:
            path = _write_case(Path(tmp), channels, samples)
            record_mb = samples * channels * 8 / 1e6
            csv_mb = path.stat().st_size / 1e6
            ours = _run("ours", path, channels, method)
            line = (
                f"{channels:>8} {samples:>9} {record_mb:>9.1f} {csv_mb:>7.0f} | {ours['wall']:>7.2f}"
                f" {ours['peak_mb']:>8.0f} {ours['peak_mb'] / record_mb:>6.1f} {ours['err']:>8.1e} |"
            )
            baseline_bytes = 5 * BLOCK_ROWS * channels * samples * 8
            if baseline_bytes > BASELINE_LIMIT:
                line += f" {'skipped (memory)':>28}"
            else:
                base = _run("baseline", path, channels, method)
                line += f" {base['wall']:>10.2f} {base['peak_mb']:>8.0f} {base['err']:>8.1e}"
            print(line, flush=True)
            path.unlink()


if __name__ == "__main__":
    main()
