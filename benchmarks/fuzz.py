"""Seeded fuzzer of the whole command line: mutated sample files and odd output paths through every command.

    python benchmarks/fuzz.py [--cases 3000] [--seed 0] [--timeout 60]

Each case runs ``rigidid`` in-process (``rigidid.cli.run``) in a fresh folder and
checks the contract of issue 10: status 0, 1 or 2; no traceback; a failure is one
line on stderr; nothing new left behind after a failure; no NaN or infinity in
any JSON or CSV written; device nodes, FIFOs and symlinks (made in the folder,
never the system's /dev) still what they were. Prints the count per outcome.
``tests/test_fuzz.py`` runs a few dozen cases of the same fuzzer.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import random
import re
import select
import shutil
import signal
import stat
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "samples"

OUTCOMES = ("ok", "traceback", "hang", "bad status", "not one line", "partial output", "non-finite output",
            "damaged target")  # fmt: skip


class _Timeout(Exception):
    pass


@dataclass
class Case:
    """One command line and the files it needs (name -> bytes), made in a fresh folder."""

    argv: list[str]
    files: dict[str, bytes] = field(default_factory=dict)
    specials: dict[str, str] = field(default_factory=dict)  # name -> "chardev" | "fifo" | "symlink" | "dir" | "file"
    note: str = ""


@dataclass
class Result:
    outcome: str
    status: int | None
    stderr: str
    case: Case
    detail: str = ""
    reader: bool = False  # a records-reader (read_record) case


# ----------------------------------------------------------------------------- base files


def base_files(workdir: Path) -> dict[str, bytes]:
    """The sample inputs, plus records and a UFF made by rigidid itself (in `workdir`)."""
    from rigidid.cli import run

    files = {
        "p_layout.json": (SAMPLES / "paper-1994/layout.json").read_bytes(),
        "p_modes.csv": (SAMPLES / "paper-1994/modes.csv").read_bytes(),
        "f_layout.json": (SAMPLES / "four-mounts/layout.json").read_bytes(),
        "f_modes.csv": (SAMPLES / "four-mounts/modes.csv").read_bytes(),
        "f_body.json": (SAMPLES / "four-mounts/body.json").read_bytes(),
        "e_layout.json": (SAMPLES / "engine-on-mounts/layout.json").read_bytes(),
        "e_body.json": (SAMPLES / "engine-on-mounts/body.json").read_bytes(),
    }
    for name, data in files.items():
        (workdir / name).write_bytes(data)
    with _in(workdir), _captured():
        status = run(["simulate", "f_body.json", "f_layout.json", "--records", "rec", "--sample-rate", "128",
                      "--duration", "4", "-o", "sim.csv"])  # fmt: skip
        status |= run(["identify", "p_layout.json", "p_modes.csv", "--uff", "p.uff"])
    if status:
        raise RuntimeError("could not make the base records and UFF")
    files["rec1.csv"] = (workdir / "rec/record-1.csv").read_bytes()
    files["rec2.csv"] = (workdir / "rec/record-2.csv").read_bytes()
    files["p.uff"] = (workdir / "p.uff").read_bytes()
    files.update(_more_base_files(workdir))
    return files


READER_FILES = ("rec", "r1.", "r2.", "frf", "refs", "f_mounts", "e_mounts", "local", "p.uff")
"""Names of the base files whose faults are a reader's to catch (counted apart in the summary)."""
RECORD_FORMATS = ("csv", "semicolon.csv", "npy", "npz", "mat", "mat73.mat", "h5", "wav", "tdms", "uff")


