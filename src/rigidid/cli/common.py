"""What the commands share: errors to one line and an exit status, warnings to stderr, output checks and
writers, option parsing, and :func:`identify_files` (what ``identify`` and ``report`` both run)."""

from __future__ import annotations

import json
import os
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import typer

from rigidid.cli.options import FLAGS
from rigidid.errors import InputError, RigididError

if TYPE_CHECKING:
    from rigidid.results import IdentifyResult, TestRun


EXIT_IDENTIFICATION = 1


EXIT_INPUT = 2


def _flag_text(exc: RigididError) -> str:
    """The error's text with the API's parameter names replaced by the command line's options."""
    if isinstance(exc, InputError) and exc.source in FLAGS:
        exc.source = FLAGS[exc.source]
    text = str(exc)
    for name, flag in FLAGS.items():
        text = text.replace(f"`{name}`", flag)
    return text


def one_line(message: str) -> str:
    """A message on one line: a library's several lines (numpy's header errors) joined by "; "."""
    return "; ".join(line.strip() for line in str(message).splitlines() if line.strip())


def _fail(message: str, code: int) -> NoReturn:
    sys.stderr.write(f"rigidid: error: {one_line(message)}\n")
    raise typer.Exit(code)


def _print_warnings(caught: list[warnings.WarningMessage]) -> None:
    seen: set[str] = set()
    for w in caught:
        text = str(w.message)
        if text not in seen and issubclass(w.category, UserWarning):
            seen.add(text)
            sys.stderr.write(f"rigidid: warning: {one_line(text)}\n")


