"""The typer application: the commands registered, exit statuses, closed standard streams and SIGPIPE."""

from __future__ import annotations

import os
import sys
from typing import Annotated, NoReturn

import typer

from rigidid import __version__
from rigidid.cli.common import EXIT_INPUT, StdoutGone, one_line
from rigidid.cli.compare import compare
from rigidid.cli.convert import convert
from rigidid.cli.identify import identify
from rigidid.cli.modes import modes
from rigidid.cli.plan import plan
from rigidid.cli.report import report
from rigidid.cli.simulate import simulate

app = typer.Typer(
    name="rigidid",
    help="Centre of gravity, inertia tensor and support stiffness/damping of a rigid body from impact-test modes.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)
for _command in (identify, modes, simulate, plan, report, convert, compare):
    app.command()(_command)


def _version(value: bool) -> None:
    if value:
        sys.stdout.write(f"rigidid {__version__}\n")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool, typer.Option("--version", "-V", callback=_version, is_eager=True, help="Print the version and exit.")
    ] = False,
) -> None:
    """Rigid-body properties from the modes of an impact test."""


class _ClosedStdout:
    """Stands for a standard output that was closed (``>&-``): writing to it is an error (EBADF), not a broken
    pipe (no reader has gone; the caller gave no output): one line on stderr, exit 2."""

    encoding = "utf-8"

    def write(self, text: str) -> int:
        import errno

        raise OSError(errno.EBADF, "it is closed (>&-): nothing written")

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False

    def fileno(self) -> int:
        import io

        raise io.UnsupportedOperation("standard output is closed")


def _plug_closed_descriptors() -> None:
    """Point closed descriptors 0-2 at /dev/null, so that no file rigidid opens becomes one of them."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            opened = os.open(os.devnull, os.O_RDWR)
            if opened != fd:  # pragma: no cover - the lowest free descriptor is the closed one
                os.dup2(opened, fd)
                os.close(opened)
            if fd == 1:
                sys.stdout = _ClosedStdout()
            elif fd == 2:
                sys.stderr = open(os.devnull, "w")  # noqa: SIM115
    if sys.stdout is None:
        sys.stdout = _ClosedStdout()
    if sys.stderr is None:
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115


def _end_quietly_by_sigpipe() -> NoReturn:
    """Standard output's reader has gone: end as a Unix filter does, killed by SIGPIPE, nothing printed."""
    import signal

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # nothing left to flush at exit
    if hasattr(signal, "SIGPIPE"):
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGPIPE)
    raise SystemExit(141)  # pragma: no cover - where there is no SIGPIPE


# output options per command: file targets, then folder targets (their raw text is checked before typer
# turns it into a Path, which reads "" as "." and drops a trailing "/")
_OUTPUTS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "identify": (("--json", "--uff"), ("--csv",)),
    "report": (("--json", "--uff", "-o", "--output"), ("--png", "--csv")),
    "modes": (("-o", "--output", "--json"), ()),
    "simulate": (("-o", "--output", "--write-frf", "--frf"), ("--write-records", "--records")),
    "plan": (("--json",), ()),
    "convert": ((), ("-o", "--output")),
}


def _raw_output_fault(argv: list[str]) -> str | None:
    """An empty output path, or a file target ending in '/', in `argv` (the message), else None."""
    if not argv or argv[0] not in _OUTPUTS:
        return None
    files, folders = _OUTPUTS[argv[0]]
    for k, token in enumerate(argv[1:], start=1):
        name, eq, value = token.partition("=")
        if not eq:
            if token not in files + folders or k + 1 >= len(argv):
                continue
            name, value = token, argv[k + 1]
        if name not in files + folders:
            continue
        if not value.strip():
            return f"{name}: empty output path"
        if name in files and value != "-" and value.endswith(("/", os.sep)):
            return f"{value}: is a folder path; give a file name ({name})"
    return None


def run(argv: list[str] | None = None) -> int:
    """Run the command line on `argv` (default ``sys.argv[1:]``); return the exit status.

    Every error is one line on standard error: usage errors (status 2) included.
    A standard output that is closed or whose reader has gone raises
    :class:`BrokenPipeError` out of here; :func:`main` turns it into a quiet end.
    """
    from typer import exceptions as typer_exceptions
    from typer._click import exceptions as click_exceptions

    fault = _raw_output_fault(list(sys.argv[1:] if argv is None else argv))
    if fault is not None:
        sys.stderr.write(f"rigidid: error: {one_line(fault)}\n")
        return EXIT_INPUT
    try:
        try:
            status = app(args=argv, prog_name="rigidid", standalone_mode=False)
        except click_exceptions.NoArgsIsHelpError:
            return EXIT_INPUT
        except click_exceptions.UsageError as exc:
            command = exc.ctx.command_path if exc.ctx is not None else "rigidid"
            message = " ".join(exc.format_message().split()) or "usage error"
            sys.stderr.write(f"rigidid: error: {command}: {message} (see {command} --help)\n")
            return EXIT_INPUT
        except typer_exceptions.Abort:
            sys.stderr.write("rigidid: error: aborted\n")
            return EXIT_INPUT
        sys.stdout.flush()
    except (StdoutGone, BrokenPipeError):
        raise BrokenPipeError(32, "standard output is closed") from None
    except OSError as exc:
        sys.stderr.write(f"rigidid: error: standard output: {one_line(str(exc.strerror or exc))}\n")
        return EXIT_INPUT
    return int(status or 0)


def main() -> None:
    """Entry point of the ``rigidid`` console script."""
    _plug_closed_descriptors()
    try:
        status = run()
    except BrokenPipeError:
        _end_quietly_by_sigpipe()
    except BaseException:
        raise
    if status:
        # a failed flush at exit must not print a second message
        try:
            sys.stdout.flush()
        except OSError:
            os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
    raise SystemExit(status)