def _records(workdir: Path) -> dict[str, bytes]:
    """The four-mounts records (64 Hz, 2 s) in every records format rigidid reads, as r<k>.<format>."""
    import numpy as np

    from rigidid.cli import run
    from rigidid.io.records.binary import write_binary
    from rigidid.io.uff import write_uff_test

    with _in(workdir), _captured():
        status = run(["simulate", "f_body.json", "f_layout.json", "--records", "short", "--sample-rate", "64",
                      "--duration", "2", "-o", "short.csv"])  # fmt: skip
    if status:
        raise RuntimeError("could not make the short records")
    layout = json.loads((workdir / "f_layout.json").read_text())
    ids = [str(s["id"]) for s in layout["sensors"]]
    out: dict[str, bytes] = {}
    uff_records = []
    for k in (1, 2):
        text = (workdir / f"short/record-{k}.csv").read_text()
        out[f"r{k}.csv"] = text.encode()
        out[f"r{k}.semicolon.csv"] = text.replace(",", ";").replace(".", ",").encode()
        a = np.loadtxt(workdir / f"short/record-{k}.csv", delimiter=",", skiprows=1)
        a = a[a[:, 0] >= -1e-12]
        a[:, 0] -= a[0, 0]
        uff_records.append((a[:, 0], a[:, 1:], ids))
        buf = io.BytesIO()
        np.save(buf, a)
        out[f"r{k}.npy"] = buf.getvalue()
        for suffix in ("npz", "mat", "h5", "wav"):
            path = workdir / f"r{k}.{suffix}"
            write_binary(path, a[:, 0], a[:, 1:], ids)
            out[path.name] = path.read_bytes()
        out[f"r{k}.mat73.mat"] = _mat73(workdir / f"r{k}.mat73.mat", a, ids)
        out[f"r{k}.tdms"] = _tdms(workdir / f"r{k}.tdms", a, ids)
    ax = json.loads((workdir / "ax_layout.json").read_text())
    write_uff_test(workdir / "r.uff", ax, uff_records)
    out["r1.uff"] = (workdir / "r.uff").read_bytes()
    return out


