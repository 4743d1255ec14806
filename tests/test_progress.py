"""The progress callback: silent unless standard error is a terminal."""

from __future__ import annotations

import io

from rigidid.progress import no_progress, terminal_progress


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_not_a_terminal_gets_the_silent_callback() -> None:
    out = io.StringIO()
    with terminal_progress(out) as progress:
        assert progress is no_progress
        progress("reading", 1, 2)
    assert out.getvalue() == ""


def test_a_terminal_gets_bars_that_name_the_task() -> None:
    out = _Tty()
    with terminal_progress(out) as progress:
        assert progress is not no_progress
        progress("decimating", 1, 4)
        progress("decimating", 4, 4)
    assert "decimating" in out.getvalue()
