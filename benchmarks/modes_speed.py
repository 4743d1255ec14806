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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", help="comma-separated CHANNELSxSAMPLES (default: 8 and 32 x 1e4, 1e5, 1e6)")
    parser.add_argument("--method", default=None, help="estimator (default: the package default)")
    parser.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
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