def _mat73(path: Path, a: Any, ids: list[str]) -> bytes:
    """A MATLAB v7.3 file (HDF5 after a 512-byte user block): time and one vector per sensor."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as fh:
        for name, column in [("time", a[:, 0])] + [(s, a[:, i + 1]) for i, s in enumerate(ids)]:
            fh[name] = column.reshape(1, -1)
            fh[name].attrs["MATLAB_class"] = b"double"
    data = bytearray(path.read_bytes())
    data[:19] = b"MATLAB 7.3 MAT-file"
    return bytes(data)


def _tdms(path: Path, a: Any, ids: list[str]) -> bytes:
    from nptdms import ChannelObject, TdmsWriter

    dt = float(a[1, 0] - a[0, 0])
    with TdmsWriter(path) as writer:
        writer.write_segment([ChannelObject("impact", s, a[:, i + 1], properties={"wf_increment": dt})
                              for i, s in enumerate(ids)])  # fmt: skip
    return path.read_bytes()


def _more_base_files(workdir: Path) -> dict[str, bytes]:
    """Records in every format, FRFs (CSV, UFF 58, 58b), references, mounts, a UFF with local systems."""
    from rigidid.cli import run

    out: dict[str, bytes] = {
        "f_mounts.json": (SAMPLES / "four-mounts/mounts.json").read_bytes(),
        "e_mounts.json": (SAMPLES / "engine-on-mounts/mounts.json").read_bytes(),
        "e_modes.csv": (SAMPLES / "engine-on-mounts/modes.csv").read_bytes(),
        "local.unv": (SAMPLES / "uff-local-systems/test.unv").read_bytes(),
        "refs.json": json.dumps(
            {
                "units": {"length": "m", "mass": "kg"},
                "references": [
                    {"id": "101", "position": [0.3, 0.2, 0.15], "direction": "+x"},
                    {"id": "102", "position": [-0.3, 0.2, -0.15], "direction": "+y"},
                    {"id": "103", "position": [0.3, -0.2, -0.15], "direction": "+z"},
                ],
            }
        ).encode(),
    }
    layout = json.loads((SAMPLES / "four-mounts/layout.json").read_text())
    for sensor in layout["sensors"]:  # UFF 58 records only +-x, +-y, +-z
        if not isinstance(sensor["direction"], str):
            sensor["direction"] = "+y"
    out["ax_layout.json"] = json.dumps(layout, indent=1).encode()
    for name, data in out.items():
        (workdir / name).write_bytes(data)
    with _in(workdir), _captured():
        status = 0
        for target, fmt in (("frf.csv", "csv"), ("frf.uff", "uff-ascii"), ("frfb.uff", "uff")):
            status |= run(["simulate", "f_body.json", "ax_layout.json", "-o", "frf_modes.csv", "--frf", target,
                           "--frf-format", fmt, "--references", "refs.json"])  # fmt: skip
    if status:
        raise RuntimeError("could not make the FRF files")
    lines = (workdir / "frf.csv").read_text().splitlines()
    out["frf.csv"] = ("\n".join(lines[:1] + [ln for ln in lines[1:] if _keep_line(ln)]) + "\n").encode()
    out["frf.uff"] = (workdir / "frf.uff").read_bytes()
    out["frfb.uff"] = (workdir / "frfb.uff").read_bytes()
    out.update(_records(workdir))
    return out


def _keep_line(line: str) -> bool:
    """Every fourth frequency line of the FRF CSV (a file a quarter the size, same pairs)."""
    try:
        return round(float(line.split(",")[0]) / 0.26077) % 4 == 1
    except ValueError:
        return True


# ----------------------------------------------------------------------------- mutations

ODD_NUMBERS = ["NaN", "Infinity", "-Infinity", "1e308", "-1e308", "1e-320", "0", "-0", "true", "null", '"7"',
               "1_0", "1e999", "[]", "{}", '"\u00e9\u4e2d"']  # fmt: skip
ODD_CELLS = ["", "nan", "inf", "-inf", "1e308", "1_0", "true", "0x10", " ", "\u00e9", "1e-320", "--1", "1,2"]


BINARY = (".npy", ".npz", ".mat", ".h5", ".wav", ".tdms")


def mutate_binary(data: bytes, rnd: random.Random) -> tuple[bytes, str]:
    """One random fault in a binary file: truncation, flipped bytes (often in the header), a zeroed run."""
    kind = rnd.choice(["truncate", "flip", "flip header", "zero run", "empty", "append"])
    b = bytearray(data)
    if kind == "truncate":
        return bytes(b[: rnd.randrange(len(b) + 1)]), kind
    if kind in ("flip", "flip header") and b:
        span = min(len(b), 600) if kind == "flip header" else len(b)
        for _ in range(rnd.randint(1, 3)):
            b[rnd.randrange(span)] = rnd.randrange(256)
        return bytes(b), kind
    if kind == "zero run" and b:
        at = rnd.randrange(len(b))
        n = min(len(b) - at, rnd.choice([4, 64, 4096]))
        b[at : at + n] = bytes(n)
        return bytes(b), kind
    if kind == "append":
        return bytes(b) + bytes(rnd.randrange(256) for _ in range(rnd.choice([1, 100]))), kind
    return b"", "empty"


def mutate(data: bytes, rnd: random.Random, name: str = "") -> tuple[bytes, str]:
    """One random fault in a file's bytes; returns the new bytes and what was done."""
    if name.endswith(BINARY) or (name.endswith(".uff") and b"\x00" in data[:100000]):
        return mutate_binary(data, rnd)
    text = data.decode("utf-8", "replace")
    kind = rnd.choice(["truncate", "flip", "delete line", "duplicate line", "number", "cell", "swap columns",
                       "dup key", "nest", "unicode", "empty", "blank lines", "drop column", "huge line"])  # fmt: skip
    if kind == "truncate":
        return data[: rnd.randrange(len(data) + 1)], kind
    if kind == "flip":
        b = bytearray(data)
        for _ in range(rnd.randint(1, 4)):
            if b:
                b[rnd.randrange(len(b))] = rnd.randrange(256)
        return bytes(b), kind
    lines = text.split("\n")
    if kind in ("delete line", "duplicate line") and len(lines) > 1:
        i = rnd.randrange(len(lines))
        if kind == "delete line":
            del lines[i]
        else:
            lines.insert(i, lines[i])
        return "\n".join(lines).encode(), kind
    if kind == "number":
        numbers = list(re.finditer(r"-?\d+(\.\d+)?([eE][+-]?\d+)?", text))
        if numbers:
            m = rnd.choice(numbers)
            value = rnd.choice(ODD_NUMBERS)
            return (text[: m.start()] + value + text[m.end() :]).encode(), f"number -> {value}"
    if kind == "cell" and "," in text:
        i = rnd.randrange(1, max(2, len(lines)))
        if i < len(lines) and lines[i]:
            cells = lines[i].split(",")
            j = rnd.randrange(len(cells))
            cells[j] = rnd.choice(ODD_CELLS)
            lines[i] = ",".join(cells)
            return "\n".join(lines).encode(), f"cell -> {cells[j]!r}"
    if kind in ("swap columns", "drop column") and "," in lines[0]:
        rows = [line.split(",") for line in lines]
        width = len(rows[0])
        a, b = rnd.randrange(width), rnd.randrange(width)
        for row in rows:
            if len(row) == width:
                if kind == "swap columns":
                    row[a], row[b] = row[b], row[a]
                else:
                    del row[a]
        return "\n".join(",".join(row) for row in rows).encode(), kind
    if kind == "dup key" and text.lstrip().startswith("{"):
        m = re.search(r'"(\w+)"\s*:\s*([^,{}\[\]]+)', text)
        if m:
            extra = f'"{m.group(1)}": {rnd.choice(["1", "2.5", "-3"])}, '
            return (text[: m.start()] + extra + text[m.start() :]).encode(), kind
    if kind == "nest":
        depth = rnd.choice([50, 5000, 200000])
        return ("[" * depth + "1" + "]" * rnd.choice([0, depth])).encode(), f"nest {depth}"
    if kind == "unicode":
        i = rnd.randrange(len(text) + 1)
        return (text[:i] + rnd.choice(["\u00e9", "\ufeff", "\u0000", "\ud7ff", "\u202e", "\U0001f600"])
                + text[i:]).encode("utf-8", "surrogatepass"), kind  # fmt: skip
    if kind == "empty":
        return b"", kind
    if kind == "blank lines":
        return ("\n\n" + text.replace("\n", "\n\n")).encode(), kind
    if kind == "huge line":
        return data + b"9" * rnd.choice([10, 200_000]), kind
    return data[:-1], "truncate 1"


