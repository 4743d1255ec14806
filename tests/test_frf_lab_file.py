"""One lab file in: a UFF of geometry and FRFs (samples/frf-uff, written as Testlab and ME'scope write them)
identifies alone, to the answer of layout + CSV; references from the layout, the UFF headers or references.json
agree, and a contradiction is refused naming both."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rigidid.api import frf as api_frf
from rigidid.errors import InputError

from .conftest import SAMPLES

CASE = SAMPLES / "frf-uff"


def run(*args: str | Path) -> SimpleNamespace:
    """The command line, in this process."""
    from typer.testing import CliRunner

    from rigidid.cli import app

    result = CliRunner().invoke(app, [str(a) for a in args])
    return SimpleNamespace(returncode=result.exit_code, stdout=result.stdout, stderr=result.stderr)


def _bare_layout(tmp_path: Path) -> Path:
    """layout.json without its `references`."""
    layout = json.loads((CASE / "layout.json").read_text())
    del layout["references"]
    path = tmp_path / "layout.json"
    path.write_text(json.dumps(layout))
    return path


def test_the_uff_alone_gives_the_layout_and_csv_test(tmp_path: Path) -> None:
    """Sensors from the response nodes through their local systems, references from the reference nodes."""
    lay_u, refs_u, data_u = api_frf.load_frf_test(CASE / "test.uff")
    ways = [
        api_frf.load_frf_test(CASE / "layout.json", CASE / "frf.csv"),  # the layout's references
        api_frf.load_frf_test(_bare_layout(tmp_path), CASE / "frf.csv", CASE / "refs.json"),  # references.json
        api_frf.load_frf_test(_bare_layout(tmp_path), CASE / "test.uff"),  # the UFF headers
        api_frf.load_frf_test(CASE / "layout.json", CASE / "test.uff", CASE / "refs.json"),  # all three
    ]
    for lay, refs, data in ways:
        assert [s.id for s in lay.sensors] == [s.id for s in lay_u.sensors]
        np.testing.assert_allclose([s.position for s in lay.sensors], [s.position for s in lay_u.sensors], atol=0)
        np.testing.assert_allclose(
            [s.unit_direction() for s in lay.sensors], [s.unit_direction() for s in lay_u.sensors], atol=1e-15
        )
        assert [r.id for r in refs.references] == [r.id for r in refs_u.references]
        np.testing.assert_allclose([r.position for r in refs.references], [r.position for r in refs_u.references])
        np.testing.assert_allclose(
            [r.unit_direction() for r in refs.references], [r.unit_direction() for r in refs_u.references], atol=1e-15
        )
        np.testing.assert_array_equal(data.frequencies, data_u.frequencies)
        np.testing.assert_array_equal(data.frf, data_u.frf)


def test_identify_test_uff_alone_gives_the_expected_answer() -> None:
    """`rigidid identify test.uff` (method auto) == expected.json, which layout.json + frf.csv also give."""
    out = run("identify", CASE / "test.uff", "--json", "-")
    assert out.returncode == 0, out.stderr
    got, want = json.loads(out.stdout), json.loads((CASE / "expected.json").read_text())
    for key in ("mass_measured", "center_of_gravity", "inertia_tensor"):
        # iterative fits (pole refinement, output error) stop within their tolerances: a regression
        # check far below the answer's own standard error (about 1e-4 here), not a CPU's rounding
        np.testing.assert_allclose(got[key], want[key], rtol=1e-7, atol=0.0)
    assert got["route"] == want["route"]
    assert [r["route"] for r in got["routes"]] == ["residues", "massline"]
    assert sum(r["chosen"] for r in got["routes"]) == 1
    np.testing.assert_allclose(got["mass_measured"], 40.0, rtol=1e-5)  # the body (FRFs kept to 6 digits)


@pytest.mark.parametrize(
    ("field", "value", "says"),
    [("position", [0.25, 0.22, 0.11], "is at"), ("direction", "-x", "acts along")],
)
def test_references_that_contradict_are_refused_naming_both(
    tmp_path: Path, field: str, value: object, says: str
) -> None:
    refs = json.loads((CASE / "refs.json").read_text())
    refs["references"][0][field] = value
    (tmp_path / "refs.json").write_text(json.dumps(refs))
    out = run("identify", CASE / "layout.json", "--frf", CASE / "frf.csv", "--references", tmp_path / "refs.json")
    assert out.returncode == 2
    line = out.stderr.strip()
    assert "\n" not in line and says in line and "refs.json" in line and "the layout's references" in line
    with pytest.raises(InputError, match="FRF headers"):  # the UFF's headers against references.json
        api_frf.load_frf_test(_bare_layout(tmp_path), CASE / "test.uff", tmp_path / "refs.json")


def test_no_references_is_one_line_naming_the_three_ways(tmp_path: Path) -> None:
    out = run("identify", _bare_layout(tmp_path), "--frf", CASE / "frf.csv")
    assert out.returncode == 2
    assert "`references`" in out.stderr and "--references" in out.stderr and "UFF" in out.stderr
    assert out.stderr.strip().count("\n") == 0


def test_a_layout_lists_its_references_once(tmp_path: Path) -> None:
    layout = json.loads((CASE / "layout.json").read_text())
    layout["references"].append(dict(layout["references"][0]))
    (tmp_path / "layout.json").write_text(json.dumps(layout))
    out = run("identify", tmp_path / "layout.json", "--frf", CASE / "frf.csv")
    assert out.returncode == 2 and "duplicate reference id" in out.stderr


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (("--records",), "holds FRFs .* not time records"),
        (("--method", "structured"), "FRFs are identified with --method auto, massline, residues"),
    ],
)
def test_a_uff_of_frfs_with_an_option_of_the_other_routes_is_one_line(args: tuple[str, ...], says: str) -> None:
    import re

    out = run("identify", CASE / "test.uff", *args)
    assert out.returncode == 2 and re.search(says, out.stderr), out.stderr
    assert out.stderr.strip().count("\n") == 0


def test_a_uff_of_frfs_is_read_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`identify LAYOUT --frf test.uff`: the references from the headers (through the file's geometry) and the
    FRFs come from one reading of the file, and give the test of references.json + CSV; the command tells a file
    of FRFs from one of records by the 58s' headers alone."""
    from rigidid.io import uff
    from rigidid.io.uff import uff_function_types

    real, calls = uff.read_all, []
    monkeypatch.setattr(uff, "read_all", lambda path: calls.append(path) or real(path))
    _, refs, data = api_frf.load_frf_test(_bare_layout(tmp_path), CASE / "test.uff")
    assert calls == [CASE / "test.uff"]
    _, refs_csv, data_csv = api_frf.load_frf_test(_bare_layout(tmp_path), CASE / "frf.csv", CASE / "refs.json")
    assert [r.id for r in refs.references] == [r.id for r in refs_csv.references]
    np.testing.assert_allclose([r.position for r in refs.references], [r.position for r in refs_csv.references])
    np.testing.assert_array_equal(data.frf, data_csv.frf)
    assert uff_function_types(CASE / "test.uff") == [4] * data.frf.shape[0] * data.frf.shape[1]
    assert set(uff_function_types(SAMPLES / "engine-test" / "test.uff") or [0]) == {1}  # time records
    assert uff_function_types(CASE / "layout.json") is None  # not a universal file: read it to say why
