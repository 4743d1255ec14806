"""CSV parsers on an impact record: wall time and peak memory of parsing alone (not a test).

Each contender runs in a fresh process on the same file (the records ``modes_speed.py --floor
... --keep DIR`` writes), reads every row into float64 numpy arrays and is timed from before its
import to the last row; peak memory is the process's VmHWM. Contenders whose package is not
installed are reported as such (pyarrow is not a rigidid dependency: run the script with a Python
that has pandas, polars and pyarrow to compare all of them):

- pandas' C engine, in chunks of 16384 rows (rigidid's reader before this change), and whole;
- pyarrow.csv: its streaming reader (``open_csv``, 1 MiB blocks) and ``read_csv`` whole;
- polars: its streaming engine (``scan_csv(...).collect_batches``), ``read_csv`` whole, and
  ``read_csv`` on 8 MiB chunks of lines (rigidid's reader now: memory bounded by a chunk);
- rigidid's own reader (:func:`rigidid.io.records.read_record`, parsing and checks), with polars
  installed and with polars hidden (``sys.modules["polars"] = None``): what the optional
  ``fast-csv`` extra buys. The file must decay (a record), its header ``time,<ids>``.

Run: ``python benchmarks/csv_parsers.py /tmp/cases/record_32x1000000.csv [--repeat 3] [--only rigidid]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import numpy as np

CHILD = r"""
import io, sys, time
import numpy as np
path, how = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
rows = 0
try:
    if how.startswith("rigidid"):
        if how == "rigidid read_record, pandas only":
            sys.modules["polars"] = None  # import polars -> ImportError: the reader's pandas-only path
        from rigidid.io.records import read_record
        with open(path) as fh:
            ids = fh.readline().strip().split(",")[1:]
        rows = read_record(path, ids)[0].shape[0]
    elif how.startswith("pandas"):
        import pandas as pd
        if how == "pandas C, chunks":
            for chunk in pd.read_csv(path, engine="c", chunksize=1 << 14, dtype=np.float64):
                rows += chunk.to_numpy().shape[0]
        else:
            rows = pd.read_csv(path, engine="c", dtype=np.float64).to_numpy().shape[0]
    elif how.startswith("pyarrow"):
        import pyarrow.csv as pc
        if how == "pyarrow, streaming":
            for batch in pc.open_csv(path, read_options=pc.ReadOptions(block_size=1 << 20)):
                rows += np.column_stack([c.to_numpy() for c in batch.columns]).shape[0]
        else:
            table = pc.read_csv(path)
            rows = np.column_stack([c.to_numpy() for c in table.columns]).shape[0]
    else:
        import polars as pl
        if how == "polars, streaming engine":
            for frame in pl.scan_csv(path).collect_batches(chunk_size=1 << 14, engine="streaming"):
                rows += frame.to_numpy().shape[0]
        elif how == "polars, whole":
            rows = pl.read_csv(path).to_numpy().shape[0]
        else:
            import os
            with open(path, "rb") as fh:
                n = fh.readline().count(b",") + 1
                schema = {f"c{k}": pl.Float64 for k in range(n)}
                left, rest = os.fstat(fh.fileno()).st_size - fh.tell(), b""
                while left > 0:
                    data = fh.read(min(1 << 23, left))
                    left -= len(data)
                    data = rest + data
                    cut = data.rfind(b"\n") + 1 if left > 0 else len(data)
                    data, rest = data[:cut], data[cut:]
                    if data:
                        frame = pl.read_csv(io.BytesIO(data), has_header=False, schema=schema)
                        rows += frame.to_numpy().shape[0]
except ImportError as exc:
    print(f"not installed ({exc.name})")
    raise SystemExit(0)
wall = time.perf_counter() - t0
with open("/proc/self/status") as fh:
    peak = next(int(line.split()[1]) for line in fh if line.startswith("VmHWM")) / 1024
print(f"{wall:.3f} {peak:.0f} {rows}")
"""

CONTENDERS = [
    "rigidid read_record, polars",
    "rigidid read_record, pandas only",
    "pandas C, chunks",
    "pandas C, whole",
    "pyarrow, streaming",
    "pyarrow, whole",
    "polars, streaming engine",
    "polars, whole",
    "polars, 8 MiB chunks",
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", help="a record written by modes_speed.py (time and channels, comma-separated)")
    parser.add_argument("--repeat", type=int, default=3, help="interleaved runs per contender (medians)")
    parser.add_argument("--only", default="", help="run only the contenders whose name starts with this")
    args = parser.parse_args()
    size = os.path.getsize(args.csv) / 1e6
    load = os.getloadavg()
    print(f"{args.csv}: {size:.0f} MB; load average {load[0]:.1f}; {os.cpu_count()} CPUs; "
          f"medians of {args.repeat} interleaved runs, each a fresh process")  # fmt: skip
    results: dict[str, list[tuple[float, float]]] = {name: [] for name in CONTENDERS}
    missing: dict[str, str] = {}
    for _ in range(args.repeat):
        for name in CONTENDERS:
            if name in missing or not name.startswith(args.only):
                continue
            out = subprocess.run(
                [sys.executable, "-c", CHILD, args.csv, name], capture_output=True, text=True, check=True
            ).stdout.strip()
            if out.startswith("not installed"):
                missing[name] = out
                continue
            wall, peak, _ = out.split()
            results[name].append((float(wall), float(peak)))
    print(f"{'parser':<26} {'wall s':>7} {'peak MB':>8}")
    for name in CONTENDERS:
        if not name.startswith(args.only):
            continue
        if name in missing:
            print(f"{name:<26} {missing[name]}")
            continue
        wall = float(np.median([w for w, _ in results[name]]))
        peak = float(np.median([m for _, m in results[name]]))
        print(f"{name:<26} {wall:>7.2f} {peak:>8.0f}")


if __name__ == "__main__":
    main()