# ----------------------------------------------------------------------------- case generation

TARGETS = ["new", "new", "existing", "chardev", "fifo", "symlink", "dir", "empty", "slash", "nodir", "afile", "dash"]


def _target(rnd: random.Random, case: Case, stem: str, allow_dash: bool = True) -> str:
    kind = rnd.choice(TARGETS if allow_dash else TARGETS[:-1])
    name = f"{stem}_{kind}"
    if kind in ("new", "dash") and not allow_dash:
        return name + ".out"
    if kind == "new":
        return name + ".out"
    if kind == "existing":
        case.files[name] = b"old contents\n"
        return name
    if kind in ("chardev", "fifo", "dir"):
        case.specials[name] = kind
        return name
    if kind == "symlink":
        case.files[name + ".real"] = b"old real\n"
        case.specials[name] = "symlink"
        return name
    if kind == "empty":
        return ""
    if kind == "slash":
        return name + "dir/"
    if kind == "nodir":
        return "nodir/" + name
    if kind == "afile":
        case.files["afile"] = b"a file\n"
        return "afile/" + name
    return "-"


def _folder(rnd: random.Random, case: Case, stem: str) -> str:
    kind = rnd.choice(["new", "new", "nested", "dir", "file", "empty", "chardev"])
    if kind == "new":
        return stem + "_d"
    if kind == "nested":
        return f"{stem}_a/b"
    if kind == "dir":
        case.specials[stem + "_d"] = "dir"
        return stem + "_d"
    if kind == "file":
        case.files[stem + "_f"] = b"a file\n"
        return stem + "_f"
    if kind == "chardev":
        case.specials[stem + "_c"] = "chardev"
        return stem + "_c"
    return ""


ODD_OPTIONS: dict[str, list[list[str]]] = {
    "identify": [["--mass", "1e308"], ["--mass", "-1"], ["--mass", "nan"], ["--mass", "inf"], ["--seed", "-1"],
                 ["--shape-noise", "inf"], ["--uncertainty", "-3"], ["--method", "xyz"], ["--modes", "1,2,x"],
                 ["--modes", "1,2,3,4,5,99"], ["--bogus"], ["--uncertainty"], ["--frequency-noise", "1e308"],
                 ["--units", "in"], ["--mass", "1e-300"], ["--angle-noise", "-1"], ["--seed", "abc"]],
    "simulate": [["--shape-noise", "inf"], ["--frequency-noise", "1e308"], ["--seed", "-1"], ["--sample-rate", "1e9"],
                 ["--sample-rate", "0"], ["--duration", "nan"], ["--impact", "0,0,0:0,0,1e-200"],
                 ["--impact", "0,0,0:0,0,0"], ["--impact", "1,2:3"], ["--record-noise", "inf"], ["--pretrigger", "-1"]],
    "plan": [["--draws", "1"], ["--add", "-1"], ["--seed", "-1"], ["--shape-noise", "nan"], ["--draws", "abc"]],
    "modes": [["--n-modes", "100"], ["--max-order", "100000"], ["--method", "xyz"], ["--band", "5", "1"],
              ["--band", "nan", "1"], ["--decimate", "0"], ["--n-modes", "0"]],
    "report": [["--mass", "1e308"], ["--seed", "-1"], ["--title", "\u00e9<script>"]],
    "convert": [["--units", "in,furlong"], ["--units", "x"]],
}  # fmt: skip


