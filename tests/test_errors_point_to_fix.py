"""Issue 25: errors that say what to do: swapped files, a force column to leave out, options that do not apply."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rigidid.cli import run

from .conftest import SAMPLES

CASE = SAMPLES / "engine-test"
ENGINE = SAMPLES / "engine-on-mounts"


def _error(capsys: pytest.CaptureFixture[str], *args: str | Path) -> str:
    status = run([str(a) for a in args])
    err = capsys.readouterr().err
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigidid: error: "), err
    return lines[0]


def test_layout_and_modes_swapped(capsys: pytest.CaptureFixture[str]) -> None:
    message = _error(capsys, "identify", CASE / "modes.csv", CASE / "layout.json")
    assert "modes.csv" in message and "this is a modes table" in message and "swapped?" in message


def test_layout_given_twice(capsys: pytest.CaptureFixture[str]) -> None:
    message = _error(capsys, "identify", CASE / "layout.json", CASE / "layout.json")
    assert "this is a JSON file, not a modes table" in message


def test_record_given_as_modes(capsys: pytest.CaptureFixture[str]) -> None:
    message = _error(capsys, "identify", CASE / "layout.json", CASE / "hit1.csv")
    assert "this is a time record" in message and "--records" in message


def test_force_column_says_how_to_leave_it_out(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    lines = (CASE / "hit1.csv").read_text().splitlines()
    head, rows = lines[0].split(",", 1), lines[1:]
    text = [f"{head[0]},F_hammer,{head[1]}"] + [f"{r.split(',', 1)[0]},0.5,{r.split(',', 1)[1]}" for r in rows]
    (tmp_path / "hit.csv").write_text("\n".join(text) + "\n")
    message = _error(capsys, "identify", CASE / "layout.json", "--records", tmp_path / "hit.csv", CASE / "hit2.csv")
    assert "'F_hammer' is not a sensor" in message and "rename it (e.g. 'hammer')" in message
    # renamed as the message says, the column is left out with a warning and the run goes on
    (tmp_path / "hit.csv").write_text("\n".join(text).replace("F_hammer", "hammer", 1) + "\n")
    out = tmp_path / "modes.csv"
    status = run(
        ["modes", str(CASE / "layout.json"), str(tmp_path / "hit.csv"), str(CASE / "hit2.csv"), "-o", str(out)]
    )
    err = capsys.readouterr().err
    assert status == 0, err
    assert "columns 'hammer' are not sensors" in err and "left out" in err


def test_mounts_without_damping_cannot_be_simulated(capsys: pytest.CaptureFixture[str]) -> None:
    """Was a 914-character dump of the body object."""
    message = _error(
        capsys, "simulate", ENGINE / "body.json", ENGINE / "layout.json", "--mounts", ENGINE / "mounts.json"
    )
    assert "mounts.json" in message and "no mount has a damping" in message and len(message) < 250


@pytest.mark.parametrize(
    "args",
    [
        ("identify", "{layout}", "{modes}", "--units", "mm,kg"),
        ("identify", "{layout}", "--records", "{hit}", "--units", "mm,kg"),
        ("modes", "{layout}", "{hit}", "--units", "mm,kg"),
        ("plan", "{layout}", "--units", "mm,kg"),
        ("plan", "{layout}", "--geometry", "{geometry}"),
    ],
)
def test_uff_options_on_a_json_layout_are_refused(capsys: pytest.CaptureFixture[str], args: tuple[str, ...]) -> None:
    names = {"layout": CASE / "layout.json", "modes": CASE / "modes.csv", "hit": CASE / "hit1.csv",
             "geometry": CASE / "geometry.unv"}  # fmt: skip
    message = _error(capsys, *(a.format(**names) for a in args))
    assert "--units" in message or "--geometry" in message
    assert "UFF" in message


@pytest.mark.parametrize(
    ("args", "flag"),
    [(("--body", "{body}", "--sample-rate", "0"), "--sample-rate"),
     (("--body", "{body}", "--impact", "1,2:0,0,1"), "--impact"), (("--records",), "--records")],
)  # fmt: skip
def test_a_planned_records_test_is_checked(
    capsys: pytest.CaptureFixture[str], args: tuple[str, ...], flag: str
) -> None:
    """``plan --records``: its test's options named when wrong, and refused without a body estimate to predict for."""
    message = _error(capsys, "plan", CASE / "layout.json", *(a.format(body=CASE / "body.json") for a in args))
    assert message.startswith(f"rigidid: error: {flag}: "), message


def test_the_modes_file_is_not_json(tmp_path: Path) -> None:
    """The hint is only for tables: a broken layout JSON keeps its plain message."""
    from rigidid.errors import InputError
    from rigidid.io.files import load_json

    (tmp_path / "broken.json").write_text('{"units": {"length": "mm",}}')
    with pytest.raises(InputError) as caught:
        load_json(tmp_path / "broken.json")
    assert "swapped" not in str(caught.value)
    (tmp_path / "table.json").write_text(json.dumps({"a": 1})[1:])
    with pytest.raises(InputError, match="invalid JSON"):
        load_json(tmp_path / "table.json")


@pytest.mark.parametrize(
    ("option", "flag"),
    [(("--no-refine",), "--no-refine"), (("--band", "2", "40"), "--band"), (("--max-order", "30"), "--max-order"),
     (("--n-modes", "7"), "--n-modes"), (("--decimate", "2"), "--decimate")],
)  # fmt: skip
def test_record_options_with_modes_are_refused(
    capsys: pytest.CaptureFixture[str], option: tuple[str, ...], flag: str
) -> None:
    message = _error(capsys, "identify", CASE / "layout.json", CASE / "modes.csv", *option)
    assert message.startswith(f"rigidid: error: {flag}: ") and "records only (--records)" in message
