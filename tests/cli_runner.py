"""The command line run in the test's own process, as a user's shell would see it.

:func:`run` calls :func:`rigidid.cli.run` (what the ``rigidid`` console script runs)
with standard output and standard error redirected, and returns a
:class:`subprocess.CompletedProcess` like ``subprocess.run(..., text=True)`` would.
It spares each call a Python start-up and the import of numpy, scipy, pydantic,
typer and rich (about 0.5 s of CPU, most of a small command's cost); the tests
that need a real process (the console script, closed pipes, README's shell
blocks) start one.
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
from collections.abc import Iterator, Mapping
from pathlib import Path


@contextlib.contextmanager
def _environment(env: Mapping[str, str] | None, cwd: Path | None) -> Iterator[None]:
    """`env` set over os.environ and `cwd` entered for the call; both restored after."""
    saved = {name: os.environ.get(name) for name in env or {}}
    here = Path.cwd()
    try:
        os.environ.update(env or {})
        if cwd is not None:
            os.chdir(cwd)
        yield
    finally:
        os.chdir(here)
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def run(
    *args: str | Path, cwd: Path | None = None, env: Mapping[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """``rigidid ARGS`` in this process: its exit status, standard output and standard error."""
    from rigidid.cli import run as cli_run

    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    with _environment(env, cwd), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli_run(argv)
    return subprocess.CompletedProcess(["rigidid", *argv], status, out.getvalue(), err.getvalue())