ODD_MORE: dict[str, list[list[str]]] = {
    "records": [["--band", "-5", "200"], ["--band", "nan", "10"], ["--band", "20", "5"], ["--band", "0", "inf"],
                ["--max-order", "1"], ["--max-order", "1001"], ["--max-order", "0"], ["--decimate", "100"],
                ["--decimate", "0"], ["--n-modes", "0"], ["--n-modes", "100"], ["--modal-method", "xyz"],
                ["--frf", "frf.csv"], ["--units", "m,kg"], ["--mass", "1e-320"], ["--refine"],
                ["--uncertainty", "5"], ["--resample", "4"], ["--csv", ""], ["--csv", "cdir/"]],
    "frf": [["--band", "-5", "200"], ["--band", "600", "300"], ["--band", "nan", "1"], ["--band", "1", "1e308"],
            ["--records"], ["--mass", "1e-320"], ["--mass", "-1"], ["--units", "in,lb"], ["--max-order", "1"],
            ["--max-order", "1001"], ["--method", "residues"], ["--modes", "1,2,3,4,5,6"]],
    "mounts": [["--torque-axis", "x"], ["--torque-axis", "0,0,0"], ["--torque-axis", "1e-200,0,0"],
               ["--torque-axis", "q"], ["--mass", "1e-320"], ["--force-unit", "kN"],
               ["--force-unit", "dyn"]],
    "plan_refs": [["--add", "2"], ["--add", "-1"], ["--draws", "1"], ["--body", "f_body.json"]],
    "simulate_frf": [["--frf-noise", "inf"], ["--frf-noise", "1e308"], ["--frf-noise", "-1"], ["--frf-noise", "nan"],
                     ["--frf-format", "xyz"], ["--frf-format", "uff-ascii"], ["--mounts", "f_mounts.json"],
                     ["--mounts", "e_mounts.json"]],
    "convert_records": [["--records-format", "xyz"], ["--records-format", "wav"], ["--units", "m,kg"],
                        ["--geometry", "local.unv"]],
}  # fmt: skip


def _records_case(rnd: random.Random, case: Case, use: Callable[[str], str]) -> None:
    fmt = rnd.choice(RECORD_FORMATS)
    if fmt == "uff":
        case.argv = ["identify", use("r1.uff"), "--no-refine"]
    else:
        first, second = use(f"r1.{fmt}"), use(f"r2.{rnd.choice(RECORD_FORMATS[:-1])}")
        command = rnd.choice(["identify", "identify", "modes"])
        case.argv = [command, use("f_layout.json"), first, second]
        case.argv += ["--records", "--no-refine"] if command == "identify" else ["-o", _target(rnd, case, "m")]
    if case.argv[0] == "identify" and rnd.random() < 0.5:
        case.argv += ["--json", _target(rnd, case, "json")]
    if case.argv[0] == "identify" and rnd.random() < 0.2:
        case.argv += ["--csv", _folder(rnd, case, "csv")]


def _frf_case(rnd: random.Random, case: Case, use: Callable[[str], str]) -> None:
    frf = use(rnd.choice(["frf.csv", "frf.uff", "frfb.uff"]))
    if rnd.random() < 0.75:
        case.argv = ["identify", use("ax_layout.json"), "--frf", frf, "--references", use("refs.json"),
                     "--method", "massline"]  # fmt: skip
        if rnd.random() < 0.5:
            case.argv += ["--json", _target(rnd, case, "json")]
        if rnd.random() < 0.2:
            case.argv += ["--csv", _folder(rnd, case, "csv")]
    else:
        case.argv = ["modes", use("ax_layout.json"), "--frf", frf, "--references", use("refs.json"),
                     "--max-order", "24", "-o", _target(rnd, case, "m")]  # fmt: skip


def _mounts_case(rnd: random.Random, case: Case, use: Callable[[str], str]) -> None:
    pick = rnd.choice(["f", "e"])
    case.argv = ["identify", use(f"{pick}_layout.json"), use(f"{pick}_modes.csv")]
    case.argv += ["--mounts", use(f"{pick}_mounts.json")]
    if pick == "e" and rnd.random() < 0.15:  # the mount model (four-mounts takes minutes: issue 24, left open)
        case.argv += ["--method", "mounts"]
    if rnd.random() < 0.5:
        case.argv += ["--json", _target(rnd, case, "json")]


