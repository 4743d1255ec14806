"""Time and peak memory of ``rigidid modes`` on one record in each binary format (issue 14).

Writes one simulated record (the four-mounts body, one impact, 8 channels,
``--rows`` samples over 20 s) as ``.npy`` (the reference: read in row blocks
since the last stop), ``.npz`` with the ``data`` member in Fortran order
(deflated), MATLAB v5 ``.mat`` (uncompressed and compressed, ``data`` plus
``channels``), MATLAB v7.3 ``.mat`` (HDF5 in MATLAB's layout: transposed
datasets, a cell array of names) and a one-array-per-sensor v5 ``.mat``. Each
``rigidid modes`` run is a fresh process (start-up and imports included);
peak = its VmHWM. Medians of ``--repeat`` interleaved runs; the modes must
agree to 1e-9.

    python benchmarks/binary_formats.py --rows 10000000 --repeat 3
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from modes_speed import CLI_CODE, DURATION, _run_peak


def _write_mat73(path: Path, time_: np.ndarray, data: np.ndarray, ids: list[str]) -> None:
    import h5py

    with h5py.File(path, "w", userblock_size=512) as fh:
        refs = fh.create_group("#refs#")
        cells = []
        for i, text in enumerate(ids):
            chars = refs.create_dataset(f"c{i}", data=np.array([ord(c) for c in text], "u2").reshape(-1, 1))
            chars.attrs["MATLAB_class"] = np.bytes_("char")
            cells.append(chars.ref)
        names = fh.create_dataset("channels", data=np.array(cells, dtype=h5py.ref_dtype).reshape(-1, 1))
        names.attrs["MATLAB_class"] = np.bytes_("cell")
        for key, value in (("time", time_.reshape(-1, 1)), ("data", data)):
            ds = fh.create_dataset(key, data=np.ascontiguousarray(value.T))  # MATLAB's m x n is an (n, m) dataset
            ds.attrs["MATLAB_class"] = np.bytes_("double")


def _files(folder: Path, channels: int, rows: int) -> tuple[dict[str, Path], Path]:
    from scipy.io import savemat

    from records_scenario import BODY, IMPACTS, layout
    from rigidid.core.timedomain import impulse_records, record_time

    ids = [f"s{i + 1}" for i in range(channels)]
    pos, dirs = layout(channels)
    lay = folder / f"layout{channels}.json"
    sensors = [
        {"id": s, "position": p.tolist(), "direction": d.tolist()} for s, p, d in zip(ids, pos, dirs, strict=True)
    ]
    lay.write_text(json.dumps({"units": {"length": "m", "mass": "kg"}, "sensors": sensors}))
    stem = folder / f"record_{channels}x{rows}"
    files = {
        ".npy": stem.with_suffix(".npy"),
        ".npz Fortran (deflated)": Path(f"{stem}-fortran.npz"),
        ".mat v5": Path(f"{stem}-v5.mat"),
        ".mat v5 compressed": Path(f"{stem}-v5z.mat"),
        ".mat v5 one array per sensor": Path(f"{stem}-v5-per-sensor.mat"),
        ".mat v7.3": Path(f"{stem}-v73.mat"),
    }
    if all(p.exists() for p in files.values()):
        return files, lay
    rate = rows / DURATION
    pre = 0.1
    data = impulse_records(
        BODY, pos, dirs, IMPACTS[:1], sample_rate=rate, duration=DURATION - pre, pretrigger=pre, noise=0.01, seed=1
    )[0][:rows]
    time_ = record_time(data.shape[0], rate, pre) - record_time(1, rate, pre)[0]
    np.save(files[".npy"], np.column_stack([time_, data]))
    fortran = np.asfortranarray(data)
    np.savez_compressed(files[".npz Fortran (deflated)"], time=time_, data=fortran, channels=np.array(ids))
    del fortran
    names = np.array(ids, dtype=object)
    savemat(files[".mat v5"], {"time": time_, "data": data, "channels": names}, oned_as="column")
    savemat(files[".mat v5 compressed"], {"time": time_, "data": data, "channels": names}, do_compression=True)
    per_sensor = {s: np.ascontiguousarray(data[:, i]) for i, s in enumerate(ids)}
    savemat(files[".mat v5 one array per sensor"], {"sample_rate": rate, **per_sensor}, oned_as="column")
    _write_mat73(files[".mat v7.3"], time_, data, ids)
    return files, lay


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=10_000_000)
    parser.add_argument("--channels", type=int, default=8)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--keep", help="folder to keep (and reuse) the files in")
    args = parser.parse_args()
    with contextlib.ExitStack() as stack:
        folder = Path(args.keep) if args.keep else Path(stack.enter_context(tempfile.TemporaryDirectory()))
        folder.mkdir(parents=True, exist_ok=True)
        load = os.getloadavg()
        print(f"load average at start: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f} ({os.cpu_count()} CPUs)")
        t0 = time.perf_counter()
        files, lay = _files(folder, args.channels, args.rows)
        size = args.channels * args.rows * 8 / 1e6
        print(
            f"{args.channels} channels x {args.rows} rows (record {size:.0f} MB), "
            f"files ready in {time.perf_counter() - t0:.0f} s; medians of {args.repeat} interleaved runs"
        )
        commands = {
            name: [sys.executable, "-c", CLI_CODE, "modes", str(lay), str(p), "-o", str(folder / f"m{k}.csv")]
            for k, (name, p) in enumerate(files.items())
        }
        runs: dict[str, list[tuple[float, float]]] = {name: [] for name in commands}
        for _ in range(args.repeat):
            for name, cmd in commands.items():
                runs[name].append(_run_peak(cmd, folder))
        ref = np.loadtxt(folder / "m0.csv", delimiter=",", skiprows=1, usecols=(1, 2))
        base_wall = float(np.median([w for w, _ in runs[".npy"]]))
        print(f"{'file':<30} {'MB':>6} {'wall s':>7} {'x .npy':>7} {'peak MB':>8}  modes = .npy to 1e-9")
        for k, (name, values) in enumerate(runs.items()):
            wall = float(np.median([w for w, _ in values]))
            peak = float(np.median([m for _, m in values]))
            modes = np.loadtxt(folder / f"m{k}.csv", delimiter=",", skiprows=1, usecols=(1, 2))
            same = modes.shape == ref.shape and bool(np.allclose(modes, ref, rtol=1e-9, atol=0))
            size = files[name].stat().st_size / 1e6
            print(f"{name:<30} {size:>6.0f} {wall:>7.2f} {wall / base_wall:>7.2f} {peak:>8.0f}  {same}")
        load = os.getloadavg()
        print(f"load average at end: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")


if __name__ == "__main__":
    main()
