"""Issue 25: one vocabulary on the command line: one option name per concept, metavars in one style,
every method in --help, old names kept as hidden aliases that warn."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
import typer.main

from rigidid.cli import run
from rigidid.cli.app import app

from .conftest import SAMPLES

CASE = SAMPLES / "engine-test"


def _commands() -> dict[str, Any]:
    group: Any = typer.main.get_command(app)
    return dict(group.commands)


def _visible(command: Any) -> list[Any]:
    return [p for p in command.params if not getattr(p, "hidden", False)]


def test_every_value_has_an_uppercase_metavar_and_flags_none() -> None:
    for name, command in _commands().items():
        for param in _visible(command):
            if getattr(param, "is_flag", False):
                assert not param.metavar or not param.metavar.strip(), (name, param.opts)
            elif param.name != "help":
                assert param.metavar and re.fullmatch(r"[A-Z][A-Z0-9,|:. _\-]*", param.metavar), (name, param.opts)


def test_one_name_per_concept() -> None:
    commands = _commands()
    for name, command in commands.items():
        opts = {o: p for p in _visible(command) for o in p.opts}
        if "--records" in opts:  # identify, report: the inputs are records
            assert opts["--records"].is_flag, name
        assert "--draws" not in opts, name  # Monte Carlo draws: --uncertainty everywhere
        noise = [o for o in opts if o.endswith("-noise")]
        if name == "simulate":  # noise added to the simulated data
            assert noise and all(o.startswith("--add-") for o in noise), noise
        else:  # noise assumed by the estimate
            assert not any(o.startswith("--add-") for o in noise), (name, noise)
    for name in ("identify", "report", "plan"):
        assert any("--uncertainty" in p.opts for p in _visible(commands[name])), name
    simulate = {o for p in _visible(commands["simulate"]) for o in p.opts}
    assert {"--write-records", "--write-frf"} <= simulate and not {"--records", "--frf"} & simulate


def test_every_method_is_in_help() -> None:
    method = next(p for p in _commands()["identify"].params if "--method" in p.opts)
    for name in ("structured", "paper", "mounts", "massline", "residues"):
        assert name in method.help, name


def test_old_names_still_work_and_warn(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    args = ["simulate", str(CASE / "body.json"), str(CASE / "layout.json"), "-o", str(tmp_path / "m.csv")]
    status = run(
        [*args, "--records", str(tmp_path / "recs"), "--record-noise", "0.01", "--duration", "1", "--seed", "1"]
    )
    err = capsys.readouterr().err
    assert status == 0, err
    assert "simulate --records is deprecated; use --write-records" in err
    assert "simulate --record-noise is deprecated; use --add-record-noise" in err
    assert len(list((tmp_path / "recs").glob("record-*.csv"))) == 2
    status = run([*args, "--frequency-noise", "0.01", "--add-frequency-noise", "0.02"])
    err = capsys.readouterr().err
    assert status == 2 and "give --add-frequency-noise only (--frequency-noise is its old name)" in err
    status = run(["plan", str(CASE / "layout.json"), "--body", str(CASE / "cad-estimate.json"), "--draws", "1"])
    err = capsys.readouterr().err
    assert status == 2 and "plan --draws is deprecated; use --uncertainty" in err and "--uncertainty: need" in err