def _plan_refs_case(rnd: random.Random, case: Case, use: Callable[[str], str]) -> None:
    case.argv = ["plan", use("ax_layout.json"), "--references", use("refs.json"), "--draws", "20"]
    if rnd.random() < 0.6:
        case.argv += ["--json", _target(rnd, case, "json")]


def _simulate_frf_case(rnd: random.Random, case: Case, use: Callable[[str], str]) -> None:
    case.argv = ["simulate", use("f_body.json"), use("ax_layout.json"), "-o", _target(rnd, case, "csv"),
                 "--frf", _target(rnd, case, "frf", allow_dash=False), "--references", use("refs.json")]  # fmt: skip


def _convert_records_case(rnd: random.Random, case: Case, use: Callable[[str], str]) -> None:
    source = use(rnd.choice(["r1.uff", "r1.uff", "local.unv"]))
    case.argv = ["convert", source, "-o", _folder(rnd, case, "conv")]
    case.argv += ["--records-format", rnd.choice(["csv", "npz", "mat", "h5", "wav"])]


_MORE = {"records": _records_case, "frf": _frf_case, "mounts": _mounts_case, "plan_refs": _plan_refs_case,
         "simulate_frf": _simulate_frf_case, "convert_records": _convert_records_case}  # fmt: skip


def make_case(rnd: random.Random, base: dict[str, bytes], *, slow: bool = True) -> Case:
    """A random command line over (possibly mutated) sample files and odd output paths."""
    commands = ["identify"] * 6 + ["simulate"] * 3 + ["plan"] * 2 + ["convert"] * 2 + ["uff"] * 2
    commands += ["records"] * 8 + ["frf"] * 5 + ["mounts"] * 3 + ["plan_refs"] * 2 + ["simulate_frf"] * 2
    commands += ["convert_records"] * 2
    if slow:
        commands += ["modes", "report"]
    command = rnd.choice(commands)
    case = Case([])

    def use(name: str) -> str:
        case.files.setdefault(name, base[name])
        return name

    if command in _MORE:
        _MORE[command](rnd, case, use)
    elif command == "identify":
        pick = rnd.choice(["p", "f"])
        case.argv = ["identify", use(f"{pick}_layout.json"), use(f"{pick}_modes.csv")]
        if rnd.random() < 0.6:
            case.argv += ["--json", _target(rnd, case, "json")]
        if rnd.random() < 0.4:
            case.argv += ["--uff", _target(rnd, case, "uff", allow_dash=False)]
        if rnd.random() < 0.2:
            case.argv += ["--uncertainty", "20"]
    elif command == "uff":
        case.argv = ["identify", use("p.uff"), "--json", _target(rnd, case, "json")]
    elif command == "simulate":
        pick = rnd.choice(["f", "e"])
        case.argv = ["simulate", use(f"{pick}_body.json"), use(f"{pick}_layout.json")]
        case.argv += ["-o", _target(rnd, case, "csv")]
        if rnd.random() < 0.4:
            case.argv += ["--records", _folder(rnd, case, "rec"), "--sample-rate", "64", "--duration", "2"]
        if rnd.random() < 0.3:
            case.argv += ["--shape-noise", "0.01", "--seed", "3"]
    elif command == "plan":
        case.argv = ["plan", use("f_layout.json"), "--draws", "20"]
        if rnd.random() < 0.5:
            case.argv += ["--body", use("f_body.json")]
        if rnd.random() < 0.6:
            case.argv += ["--json", _target(rnd, case, "json")]
    elif command == "convert":
        case.argv = ["convert", use("p.uff"), "-o", _folder(rnd, case, "conv")]
    elif command == "modes":
        case.argv = ["modes", use("f_layout.json"), use("rec1.csv"), use("rec2.csv"), "-o", _target(rnd, case, "m")]
        if rnd.random() < 0.5:
            case.argv += ["--json", _target(rnd, case, "json")]
    else:  # report
        case.argv = ["report", use("p_layout.json"), use("p_modes.csv"), "-o", _target(rnd, case, "r", False)]
        if rnd.random() < 0.3:
            case.argv += ["--png", _folder(rnd, case, "png")]
        if rnd.random() < 0.3:
            case.argv += ["--body", use("f_body.json")]
    inputs = [name for name in case.files if name in base]
    if inputs and rnd.random() < 0.6:
        name = rnd.choice(inputs)
        case.files[name], what = mutate(base[name], rnd, name)
        case.note = f"{name}: {what}"
    odd = ODD_MORE.get(command) or ODD_OPTIONS.get(case.argv[0], [])
    if odd and rnd.random() < 0.25:
        extra = rnd.choice(odd)
        case.argv += extra
        for token in extra:
            if token in base:
                use(token)
        case.note += f" option {' '.join(extra)}"
    return case


