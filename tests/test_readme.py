"""Issue 25: every example of README.md runs as written, on the files of ``samples/engine-test``.

The README's ``bash`` blocks are run block by block with ``bash -e -o pipefail`` in a
folder holding a copy of ``samples/engine-test`` (every file name the examples use),
``samples/`` itself, a ``campaign/`` of the other samples (one folder per test, with its
``expected.json`` as ``reference.json``) and a ``rigidid`` command on the PATH; the
``python`` block runs there too. The only lines not run are in :data:`NOT_RUN`, each
with its reason.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import ROOT, SAMPLES

README = ROOT / "README.md"

NOT_RUN = {
    "python3 -m venv .venv && .venv/bin/pip install -e '.[test]' && ": "installs rigidid (the folder has a "
    "`.venv/bin/rigidid` already): the rest of the line runs",
    ".venv/bin/python -m pytest": "the test suite itself",
    ".venv/bin/pip install -e '.[dev]'": "installs the development tools",
    ".venv/bin/ruff check src tests benchmarks samples && .venv/bin/mypy src/rigidid": "the linters (run by CI)",
}
"""Text taken out of README's blocks before running them, and why."""


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README.read_text(), flags=re.S)


def _shim(path: Path, command: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'#!/bin/sh\nexec {command} "$@"\n')
    path.chmod(path.stat().st_mode | stat.S_IEXEC)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A test's folder as README assumes it, with a rigidid command."""
    here = tmp_path_factory.mktemp("readme")
    for item in (SAMPLES / "engine-test").iterdir():
        if item.is_file() and item.suffix != ".py":
            shutil.copy(item, here / item.name)
    (here / "samples").symlink_to(SAMPLES, target_is_directory=True)
    for case in ("paper-1994", "four-mounts", "engine-on-mounts"):
        test = here / "campaign" / case
        test.mkdir(parents=True)
        for name in ("layout.json", "modes.csv"):
            shutil.copy(SAMPLES / case / name, test / name)
        shutil.copy(SAMPLES / case / "expected.json", test / "reference.json")
    _shim(here / "bin" / "rigidid", f"{sys.executable} -m rigidid")
    _shim(here / ".venv" / "bin" / "rigidid", f"{sys.executable} -m rigidid")
    _shim(here / ".venv" / "bin" / "python", sys.executable)
    return here


def _env(folder: Path) -> dict[str, str]:
    env = dict(os.environ)
    # the examples' processes share one bytecode cache in the folder rather than compile rigidid each time
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(folder / ".pycache")
    env["PATH"] = f"{folder / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT / "src"), env.get("PYTHONPATH", "")) if p)
    env["COLUMNS"] = "120"
    return env


def _runnable(block: str) -> str:
    for text in NOT_RUN:
        block = block.replace(text, "")
    return block


def test_not_run_lines_are_in_readme() -> None:
    """Every exception still names README text (a stale one would hide nothing, but mislead)."""
    text = README.read_text()
    assert all(line in text for line in NOT_RUN)


@pytest.mark.slow  # about 45 s of CPU: plan --add and the report are most of it
@pytest.mark.parametrize("index", range(len(_blocks("bash"))))
def test_readme_bash_block_runs(folder: Path, index: int) -> None:
    block = _runnable(_blocks("bash")[index])
    if not block.strip():
        pytest.skip("nothing left to run")
    out = subprocess.run(
        ["bash", "-e", "-o", "pipefail", "-c", block],
        cwd=folder,
        env=_env(folder),
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 0, f"block {index}:\n{block}\nstdout: {out.stdout[-3000:]}\nstderr: {out.stderr[-3000:]}"
    assert "Traceback" not in out.stderr


def test_readme_python_block_runs(folder: Path) -> None:
    (block,) = _blocks("python")
    out = subprocess.run(
        [sys.executable, "-c", block], cwd=folder, env=_env(folder), capture_output=True, text=True, check=False
    )
    assert out.returncode == 0, out.stderr
    assert (folder / "report.html").stat().st_size > 10_000
