"""Peak memory of ``.h5`` records as they grow (issue 24): the reader alone, and ``rigidid identify --records``.

    python benchmarks/h5_memory.py [--rows 250000 1000000 2000000] [--folder DIR]

Part 1, the reader: for nine ways of writing the same 8-channel record to HDF5 (``time``/``data``/
``channels`` as ``convert`` writes it; float32; channels x samples; gzip-chunked; gzip-chunked and
transposed; one dataset per channel with a ``dt`` attribute; variable-length channel names; a
``sample_rate`` attribute; int16), ``open_source`` reads every block in a fresh process; prints the
peak resident memory above the process's start (VmHWM minus VmRSS before reading).

Part 2, a whole run: simulated impact records of the engine-on-mounts sample (12 sensors, two
impacts, 0.5 % noise, 20 kHz), of each length, written as ``.h5`` and ``.npy``; prints the wall time
and peak resident memory of ``rigidid identify LAYOUT --records R1 R2`` in a fresh process.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ENGINE = ROOT / "samples" / "engine-on-mounts"
VARIANTS = ("plain", "f4", "transposed", "gzip", "gzip-transposed", "per-channel", "vlen-names", "rate-attr", "int16")

READ_CODE = """
import sys
from pathlib import Path
from rigidid.io.records import layout_ids, open_source
def status(key):
    with open("/proc/self/status") as fh:
        return int(next(line.split()[1] for line in fh if line.startswith(key)))
ids = sys.argv[2].split(",")
before = status("VmRSS:")
source = open_source(Path(sys.argv[1]), layout_ids(ids, sys.argv[1]), None)
rows = sum(values.shape[0] for _, values in source.blocks)
print(rows, (status("VmHWM:") - before) / 1024.0)
"""

CLI_CODE = """
import atexit, sys
def peak():
    with open("/proc/self/status") as fh:
        sys.stderr.write("PEAK " + next(line.split()[1] for line in fh if line.startswith("VmHWM:")) + "\\n")
atexit.register(peak)
from rigidid.cli import main
sys.argv = ["rigidid", *sys.argv[1:]]
main()
"""


def write_variant(path: Path, variant: str, data: np.ndarray, dt: float, ids: list[str]) -> None:
    import h5py

    t = np.arange(data.shape[0]) * dt
    names = np.array(ids, dtype="S")
    with h5py.File(path, "w") as fh:
        if variant == "per-channel":
            fh.attrs["dt"] = dt
            for i, k in enumerate(ids):
                fh[k] = data[:, i]
            return
        fh["channels"] = np.array(ids, dtype=h5py.string_dtype()) if variant == "vlen-names" else names
        values = {"f4": data.astype("f4"), "int16": np.round(data / np.abs(data).max() * 3e4).astype("i2")}.get(
            variant, data
        )
        if variant in ("transposed", "gzip-transposed"):
            values = np.ascontiguousarray(values.T)
        if variant.startswith("gzip"):
            fh.create_dataset("data", data=values, compression="gzip", chunks=True)
        else:
            fh["data"] = values
        if variant == "rate-attr":
            fh["data"].attrs["sample_rate"] = 1.0 / dt
        else:
            fh["time"] = t


def reader_peaks(folder: Path, rows_list: list[int]) -> None:
    ids = [f"c{i}" for i in range(8)]
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    print("part 1: open_source over every block, peak MB above the start (8 channels)")
    print(f"{'variant':>16} " + " ".join(f"{n:>10}" for n in rows_list))
    for variant in VARIANTS:
        cells = []
        for n in rows_list:
            rng = np.random.default_rng(0)
            path = folder / f"{variant}-{n}.h5"
            write_variant(path, variant, rng.standard_normal((n, 8)), 1e-4, ids)
            out = subprocess.run([sys.executable, "-c", READ_CODE, str(path), ",".join(ids)], env=env,
                                 capture_output=True, text=True, check=True).stdout.split()  # fmt: skip
            assert int(out[0]) == n, out
            cells.append(f"{float(out[1]):>10.1f}")
            path.unlink()
        print(f"{variant:>16} " + " ".join(cells))


def whole_runs(folder: Path, rows_list: list[int]) -> None:
    from rigidid.api.load import body_from_file
    from rigidid.core.timedomain.simulate import impulse_records
    from rigidid.io import files
    from rigidid.io.records.binary import write_binary

    spec = files.load_body(ENGINE / "body.json")
    layout = files.load_layout(ENGINE / "layout.json")
    ids, pos, dirs = files.layout_arrays(layout)
    body = body_from_file(spec)
    impacts = [(pos[0], (1.0, 1.0, 1.0)), (pos[-1], (-1.0, 1.0, -1.0))]
    rate = 20_000.0
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    print("\npart 2: rigidid identify LAYOUT --records R1 R2 (12 sensors, 20 kHz), wall s / peak MB")
    print(f"{'rows':>10} {'h5':>16} {'npy':>16}")
    for n in rows_list:
        records = impulse_records(body, pos, dirs, impacts, sample_rate=rate, duration=(n - 1000) / rate,
                                  pretrigger=1000 / rate, noise=0.005, seed=1)  # fmt: skip
        cells = []
        for suffix in (".h5", ".npy"):
            paths = []
            for k, rec in enumerate(records):
                t = (np.arange(rec.shape[0]) - 1000) / rate
                paths.append(folder / f"r{k}-{n}{suffix}")
                if suffix == ".npy":
                    np.save(paths[-1], np.column_stack([t, rec]))
                else:
                    write_binary(paths[-1], t, rec, ids)
            t0 = time.perf_counter()
            proc = subprocess.run([sys.executable, "-c", CLI_CODE, "identify", str(ENGINE / "layout.json"),
                                   "--records", *map(str, paths), "--json", os.devnull],
                                  env=env, capture_output=True, text=True)  # fmt: skip
            wall = time.perf_counter() - t0
            peak = [line for line in proc.stderr.splitlines() if line.startswith("PEAK ")]
            status = "" if proc.returncode == 0 else f" (exit {proc.returncode})"
            cells.append(f"{wall:>6.1f} / {int(peak[-1].split()[1]) / 1024 if peak else 0:>5.0f}{status}")
            for p in paths:
                p.unlink()
        print(f"{n:>10} {cells[0]:>16} {cells[1]:>16}")
        del records


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, nargs="+", default=[250_000, 1_000_000, 2_000_000])
    parser.add_argument("--folder", type=Path, default=None)
    parser.add_argument("--skip-runs", action="store_true", help="part 1 only")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT / "src"))
    with tempfile.TemporaryDirectory(dir=args.folder) as tmp:
        reader_peaks(Path(tmp), args.rows)
        if not args.skip_runs:
            whole_runs(Path(tmp), args.rows)


if __name__ == "__main__":
    main()