# ----------------------------------------------------------------------------- running and checking


@contextlib.contextmanager
def _in(folder: Path) -> Iterator[None]:
    before = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(before)


@contextlib.contextmanager
def _captured() -> Iterator[tuple[io.StringIO, io.StringIO]]:
    out, err = io.StringIO(), io.StringIO()
    old = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = out, err
    try:
        yield out, err
    finally:
        sys.stdout, sys.stderr = old


class _FifoReader:
    """Drain a FIFO in a thread so that a writer never blocks; counts the bytes read."""

    def __init__(self, path: Path) -> None:
        self.fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        self.stop = False
        self.count = 0
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stop:
            ready, _, _ = select.select([self.fd], [], [], 0.05)
            if ready:
                with contextlib.suppress(BlockingIOError):
                    self.count += len(os.read(self.fd, 1 << 16))

    def close(self) -> None:
        self.stop = True
        self.thread.join()
        os.close(self.fd)


def _snapshot(folder: Path) -> dict[str, tuple[str, str]]:
    out: dict[str, tuple[str, str]] = {}
    for path in sorted(folder.rglob("*")):
        rel = str(path.relative_to(folder))
        st = os.lstat(path)
        if stat.S_ISLNK(st.st_mode):
            out[rel] = ("symlink", os.readlink(path))
        elif stat.S_ISREG(st.st_mode):
            out[rel] = ("file", hashlib.sha1(path.read_bytes()).hexdigest())
        elif stat.S_ISDIR(st.st_mode):
            out[rel] = ("dir", "")
        elif stat.S_ISCHR(st.st_mode):
            out[rel] = ("chardev", str(st.st_rdev))
        elif stat.S_ISFIFO(st.st_mode):
            out[rel] = ("fifo", "")
        else:
            out[rel] = ("other", "")
    return out


def _non_finite(path: Path) -> bool:
    """True if a JSON or CSV output holds NaN or infinity (or is not strict JSON)."""
    if path.suffix in (".uff", ".html", ".png") or path.name.startswith("uff_") or path.name.startswith("r_"):
        return False
    try:
        text = path.read_text(encoding="utf-8")
    except (UnicodeDecodeError, OSError):
        return False
    return _text_non_finite(text)


def _refuse(name: str) -> float:
    raise ValueError(name)


def _text_non_finite(text: str) -> bool:
    stripped = text.lstrip()
    if stripped.startswith(("{", "[")):
        try:
            json.loads(text, parse_constant=_refuse)
        except ValueError:
            return True
        return False
    return bool(re.search(r"(?i)(^|[,\s])[-+]?(nan|inf|infinity)([,\s]|$)", text))


def prepare(case: Case, folder: Path) -> dict[str, _FifoReader]:
    """Make the case's files and special targets in `folder`."""
    for name, data in case.files.items():
        (folder / name).write_bytes(data)
    readers: dict[str, _FifoReader] = {}
    for name, kind in case.specials.items():
        path = folder / name
        if kind == "chardev":
            os.mknod(path, 0o666 | stat.S_IFCHR, os.stat("/dev/null").st_rdev)
        elif kind == "fifo":
            os.mkfifo(path)
            readers[name] = _FifoReader(path)
        elif kind == "symlink":
            os.symlink(name + ".real", path)
        elif kind == "dir":
            path.mkdir()
    return readers