@contextmanager
def reported() -> Iterator[None]:
    """Turn rigidid's errors into one line on stderr, after the warnings that came before them."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        except InputError as exc:
            _print_warnings(caught)
            _fail(_flag_text(exc), EXIT_INPUT)
        except RigididError as exc:
            _print_warnings(caught)
            _fail(_flag_text(exc), EXIT_IDENTIFICATION)
        except BrokenPipeError:
            raise StdoutGone() from None
        except OSError as exc:
            _print_warnings(caught)
            _fail(f"{exc.filename or 'standard output'}: {exc.strerror or exc}", EXIT_INPUT)
        except (MemoryError, RecursionError) as exc:
            _print_warnings(caught)
            _fail(f"input too large or too deeply nested ({type(exc).__name__})", EXIT_INPUT)
        except (ArithmeticError, ValueError) as exc:
            # last resort for numbers the limits let through (LinAlgError is a ValueError)
            if type(exc).__name__ not in ("LinAlgError", "OverflowError", "FloatingPointError", "ZeroDivisionError"):
                raise
            _print_warnings(caught)
            _fail(f"the computation failed numerically ({exc}); check the inputs' magnitudes", EXIT_IDENTIFICATION)
        _print_warnings(caught)


def make_console() -> Any:
    from rich.console import Console

    columns = os.environ.get("COLUMNS", "")
    if columns.isdigit() and int(columns) > 0:
        return Console(width=int(columns))
    return Console(width=None if sys.stdout.isatty() else 150)


def stage_tables(*renderables: Any) -> None:
    """Stage rich tables for standard output in the active output set: written first when it publishes,
    so that a standard output that fails (a full disk, a closed stream) leaves no output file behind."""
    from rigidid.io.atomic import transaction

    console = make_console()
    with console.capture() as captured:
        for item in renderables:
            console.print(item)
    with transaction() as outs:
        outs.stdout(captured.get())


def check_force_unit(text: str | None) -> str | None:
    from rigidid.units import FORCE_UNITS

    if text is not None and text not in FORCE_UNITS:
        raise InputError(f"unknown force unit {text!r}; choose {', '.join(FORCE_UNITS)}", source="--force-unit")
    return text


def write_csv(directory: Path, result: IdentifyResult, force_unit: str | None) -> None:
    from rigidid.io.atomic import transaction, write_text_atomic
    from rigidid.render import result_csv_files

    with transaction() as outs:
        outs.folder(directory, option="--csv")
    files = result_csv_files(result, force_unit)
    for name, text in files.items():
        write_text_atomic(directory / name, text)
    sys.stderr.write(f"rigidid: wrote {len(files)} CSV files to {directory}\n")


def parse_modes(text: str | None) -> list[int] | None:
    if text is None:
        return None
    try:
        return [int(part) for part in text.replace(" ", "").split(",") if part]
    except ValueError:
        raise InputError(f"expected mode labels like 1,2,3,5,6,7, got {text!r}", source="--modes") from None


def add_mounts(result: IdentifyResult, mounts: Path | None, torque_axis: str | None) -> IdentifyResult:
    """Per-mount rates and the torque roll axis, when --mounts or --torque-axis are given."""
    if mounts is None and torque_axis is None:
        return result
    from rigidid import api

    axis = None
    if torque_axis is not None:
        named = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
        try:
            axis = named.get(torque_axis.strip().lower()) or tuple(float(v) for v in torque_axis.split(","))
        except ValueError:
            raise InputError(f"expected x, y, z or X,Y,Z, got {torque_axis!r}", source="--torque-axis") from None
        if len(axis) != 3:
            raise InputError(f"expected x, y, z or X,Y,Z, got {torque_axis!r}", source="--torque-axis")
    try:
        return api.with_mounts(result, mounts, torque_axis=axis)
    except InputError as exc:
        if exc.source == "torque_axis":
            exc.source = "--torque-axis"
        raise


def parse_units(text: str | None, layout: Path | None = None) -> dict[str, str] | None:
    """``--units LENGTH,MASS``; refused beside a layout that is not a UFF file (a layout.json states its units)."""
    if text is None:
        return None
    from rigidid.cli.options import UFF_SUFFIXES

    if layout is not None and Path(layout).suffix.lower() not in UFF_SUFFIXES:
        raise InputError(f"is for a UFF file without dataset 164; {layout} states its own units", source="--units")
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2:
        raise InputError(f"expected LENGTH,MASS like in,lb, got {text!r}", source="--units")
    return {"length": parts[0], "mass": parts[1]}


def noise_overrides(**given: float | None) -> dict[str, float]:
    names = {"angle_deg": "--angle-noise"}
    from rigidid.limits import check_number

    out: dict[str, float] = {}
    for key, value in given.items():
        if value is None:
            continue
        check_number(value, names.get(key, f"--{key}-noise"), nonnegative=True)
        out[key] = value
    return out


def write_json(target: str, data: dict[str, Any]) -> None:
    from rigidid.io.atomic import first_non_finite, transaction, write_text_atomic

    bad = first_non_finite(data)
    if bad is not None:
        raise InputError(
            f"result field {bad} is not a finite number; nothing written (inputs or options too large?)",
            source=target if target != "-" else "--json",
        )
    text = json.dumps(data, indent=2, allow_nan=False) + "\n"
    if target == "-":
        with transaction() as outs:
            outs.stdout(text)
    else:
        write_text_atomic(target, text)


class StdoutGone(Exception):
    """Standard output is closed or its reader has gone (broken pipe)."""


def check_outputs(files: dict[str, Any], folders: dict[str, Any] | None = None) -> None:
    """Check every output path (by option name) before any work; '-' and None need no check."""
    from rigidid.io.atomic import check_folder, check_output

    for option, path in files.items():
        if path is not None and str(path) != "-":
            check_output(path, option=option)
    for option, path in (folders or {}).items():
        if path is not None:
            check_folder(path, option=option)


def old_name(command: str, old: str, new: str, old_value: Any, value: Any, default: Any) -> Any:
    """The value of an option given by its old (hidden) name, with a warning; refused beside the new name.

    One concept has one option name in every command; a renamed option keeps its old name
    as a hidden alias that says the new one.
    """
    if old_value is None:
        return value
    if value != default and value != old_value:
        raise InputError(f"give {new} only ({old} is its old name)", source=old)
    sys.stderr.write(f"rigidid: warning: {command} {old} is deprecated; use {new}\n")
    return old_value


def check_options(**values: Any) -> None:
    """Refuse option values that would overflow or run without bound (name -> value, by flag)."""
    from rigidid.limits import MAX_MAGNITUDE, MAX_MODEL_ORDER, MAX_MODES, MAX_SEGMENTS, check_count, check_number

    counts = {"--n-modes": (1, MAX_MODES), "--max-order": (1, MAX_MODEL_ORDER), "--resample": (0, MAX_SEGMENTS),
              "--decimate": (1, 10_000), "--uncertainty": (0, 1_000_000), "--draws": (2, 1_000_000),
              "--add": (0, 1000), "--seed": (0, 2**63 - 1)}  # fmt: skip
    for name, value in values.items():
        flag = "--" + name.replace("_", "-")
        if name == "band" and value is not None:
            for v in value:
                check_number(v, "--band", nonnegative=True)
            if not value[0] < value[1]:
                raise InputError(f"FMIN must be below FMAX, got {value[0]:g} {value[1]:g}", source="--band")
        elif flag in counts and value is not None:
            check_count(value, flag, low=counts[flag][0], high=counts[flag][1])
        elif isinstance(value, float):
            check_number(value, flag, positive=name in ("sample_rate", "duration", "mass"), nonnegative=True)
            if name == "mass" and value < 1.0 / MAX_MAGNITUDE:  # 1e-320 would divide by zero
                raise InputError(f"must be at least {1.0 / MAX_MAGNITUDE:g}, got {value:g}", source=flag)


def identify_files(
    layout: Path,
    inputs: list[Path] | None,
    records: bool,
    units: str | None,
    modal: dict[str, Any],
    *,
    method: str,
    draws: int,
    mass: float | None,
    seed: int,
    resample: int = 0,
    geometry: Path | None = None,
    mounts: Path | None = None,
    spectrum: bool = False,
    **options: Any,
) -> TestRun:
    """Check the options, then :func:`rigidid.api.records.identify_test` (what identify and report share)."""
    from rigidid import api
    from rigidid.api.records import ModalOptions
    from rigidid.core.identify import METHODS
    from rigidid.progress import terminal_progress

    if method not in (*METHODS, "mounts"):
        raise InputError(f"unknown method {method!r}; choose {', '.join(METHODS)} or mounts", source="--method")
    if method == "mounts" and mounts is None:
        raise InputError("--method mounts needs --mounts FILE (mounts.json or body.json)", source="--method")
    if draws < 0:
        raise InputError(f"must be zero or positive, got {draws}", source="--uncertainty")
    check_options(mass=mass, uncertainty=draws, seed=seed, resample=resample)
    if records:
        check_options(**{k: v for k, v in modal.items() if k != "method"})
    chosen = parse_modes(options.pop("modes_used"))
    with terminal_progress() as progress:
        return api.identify_test(
            layout, inputs, records=records, modal=ModalOptions(**modal), units=parse_units(units, layout),
            geometry=geometry, resample=resample, spectrum=spectrum, progress=progress, mass=mass,
            modes_used=chosen, method=method, uncertainty=draws, seed=seed, mounts=mounts, **options,
        )  # fmt: skip


def refuse_unused(context: str, given: dict[str, bool]) -> None:
    """Refuse the first option of `given` (flag -> whether it was given) that does not apply in `context`.

    Options that do not apply to the input given are refused, not ignored: the error names the option and
    says what it would need (``context``, e.g. "applies only with --write-records").
    """
    for flag, was_given in given.items():
        if was_given:
            raise InputError(context, source=flag)
