"""A bounded, seeded run of the command-line fuzzer (benchmarks/fuzz.py has the long run)."""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import pytest

from .conftest import ROOT


def _fuzzer():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("rigidid_fuzz", ROOT / "benchmarks" / "fuzz.py")
    assert spec is not None and spec.loader is not None
    if "rigidid_fuzz" in sys.modules:
        return sys.modules["rigidid_fuzz"]
    module = importlib.util.module_from_spec(spec)
    sys.modules["rigidid_fuzz"] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


@pytest.mark.skipif(os.geteuid() != 0, reason="the fuzzer makes device nodes, which needs root")
def test_fuzzed_command_lines_keep_the_contract() -> None:
    fuzz = _fuzzer()
    results = fuzz.fuzz(24, seed=20261123, slow=False, timeout=30.0)
    bad = [f"{r.outcome}: {' '.join(r.case.argv)} [{r.case.note}] {r.detail}" for r in results if r.outcome != "ok"]
    assert bad == []
    statuses = {r.status for r in results}
    assert 0 in statuses and 2 in statuses  # the cases reach both success and refusal


def _fake_run(action: str):  # type: ignore[no-untyped-def]
    def run(argv: list[str]) -> int:
        if action == "replace target":
            os.unlink("t")
            Path("t").write_text("regular now")
            return 0
        if action == "partial":
            Path("o.json").write_text("{}")
            sys.stderr.write("rigidid: error: later step failed\n")
            return 2
        if action == "nan":
            Path("o.json").write_text('{"a": NaN}')
            return 0
        if action == "two lines":
            sys.stderr.write("rigidid: error: one\nrigidid: error: two\n")
            return 2
        raise KeyError("boom")

    return run


@pytest.mark.parametrize(
    ("action", "outcome"),
    [("replace target", "damaged target"), ("partial", "partial output"), ("nan", "non-finite output"),
     ("two lines", "not one line"), ("raise", "traceback")],
)  # fmt: skip
def test_the_checker_catches_each_fault(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, action: str, outcome: str
) -> None:
    fuzz = _fuzzer()
    monkeypatch.setattr("rigidid.cli.run", _fake_run(action))
    case = fuzz.Case(["identify"], specials={"t": "fifo"})
    assert fuzz.run_case(case, tmp_path).outcome == outcome