def run_case(case: Case, folder: Path, timeout: float = 60.0) -> Result:
    """Run one case in-process in `folder` (empty) and check the contract."""
    from rigidid.cli import run

    readers = prepare(case, folder)
    before = _snapshot(folder)
    status: int | None = None
    escaped = ""

    def alarm(signum: int, frame: object) -> None:
        raise _Timeout()

    # a hang: `timeout` seconds of this process's CPU (a busy machine stretches wall time, not CPU time), or ten
    # times that of wall time (a read that blocks uses no CPU)
    old = signal.signal(signal.SIGALRM, alarm)
    old_prof = signal.signal(signal.SIGPROF, alarm)
    signal.setitimer(signal.ITIMER_REAL, 10.0 * timeout)
    signal.setitimer(signal.ITIMER_PROF, timeout)
    try:
        with _in(folder), _captured() as (out, err):
            try:
                status = run(case.argv)
            except _Timeout:
                escaped = "hang"
            except SystemExit as exc:  # pragma: no cover - run returns its status
                status = int(exc.code or 0)
            except BaseException as exc:
                escaped = f"{type(exc).__name__}: {exc}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGALRM, old)
        signal.signal(signal.SIGPROF, old_prof)
        for reader in readers.values():
            reader.close()
    stderr = err.getvalue()
    after = _snapshot(folder)
    reader_case = case.note.startswith(READER_FILES)  # a mutated file of one of the readers

    def result(outcome: str, detail: str = "") -> Result:
        return Result(outcome, status, stderr, case, detail, reader_case)

    if escaped == "hang":
        return result("hang")
    if escaped or "Traceback" in stderr:
        return result("traceback", escaped or stderr.strip().splitlines()[-1])
    if status not in (0, 1, 2):
        return result("bad status", str(status))
    lines = [line for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("rigidid: error:")]
    others = [line for line in lines if not line.startswith(("rigidid: error:", "rigidid: warning:", "rigidid: wrote"))]
    if others or len(errors) > 1 or (status == 2 and len(errors) != 1):
        return result("not one line", " | ".join(lines)[:300])
    # targets: specials still what they were
    for name, kind in case.specials.items():
        now = after.get(name, ("absent", ""))
        if now[0] != kind or (kind == "symlink" and now != before[name]):
            return result("damaged target", f"{name} was {kind}, now {now[0]}")
    verdict = status == 1 and case.argv[0] == "plan"  # an exit-1 verdict writes its report (FORMATS)
    if status != 0 and not verdict:
        changed = [name for name in after if before.get(name) != after[name]]
        if changed:
            return result("partial output", ", ".join(changed))
    written = [folder / name for name in after if before.get(name) != after[name] and after[name][0] == "file"]
    written += [folder / f"{name}.real" for name, kind in case.specials.items() if kind == "symlink"]
    for path in written:
        if path.exists() and _non_finite(path):
            return result("non-finite output", str(path.relative_to(folder)))
    if _text_non_finite(out.getvalue()) and ("--json" in case.argv or case.argv[0] in ("simulate", "modes")):
        return result("non-finite output", "standard output")
    return result("ok")


def fuzz(cases: int, seed: int, *, slow: bool = True, timeout: float = 60.0,
         progress: Callable[[int, Result], None] | None = None) -> list[Result]:  # fmt: skip
    """Run `cases` seeded cases; return their results."""
    results: list[Result] = []
    with tempfile.TemporaryDirectory(prefix="rigidid-fuzz-") as tmp:
        work = Path(tmp)
        (work / "base").mkdir()
        base = base_files(work / "base")
        for i in range(cases):
            rnd = random.Random(seed * 1_000_003 + i)
            case = make_case(rnd, base, slow=slow)
            folder = work / f"case{i}"
            folder.mkdir()
            res = run_case(case, folder, timeout)
            results.append(res)
            shutil.rmtree(folder, ignore_errors=True)
            if progress:
                progress(i, res)
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=60.0,
                        help="CPU seconds (or 10 x as many wall seconds) before a case is a hang")  # fmt: skip
    parser.add_argument("--fast", action="store_true", help="leave out modes and report (the slow commands)")
    args = parser.parse_args()
    t0 = time.perf_counter()
    statuses: Counter[int | None] = Counter()

    def show(i: int, res: Result) -> None:
        statuses[res.status] += 1
        if res.outcome != "ok":
            print(f"case {i}: {res.outcome}: {' '.join(res.case.argv)} [{res.case.note}] {res.detail}", flush=True)

    results = fuzz(args.cases, args.seed, slow=not args.fast, timeout=args.timeout, progress=show)
    counts = Counter(r.outcome for r in results)
    reader = Counter(r.outcome for r in results if r.reader and r.outcome != "ok")
    print(f"\n{len(results)} cases, seed {args.seed}, {time.perf_counter() - t0:.0f} s")
    print("commands: " + ", ".join(f"{k} {v}" for k, v in sorted(Counter(r.case.argv[0] for r in results).items())))
    print("exit statuses: " + ", ".join(f"{k}: {v}" for k, v in sorted(statuses.items(), key=str)))
    for outcome in OUTCOMES:
        print(f"{outcome:>18}: {counts.get(outcome, 0)}" + (f" (records reader: {reader[outcome]})"
                                                           if reader.get(outcome) else ""))  # fmt: skip


if __name__ == "__main__":
    main()
