"""Progress reporting: one callback type for the core, one rich display for the command line.

The core and the API take an optional ``progress`` callable and know nothing of
terminals::

    def step(task: str, done: float, total: float | None) -> None: ...

``task`` names the step in words ("reading hit1.csv", "decimating"), ``done``
counts units of work finished and ``total`` is how many there are (None when
unknown). Callers that pass nothing get :func:`no_progress`.

The command line uses :func:`terminal_progress`: a rich progress bar on standard
error, shown only when standard error is a terminal, so pipelines, CI logs and
captured output stay clean.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["ProgressCallback", "no_progress", "terminal_progress"]

ProgressCallback = Callable[[str, float, "float | None"], None]
"""``progress(task, done, total)``: see the module's docstring."""


def no_progress(task: str, done: float, total: float | None) -> None:
    """A progress callback that does nothing (the default everywhere)."""


@contextmanager
def terminal_progress(stream: Any = None) -> Iterator[ProgressCallback]:
    """Yield a progress callback that draws rich bars on standard error when it is a terminal.

    Parameters
    ----------
    stream : file-like, optional
        Where to draw (default ``sys.stderr``). When it is not a terminal the
        callback does nothing.

    Yields
    ------
    callable
        ``progress(task, done, total)``; each distinct ``task`` gets its own bar.
    """
    out = sys.stderr if stream is None else stream
    try:
        interactive = bool(out.isatty())
    except (AttributeError, ValueError, OSError):
        interactive = False
    if not interactive:
        yield no_progress
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn

    bars = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f} %"),
        TimeElapsedColumn(),
        console=Console(file=out),
        transient=True,
    )
    tasks: dict[str, TaskID] = {}

    def update(task: str, done: float, total: float | None) -> None:
        if task not in tasks:
            tasks[task] = bars.add_task(task, total=total)
        bars.update(tasks[task], completed=done, total=total)

    with bars:
        yield update
