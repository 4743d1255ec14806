"""Hostile input, odd output targets, full disks and broken pipes (issue 10).

Device nodes and FIFOs are made in a temporary folder, never in the system's /dev.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import stat
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.cli import run
from rigidid.errors import InputError, PhysicalPlausibilityWarning
from rigidid.io.atomic import OutputSet, check_output, write_text_atomic

from .conftest import DATA, PAPER, SAMPLES

BAD = DATA / "bad"
FOUR = SAMPLES / "four-mounts"
ROOT_ONLY = pytest.mark.skipif(os.geteuid() != 0, reason="making a device node needs root")


def chardev(path: Path, like: str = "/dev/null") -> Path:
    os.mknod(path, 0o666 | stat.S_IFCHR, os.stat(like).st_rdev)
    return path


@contextlib.contextmanager
def captured(folder: Path) -> Iterator[tuple[io.StringIO, io.StringIO]]:
    out, err = io.StringIO(), io.StringIO()
    old = sys.stdout, sys.stderr, os.getcwd()
    sys.stdout, sys.stderr = out, err
    os.chdir(folder)
    try:
        yield out, err
    finally:
        sys.stdout, sys.stderr = old[:2]
        os.chdir(old[2])


def cli(folder: Path, *args: str | Path) -> tuple[int, str, str]:
    with captured(folder) as (out, err):
        status = run([str(a) for a in args])
    return status, out.getvalue(), err.getvalue()


def one_error(stderr: str) -> str:
    lines = [line for line in stderr.splitlines() if not line.startswith(("rigidid: warning:", "rigidid: wrote"))]
    assert len(lines) == 1, stderr
    assert lines[0].startswith("rigidid: error: "), stderr
    return lines[0]


# ----------------------------------------------------------------------------- readers


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("layout_duplicate_key.json", "key 'mass' appears twice"),
        ("layout_boolean_mass.json", "mass: true/false where a number"),
        ("layout_nan_mass.json", "NaN is not a number JSON allows"),
    ],
)
def test_strict_json(name: str, message: str) -> None:
    with pytest.raises(InputError, match=message) as info:
        api.load_layout(BAD / name)
    assert str(info.value).startswith(str(BAD / name))


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("modes_underscore_number.csv", "row 5: real: '0_0324' is not a plain decimal number"),
        ("modes_empty_imag.csv", "row 5: imag: empty cell"),
    ],
)
def test_strict_modes_cells(name: str, message: str) -> None:
    with pytest.raises(InputError) as info:
        api.identify(PAPER / "layout.json", BAD / name)
    assert str(info.value) == f"{BAD / name}: {message}"


def test_huge_numbers_are_refused_at_the_reader(tmp_path: Path) -> None:
    modes = tmp_path / "modes.csv"
    modes.write_text((PAPER / "modes.csv").read_text().replace(",0.0414\n", ",1e308\n", 1))
    with pytest.raises(InputError, match=r"modes.csv: row 2: imag: must be at most 1e\+100 in magnitude"):
        api.identify(PAPER / "layout.json", modes)
    layout = tmp_path / "layout.json"
    layout.write_text((PAPER / "layout.json").read_text().replace("6.75", "1e400"))
    with pytest.raises(InputError, match=r"layout.json: sensors.0.position.0: must be at most 1e\+100"):
        api.load_layout(layout)


def test_deep_nesting_and_size_limit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 200_000)
    with pytest.raises(InputError, match="nested too deeply"):
        api.load_layout(deep)
    monkeypatch.setattr("rigidid.limits.MAX_JSON_BYTES", 100)
    with pytest.raises(InputError, match="larger than the limit"):
        api.load_layout(PAPER / "layout.json")


def test_tiny_direction_vector_normalises() -> None:
    with pytest.warns(PhysicalPlausibilityWarning):  # the paper's damping, as in test_paper
        tiny = api.identify(DATA / "layout_tiny_direction.json", PAPER / "modes.csv")
    with pytest.warns(PhysicalPlausibilityWarning):
        plain = api.identify(PAPER / "layout.json", PAPER / "modes.csv")
    np.testing.assert_allclose(tiny.directions, plain.directions, rtol=0, atol=1e-15)


# ----------------------------------------------------------------------------- writers and targets


def test_output_checks(tmp_path: Path) -> None:
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("x")
    for path, message in [
        ("", "empty output path"),
        (tmp_path / "adir", "is a directory"),
        (f"{tmp_path}/new/", "is a folder path"),
        (tmp_path / "nodir" / "x", "does not exist"),
        (tmp_path / "afile" / "x", "is not a folder"),
    ]:
        with pytest.raises(InputError, match=message):
            check_output(path)


@ROOT_ONLY
def test_device_written_in_place(tmp_path: Path) -> None:
    dev = chardev(tmp_path / "null")
    write_text_atomic(dev, "text\n")
    assert stat.S_ISCHR(os.stat(dev).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["null"]


def test_fifo_written_in_place_and_symlink_followed(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    write_text_atomic(fifo, "through the pipe\n")
    reader.join(10)
    assert got == [b"through the pipe\n"]
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    real = tmp_path / "real.json"
    real.write_text("old")
    (tmp_path / "link.json").symlink_to("real.json")
    write_text_atomic(tmp_path / "link.json", "new\n")
    assert (tmp_path / "link.json").is_symlink()
    assert real.read_text() == "new\n"


def _stage_then_fail(folder: Path) -> None:
    with OutputSet() as outs:
        write_text_atomic(folder / "a.txt", "a")
        outs.folder(folder / "new" / "deeper")
        write_text_atomic(folder / "new" / "deeper" / "b.txt", "b")
        assert not (folder / "a.txt").exists()  # staged, not yet published
        raise RuntimeError("a later step fails")


def test_output_set_all_or_nothing(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError):
        _stage_then_fail(tmp_path)
    assert list(tmp_path.iterdir()) == []
    with OutputSet() as outs:
        write_text_atomic(tmp_path / "a.txt", "a")
        outs.folder(tmp_path / "d")
        write_text_atomic(tmp_path / "d" / "b.txt", "b")
    assert (tmp_path / "a.txt").read_text() == "a"
    assert (tmp_path / "d" / "b.txt").read_text() == "b"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "d"]


# ----------------------------------------------------------------------------- the command line


@ROOT_ONLY
def test_identify_leaves_a_device_target_a_device(tmp_path: Path) -> None:
    dev = chardev(tmp_path / "null")
    status, _, err = cli(
        tmp_path, "identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", "null", "--uff", "null"
    )
    assert status == 0, err
    assert stat.S_ISCHR(os.stat(dev).st_mode)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["identify", "{L}", "{M}", "--json", "o.json", "--uff", "nodir/x.uff"], "nodir/x.uff: cannot write"),
        (["identify", "{L}", "{M}", "--json", "newdir/"], "newdir/: is a folder path"),
        (["identify", "{L}", "{M}", "--json", ""], "--json: empty output path"),
        (["identify", "{L}", "{M}", "--mass", "1e308", "--json", "o.json"], "--mass: must be at most 1e+100"),
        (["identify", "{L}", "{M}", "--seed", "-1", "--uncertainty", "5"], "--seed: must be from 0"),
        (["identify", "{L}", "{M}", "--bogus"], "rigidid identify: No such option: --bogus"),
        (["simulate", "{B}", "{FL}", "--add-shape-noise", "inf", "-o", "m.csv"], "--add-shape-noise: must be a finite"),
        (["simulate", "{B}", "{FL}", "--write-records", "rec", "-o", "nodir/m.csv"], "nodir/m.csv: cannot write"),
        (["simulate", "{B}", "{FL}", "--write-records", "rec", "--sample-rate", "1e9"], "--sample-rate/--duration:"),
        (["simulate", "{B}", "{FL}", "--write-records", "afile"], "afile: is not a folder"),
        (["report", "{L}", "{M}", "-o", "r.html", "--png", "afile/x"], "afile/x: cannot make the folder"),
        (
            ["report", "{L}", "{M}", "-o", "r.html", "--body", "{B}"],
            "body.json: units: units (m, kg) differ from the layout's units",
        ),
        (["plan", "{FL}", "--draws", "20", "--json", "adir"], "adir: is a directory"),
        (["convert", "{U}", "-o", "afile"], "afile: is not a folder"),
    ],
)
def test_cli_refuses_in_one_line_and_writes_nothing(tmp_path: Path, args: list[str], message: str) -> None:
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir()
    before = sorted(p.name for p in tmp_path.rglob("*"))
    names = {"L": PAPER / "layout.json", "M": PAPER / "modes.csv", "B": FOUR / "body.json",
             "FL": FOUR / "layout.json", "U": DATA / "none.uff"}  # fmt: skip
    status, out, err = cli(tmp_path, *[a.format(**names) for a in args])
    assert status == 2
    assert message in one_error(err)
    assert sorted(p.name for p in tmp_path.rglob("*")) == before
    assert out == ""


def test_records_errors_name_the_option_and_files(tmp_path: Path) -> None:
    status, _, err = cli(tmp_path, "simulate", FOUR / "body.json", FOUR / "layout.json", "--write-records", "rec",
                         "--sample-rate", "128", "--duration", "4", "-o", "m.csv")  # fmt: skip
    assert status == 0, err
    recs = ["rec/record-1.csv", "rec/record-2.csv"]
    status, _, err = cli(tmp_path, "modes", FOUR / "layout.json", *recs, "--method", "xyz")
    assert status == 2
    assert "--method: unknown method 'xyz'" in one_error(err)
    status, _, err = cli(tmp_path, "modes", FOUR / "layout.json", *recs, "--n-modes", "100")
    assert "--n-modes: must be from 1 to 30, got 100" in one_error(err)
    status, _, err = cli(tmp_path, "identify", FOUR / "layout.json", *recs, "--records", "--max-order", "100000")
    assert "--max-order: must be from 1 to 1000" in one_error(err)
    status, _, err = cli(tmp_path, "identify", FOUR / "layout.json", *recs, "--records", "--resample", "100")
    assert "--resample: 100 segments of records of" in one_error(err)
    status, _, err = cli(tmp_path, "modes", FOUR / "layout.json", *recs, "--json", "e.json", "-o", "nodir/m.csv")
    assert "nodir/m.csv: cannot write" in one_error(err)
    assert not (tmp_path / "e.json").exists()


def test_json_outputs_are_strict_json(tmp_path: Path) -> None:
    status, out, err = cli(tmp_path, "identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", "-")
    assert status == 0, err

    def refuse(name: str) -> float:
        raise ValueError(name)

    assert json.loads(out, parse_constant=refuse)["center_of_gravity"]


# ----------------------------------------------------------------------------- pipes, closed and full outputs


def _rigidid(*args: object, **kwargs: object) -> subprocess.Popen[str]:
    return subprocess.Popen(  # type: ignore[call-overload, no-any-return]
        [sys.executable, "-m", "rigidid", *map(str, args)], text=True, stderr=subprocess.PIPE, **kwargs
    )


def test_broken_pipe_ends_quietly() -> None:
    proc = _rigidid("simulate", FOUR / "body.json", FOUR / "layout.json", stdout=subprocess.PIPE)
    assert proc.stdout is not None
    proc.stdout.close()  # the reader goes away before rigidid writes
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGPIPE
    assert err == ""


@pytest.mark.parametrize("json_target", ["-", "out.json"])
def test_closed_stdout_is_one_line_and_writes_nothing(tmp_path: Path, json_target: str) -> None:
    # a closed standard output is not a broken pipe (no reader has gone): one line, exit 2, no output file
    proc = subprocess.run(
        f"'{sys.executable}' -m rigidid identify '{PAPER / 'layout.json'}' '{PAPER / 'modes.csv'}' "
        f"--json {json_target} >&-",
        shell=True, capture_output=True, text=True, timeout=60, check=False, cwd=tmp_path,
    )  # fmt: skip
    assert proc.returncode == 2
    assert one_error(proc.stderr) == "rigidid: error: standard output: it is closed (>&-): nothing written"
    assert list(tmp_path.iterdir()) == []


@ROOT_ONLY
def test_full_disk_is_one_line(tmp_path: Path) -> None:
    full = chardev(tmp_path / "full", "/dev/full")
    with full.open("w") as sink:
        proc = _rigidid("identify", PAPER / "layout.json", PAPER / "modes.csv", stdout=sink)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 2
    assert one_error(err) == "rigidid: error: standard output: No space left on device"
    status, _, err = cli(tmp_path, "identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", "full")
    assert status == 2
    assert one_error(err) == "rigidid: error: full: cannot write: No space left on device"
    assert stat.S_ISCHR(os.stat(full).st_mode)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["identify", "{L}", "{M}", "--csv", ""], "--csv: empty output path"),
        (["identify", "{L}", "{M}", "--uff", "x/"], "x/: is a folder path"),
        (["simulate", "{B}", "{FL}", "--records", ""], "--records: empty output path"),
        (["convert", "{U}", "-o", ""], "-o: empty output path"),
        (["identify", "{L}", "{M}", "--units", "in,lb"], "--units: is for a UFF file without dataset 164"),
        (["identify", "{L}", "{M}", "--mass", "1e-320"], "--mass: must be at least 1e-100"),
        (["simulate", "{B}", "{FL}", "--add-frequency-noise", "10", "--seed", "0"], "--add-frequency-noise: too large"),
        (["simulate", "{B}", "{FL}", "--write-frf", "f.csv", "--references", "r.json", "--add-frf-noise", "inf"],
         "--add-frf-noise: must be a finite number"),
        (["simulate", "{B}", "{FL}", "--write-records", ""], "--write-records: empty output path"),
        (["modes", "{FL}", "--frf", "f.csv", "--references", "r.json", "--max-order", "1001"],
         "--max-order: must be from 1 to 1000"),
        (["identify", "{FL}", "--records", "--frf", "f.csv", "--references", "r.json"], "give --records or --frf"),
        (["identify", "{FL}", "--frf", "f.csv", "--references", "r.json", "--method", "massline", "--band", "nan", "9"],
         "--band: must be a finite number"),
    ],
)  # fmt: skip
def test_round_two_options_and_targets_are_refused_in_one_line(tmp_path: Path, args: list[str], message: str) -> None:
    names = {"L": PAPER / "layout.json", "M": PAPER / "modes.csv", "B": FOUR / "body.json",
             "FL": FOUR / "layout.json", "U": PAPER / "layout.json"}  # fmt: skip
    status, _, err = cli(tmp_path, *[a.format(**names) for a in args])
    assert status == 2
    assert message in one_error(err)
    assert list(tmp_path.iterdir()) == []


def test_order_and_pretrigger_messages_blame_their_option(tmp_path: Path) -> None:
    eng = SAMPLES / "engine-test"
    status, _, err = cli(tmp_path, "modes", eng / "layout.json", eng / "hit1.npz", "--max-order", "1")
    assert status == 2 and "--max-order: must be at least 12 for 6 modes" in one_error(err)
    status, _, err = cli(tmp_path, "modes", eng / "layout.json", "--frf", eng / "frf.csv", "--references",
                         eng / "refs.json", "--max-order", "2")  # fmt: skip
    assert status == 2 and "--max-order: must be an integer of at least 3, got 2" in one_error(err)
    body, layout = SAMPLES / "engine-on-mounts" / "body.json", SAMPLES / "engine-on-mounts" / "layout.json"
    status, _, err = cli(tmp_path, "simulate", body, layout, "--write-records", tmp_path / "r", "--pretrigger", "1e7")
    assert status == 2 and "--pretrigger: " in one_error(err) and "(lower the pre-trigger)" in err
    assert not (tmp_path / "r").exists()


def test_a_library_message_of_several_lines_is_printed_on_one(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def numpy_like(*_: object, **__: object) -> None:
        raise InputError("Cannot parse header: '{'\nException: unexpected EOF\n  while parsing", source="x.npy")

    monkeypatch.setattr(api, "plan", numpy_like)
    status, _, err = cli(tmp_path, "plan", PAPER / "layout.json")
    assert status == 2
    assert one_error(err) == "rigidid: error: x.npy: Cannot parse header: '{'; Exception: unexpected EOF; while parsing"
