"""The ``rigidid`` command line: parse, load, compute, render. Errors become one line on stderr.

Exit status: 0 success, 1 the data determine no rigid body, 2 bad input or usage.
"""

from __future__ import annotations

import json
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, NoReturn

import typer

from rigidid import __version__
from rigidid.errors import InputError, RigididError

app = typer.Typer(
    name="rigidid",
    help="Centre of gravity, inertia tensor and support stiffness/damping of a rigid body from impact-test modes.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)

EXIT_IDENTIFICATION = 1
EXIT_INPUT = 2


def _fail(message: str, code: int) -> NoReturn:
    sys.stderr.write(f"rigidid: error: {message}\n")
    raise typer.Exit(code)


@contextmanager
def _reported() -> Iterator[None]:
    """Turn rigidid's errors into one line on stderr and its warnings into lines too."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        except InputError as exc:
            _fail(str(exc), EXIT_INPUT)
        except RigididError as exc:
            _fail(str(exc), EXIT_IDENTIFICATION)
        finally:
            seen: set[str] = set()
            for w in caught:
                text = str(w.message)
                if text not in seen:
                    seen.add(text)
                    sys.stderr.write(f"rigidid: warning: {text}\n")


def _console() -> Any:
    from rich.console import Console

    return Console(width=None if sys.stdout.isatty() else 150)


def _parse_modes(text: str | None) -> list[int] | None:
    if text is None:
        return None
    try:
        return [int(part) for part in text.replace(" ", "").split(",") if part]
    except ValueError:
        raise InputError(f"expected mode labels like 1,2,3,5,6,7, got {text!r}", source="--modes") from None


def _write_json(target: str, data: dict[str, Any]) -> None:
    from rigidid.files import write_text_atomic

    text = json.dumps(data, indent=2) + "\n"
    if target == "-":
        sys.stdout.write(text)
    else:
        write_text_atomic(target, text)


def _version(value: bool) -> None:
    if value:
        sys.stdout.write(f"rigidid {__version__}\n")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit.")
    ] = False,
) -> None:
    """Rigid-body properties from the modes of an impact test."""


@app.command()
def identify(
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json).", show_default=False)],
    modes: Annotated[Path, typer.Argument(help="Modal parameters (modes.csv).", show_default=False)],
    mass: Annotated[
        float | None, typer.Option(help="Mass of the body in the layout's mass unit (overrides the layout).")
    ] = None,
    modes_used: Annotated[
        str | None,
        typer.Option("--modes", help="The six rigid-body mode labels, e.g. 1,2,3,5,6,7.", show_default=False),
    ] = None,
    method: Annotated[
        str, typer.Option(help="structured (default, robust) or paper (the paper's eqs. 25-26 and 36-40).")
    ] = "structured",
    json_path: Annotated[
        str | None,
        typer.Option("--json", help="Also write the result JSON to PATH ('-': standard output only).", metavar="PATH"),
    ] = None,
) -> None:
    """Identify CG, inertia tensor, stiffness and damping from a layout and its modes."""
    with _reported():
        from rigidid import api
        from rigidid.core.identify import METHODS
        from rigidid.render import result_to_dict

        if method not in METHODS:
            raise InputError(f"unknown method {method!r}; choose {' or '.join(METHODS)}", source="--method")
        result = api.identify(layout, modes, mass=mass, modes_used=_parse_modes(modes_used), method=method)  # type: ignore[arg-type]
        if json_path is not None:
            _write_json(json_path, result_to_dict(result))
        if json_path != "-":
            from rigidid.render import result_tables

            _console().print(result_tables(result))


@app.command()
def simulate(
    body: Annotated[Path, typer.Argument(help="Body on mounts (body.json).", show_default=False)],
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json).", show_default=False)],
    output: Annotated[str, typer.Option("-o", "--output", help="modes.csv to write ('-': standard output).")] = "-",
    frequency_noise: Annotated[float, typer.Option(help="Relative std of frequency noise (0.001 = 0.1 %).")] = 0.0,
    damping_noise: Annotated[float, typer.Option(help="Relative std of damping-ratio noise.")] = 0.0,
    shape_noise: Annotated[float, typer.Option(help="Complex shape noise relative to each mode's RMS.")] = 0.0,
    seed: Annotated[int | None, typer.Option(help="Seed of the noise.")] = None,
) -> None:
    """Write the exact (or noisy) rigid-body modes of a body on its mounts as modes.csv."""
    with _reported():
        from rigidid import api
        from rigidid.files import modes_csv_text, write_text_atomic

        for name, value in (
            ("--frequency-noise", frequency_noise),
            ("--damping-noise", damping_noise),
            ("--shape-noise", shape_noise),
        ):
            if not value >= 0.0:
                raise InputError(f"must be zero or positive, got {value}", source=name)
        table = api.simulate(
            body,
            layout,
            frequency_noise=frequency_noise,
            damping_noise=damping_noise,
            shape_noise=shape_noise,
            seed=seed,
        )
        text = modes_csv_text(table)
        if output == "-":
            sys.stdout.write(text)
        else:
            write_text_atomic(output, text)
            sys.stderr.write(
                f"rigidid: wrote {len(table.labels)} modes x {len(table.sensor_ids)} sensors to {output}\n"
            )


def main() -> None:
    """Entry point of the ``rigidid`` console script."""
    app(prog_name="rigidid")
