"""The ``rigidid`` command line: parse, load, compute, render. Errors become one line on stderr.

Exit status: 0 success, 1 the data determine no rigid body (or ``plan`` finds the
layout unusable), 2 bad input or usage.
"""

from __future__ import annotations

import json
import os
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

# Before numpy loads: rigidid's matrices are small, and a second BLAS thread made small
# eigenproblems 10-50x slower on a busy 2-core machine (set the variable to override).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# pydantic would scan every installed package's entry points for plugins at the first
# model it builds; the command line uses none.
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

import typer

from rigidid import __version__
from rigidid.errors import InputError, RigididError, named_source

if TYPE_CHECKING:
    from rigidid.results import IdentifyResult, TestRun

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
UFF_SUFFIXES = (".uff", ".unv")

# ----------------------------------------------------------------------------- shared options

_UNC = "Uncertainty"
_TIME = "Time records"
Mass = Annotated[float | None, typer.Option(help="Mass of the body in the layout's mass unit (overrides the layout).")]
ModesUsed = Annotated[
    str | None,
    typer.Option("--modes", help="The six rigid-body mode labels, e.g. 1,2,3,5,6,7.", show_default=False),
]
IdMethod = Annotated[
    str,
    typer.Option(
        help="structured (default, robust), paper (the paper's eqs. 25-26 and 36-40); from --frf: massline, "
        "or residues (scaled modes, with MODES)."
    ),
]
FrfPath = Annotated[
    Path | None, typer.Option("--frf", help="FRF CSV (accelerance) for --method massline.", show_default=False)
]
ReferencesPath = Annotated[
    Path | None, typer.Option(help="references.json: force points and directions of the FRFs.", show_default=False)
]
JsonPath = Annotated[
    str | None,
    typer.Option("--json", help="Also write the result as JSON to PATH ('-': standard output only).", metavar="PATH"),
]
Draws = Annotated[
    int, typer.Option(help="Monte Carlo draws for uncertainty intervals (0: none).", rich_help_panel=_UNC)
]
FrequencyNoise = Annotated[
    float | None,
    typer.Option(help="Relative std of natural frequencies \\[default: 0.001].", rich_help_panel=_UNC),
]
DampingNoise = Annotated[
    float | None, typer.Option(help="Relative std of damping ratios \\[default: 0.05].", rich_help_panel=_UNC)
]
ShapeNoise = Annotated[
    float | None,
    typer.Option(
        help="Std of shape values relative to each mode's RMS \\[default: from the rigid-body fit with more than "
        "six sensors, else 0.01].",
        rich_help_panel=_UNC,
    ),
]
PositionNoise = Annotated[
    float | None, typer.Option(help="Std of sensor positions (length unit) \\[default: 0].", rich_help_panel=_UNC)
]
AngleNoise = Annotated[
    float | None, typer.Option(help="Std of sensor directions (degrees) \\[default: 0].", rich_help_panel=_UNC)
]
Seed = Annotated[int, typer.Option(help="Seed of the random draws.")]
Resample = Annotated[
    int,
    typer.Option(
        help="With --records: also re-identify on K interleaved segments of the records for a data-driven interval "
        "(sample rate / K must stay above twice the highest mode; 8 is a good choice).",
        metavar="K",
        rich_help_panel=_UNC,
    ),
]
Inputs = Annotated[
    list[Path] | None,
    typer.Argument(
        help="modes.csv; or, with --records, one records.csv per impact. Not needed when LAYOUT is a UFF file "
        "with modes (55) or records (58).",
        show_default=False,
    ),
]
RecordsFlag = Annotated[
    bool,
    typer.Option("--records", help="The inputs are impact records: estimate the modes first.", rich_help_panel=_TIME),
]
ModalMethod = Annotated[
    str | None, typer.Option(help="Modal estimator for records: era or ar \\[default: era].", rich_help_panel=_TIME)
]
Band = Annotated[
    tuple[float, float] | None,
    typer.Option(help="Frequency band of the modes (Hz).", metavar="FMIN FMAX", rich_help_panel=_TIME),
]
MaxOrder = Annotated[int | None, typer.Option(help="Highest model order of the sweep.", rich_help_panel=_TIME)]
Decimate = Annotated[
    int | None, typer.Option(help="Decimation factor \\[default: from the spectrum].", rich_help_panel=_TIME)
]
NModes = Annotated[
    int, typer.Option(help="Modes to estimate from records (more than 6 when elastic modes share the band).")
]
ForceUnit = Annotated[
    str | None,
    typer.Option(
        help="Force unit of stiffness and damping: N, kN or lbf \\[default: N for kg, g, t; lbf for lb, slug].",
        metavar="N|kN|lbf",
    ),
]
CsvDir = Annotated[
    Path | None,
    typer.Option(
        "--csv", help="Also write each result matrix as a CSV file (for spreadsheets) into DIR.", metavar="DIR"
    ),
]
Refine = Annotated[
    bool,
    typer.Option(
        "--refine/--no-refine",
        help="With --records: refine the body by an output-error fit to the records, with Cramér-Rao intervals.",
        rich_help_panel=_TIME,
    ),
]
Units = Annotated[
    str | None,
    typer.Option(help="Units of a UFF file without dataset 164, as LENGTH,MASS (e.g. in,lb).", metavar="L,M"),
]
MountsPath = Annotated[
    Path | None,
    typer.Option(
        "--mounts",
        help="mounts.json (or a body.json): mount positions and axes; adds per-mount rates fitted to K and C.",
        metavar="FILE",
        show_default=False,
    ),
]
TorqueAxis = Annotated[
    str | None,
    typer.Option(
        help="Axis of a pure torque (x, y, z or X,Y,Z; for an engine the crankshaft): adds the torque roll axis.",
        metavar="AXIS",
        show_default=False,
    ),
]
Geometry = Annotated[
    Path | None,
    typer.Option(
        help="A UFF file with the nodes (15/2411), coordinate systems (18/2420) and units (164) of a UFF input "
        "that lacks them.",
        metavar="UFF",
    ),
]


# ----------------------------------------------------------------------------- helpers


_FLAGS = {
    "modes_used": "--modes",
    "uncertainty": "--uncertainty",
    "draws": "--uncertainty",
    "segments": "--resample",
    "add": "--add",
    "impacts": "--impact",
    "band": "--band",
    "max_order": "--max-order",
    "units": "--units",
    "frf_format": "--frf-format",
    "modal_method": "--modal-method",
    "geometry": "--geometry",
}
"""API parameter names, as the API's errors name them, and the options that set them."""


def _flag_text(exc: RigididError) -> str:
    """The error's text with the API's parameter names replaced by the command line's options."""
    if isinstance(exc, InputError) and exc.source in _FLAGS:
        exc.source = _FLAGS[exc.source]
    text = str(exc)
    for name, flag in _FLAGS.items():
        text = text.replace(f"`{name}`", flag)
    return text


def _fail(message: str, code: int) -> NoReturn:
    sys.stderr.write(f"rigidid: error: {message}\n")
    raise typer.Exit(code)


def _print_warnings(caught: list[warnings.WarningMessage]) -> None:
    seen: set[str] = set()
    for w in caught:
        text = str(w.message)
        if text not in seen and issubclass(w.category, UserWarning):
            seen.add(text)
            sys.stderr.write(f"rigidid: warning: {text}\n")




@contextmanager
def _reported() -> Iterator[None]:
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
            raise _StdoutGone() from None
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


def _console() -> Any:
    from rich.console import Console

    columns = os.environ.get("COLUMNS", "")
    if columns.isdigit() and int(columns) > 0:
        return Console(width=int(columns))
    return Console(width=None if sys.stdout.isatty() else 150)


def _force_unit(text: str | None) -> str | None:
    from rigidid.units import FORCE_UNITS

    if text is not None and text not in FORCE_UNITS:
        raise InputError(f"unknown force unit {text!r}; choose {', '.join(FORCE_UNITS)}", source="--force-unit")
    return text


def _write_csv(directory: Path, result: IdentifyResult, force_unit: str | None) -> None:
    from rigidid.io.atomic import transaction, write_text_atomic
    from rigidid.render import result_csv_files

    with transaction() as outs:
        outs.folder(directory, option="--csv")
    files = result_csv_files(result, force_unit)
    for name, text in files.items():
        write_text_atomic(directory / name, text)
    sys.stderr.write(f"rigidid: wrote {len(files)} CSV files to {directory}\n")


def _parse_modes(text: str | None) -> list[int] | None:
    if text is None:
        return None
    try:
        return [int(part) for part in text.replace(" ", "").split(",") if part]
    except ValueError:
        raise InputError(f"expected mode labels like 1,2,3,5,6,7, got {text!r}", source="--modes") from None


def _with_mounts(result: IdentifyResult, mounts: Path | None, torque_axis: str | None) -> IdentifyResult:
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


def _parse_units(text: str | None) -> dict[str, str] | None:
    if text is None:
        return None
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2:
        raise InputError(f"expected LENGTH,MASS like in,lb, got {text!r}", source="--units")
    return {"length": parts[0], "mass": parts[1]}


def _noise_overrides(**given: float | None) -> dict[str, float]:
    names = {"angle_deg": "--angle-noise"}
    from rigidid.limits import check_number

    out: dict[str, float] = {}
    for key, value in given.items():
        if value is None:
            continue
        check_number(value, names.get(key, f"--{key}-noise"), nonnegative=True)
        out[key] = value
    return out


def _write_json(target: str, data: dict[str, Any]) -> None:
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


class _StdoutGone(Exception):
    """Standard output is closed or its reader has gone (broken pipe)."""


def _check_outputs(files: dict[str, Any], folders: dict[str, Any] | None = None) -> None:
    """Check every output path (by option name) before any work; '-' and None need no check."""
    from rigidid.io.atomic import check_folder, check_output

    for option, path in files.items():
        if path is not None and str(path) != "-":
            check_output(path, option=option)
    for option, path in (folders or {}).items():
        if path is not None:
            check_folder(path, option=option)


def _check_options(**values: Any) -> None:
    """Refuse option values that would overflow or run without bound (name -> value, by flag)."""
    from rigidid.limits import MAX_MODEL_ORDER, MAX_MODES, MAX_SEGMENTS, check_count, check_number

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
            check_number(value, flag, positive=name in ("sample_rate", "duration"), nonnegative=name != "mass")












def _identify(
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
    _check_options(mass=mass, uncertainty=draws, seed=seed, resample=resample)
    if records:
        _check_options(**{k: v for k, v in modal.items() if k != "method"})
    chosen = _parse_modes(options.pop("modes_used"))
    with terminal_progress() as progress:
        return api.identify_test(
            layout, inputs, records=records, modal=ModalOptions(**modal), units=_parse_units(units),
            geometry=geometry, resample=resample, spectrum=spectrum, progress=progress, mass=mass,
            modes_used=chosen, method=method, uncertainty=draws, seed=seed, mounts=mounts, **options,
        )  # fmt: skip


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


# ----------------------------------------------------------------------------- commands


@app.command()
def identify(
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json), or a UFF file.", show_default=False)],
    inputs: Inputs = None,
    records: RecordsFlag = False,
    mass: Mass = None,
    modes_used: ModesUsed = None,
    method: IdMethod = "structured",
    json_path: JsonPath = None,
    uff: Annotated[
        Path | None, typer.Option(help="Also write the identified modes and geometry as a UFF file (15, 55, 82).")
    ] = None,
    uncertainty: Draws = 0,
    frequency_noise: FrequencyNoise = None,
    damping_noise: DampingNoise = None,
    shape_noise: ShapeNoise = None,
    position_noise: PositionNoise = None,
    angle_noise: AngleNoise = None,
    seed: Seed = 0,
    resample: Resample = 0,
    modal_method: ModalMethod = None,
    n_modes: NModes = 6,
    band: Band = None,
    max_order: MaxOrder = None,
    decimate: Decimate = None,
    units: Units = None,
    geometry: Geometry = None,
    force_unit: ForceUnit = None,
    csv: CsvDir = None,
    frf: FrfPath = None,
    references: ReferencesPath = None,
    mounts: MountsPath = None,
    torque_axis: TorqueAxis = None,
    refine: Refine = True,
) -> None:
    """Identify CG, inertia tensor, stiffness and damping from a layout and its modes (or impact records)."""
    with _reported():
        from rigidid.io.atomic import OutputSet
        from rigidid.jsonout import result_to_dict

        if method in ("massline", "residues") or frf is not None:
            _check_outputs({"--json": json_path})
            _identify_massline(
                layout, frf, references, mass=mass, band=band, method=method, json_path=json_path,
                modes=inputs, modes_used=modes_used,
            )  # fmt: skip
            return
        force_unit = _force_unit(force_unit)

        _check_outputs({"--json": json_path, "--uff": uff}, {"--csv": csv})
        noise = _noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        modal = {"method": modal_method, "n_modes": n_modes, "band": band, "max_order": max_order, "decimate": decimate}
        run = _identify(
            layout, inputs, records, units, modal, mass=mass, modes_used=modes_used, method=method, draws=uncertainty,
            noise=noise, seed=seed, resample=resample, geometry=geometry, mounts=mounts, refine=refine,
        )  # fmt: skip
        result, estimate = run.result, run.estimate
        result = _with_mounts(result, mounts, torque_axis)
        with OutputSet():  # every output or none
            if json_path is not None:
                out = result_to_dict(result, force_unit)
                if estimate is not None:
                    from rigidid.jsonout import estimate_to_dict

                    out["modal_estimation"] = estimate_to_dict(estimate)
                _write_json(json_path, out)
            if uff is not None:
                from rigidid.io.uff import write_uff

                write_uff(
                    uff, result.positions, result.directions, result.sensor_ids, result.identification, result.units
                )
            if csv is not None:
                _write_csv(csv, result, force_unit)
        if json_path != "-":
            from rigidid.render import result_tables

            console = _console()
            if estimate is not None:
                from rigidid.render import estimate_tables

                console.print(estimate_tables(estimate))
            console.print(result_tables(result, force_unit))


@app.command()
def modes(
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json), or a UFF file.", show_default=False)],
    records: Annotated[
        list[Path] | None, typer.Argument(help="One records.csv per impact.", show_default=False)
    ] = None,
    output: Annotated[str, typer.Option("-o", "--output", help="modes.csv to write ('-': standard output).")] = "-",
    modal_method: ModalMethod = None,
    method: Annotated[
        str | None, typer.Option("--method", hidden=True, help="Deprecated name of --modal-method.")
    ] = None,
    n_modes: NModes = 6,
    band: Band = None,
    max_order: MaxOrder = None,
    decimate: Decimate = None,
    json_path: Annotated[
        str | None,
        typer.Option("--json", help="Write the estimation and stabilisation data as JSON to PATH.", metavar="PATH"),
    ] = None,
    units: Units = None,
    geometry: Geometry = None,
    frf: Annotated[
        Path | None, typer.Option("--frf", help="Fit the modes to FRFs (CSV or UFF 58) instead.", show_default=False)
    ] = None,
    references: ReferencesPath = None,
) -> None:
    """Estimate modal parameters from impact records (free decays) or FRFs and write modes.csv."""
    with _reported():
        from rigidid.io.atomic import OutputSet, write_text_atomic
        from rigidid.io.files import modes_csv_text
        from rigidid.jsonout import estimate_to_dict

        if frf is not None:
            _modes_frf(layout, records, frf, references, output, json_path, band, max_order, n_modes)
            return

        if method is not None:
            if modal_method is not None and modal_method != method:
                raise InputError("give --modal-method only (--method is its old name)", source="--method")
            sys.stderr.write("rigidid: warning: modes --method is deprecated; use --modal-method\n")
            modal_method = method
        if output == "-" and json_path == "-":
            raise InputError("standard output cannot take both modes.csv and JSON", source="--json")
        _check_outputs({"--output": output, "--json": json_path})
        _check_options(n_modes=n_modes, band=band, max_order=max_order, decimate=decimate)
        from rigidid import api
        from rigidid.api.records import ModalOptions
        from rigidid.progress import terminal_progress

        modal = ModalOptions(modal_method, n_modes, band, max_order, decimate)
        with terminal_progress() as progress:
            table, estimate = api.estimate_records_modes(
                layout, records or [], modal, units=_parse_units(units), geometry=geometry, progress=progress
            )
        text = modes_csv_text(table)
        with OutputSet() as outs:  # every output or none
            if json_path is not None:
                _write_json(json_path, estimate_to_dict(estimate))
            if output == "-":
                outs.stdout(text)
            else:
                write_text_atomic(output, text)
        if output != "-":
            if json_path != "-":
                from rigidid.render import estimate_tables

                _console().print(estimate_tables(estimate))
            shape = f"{len(table.labels)} modes x {len(table.sensor_ids)} sensors"
            sys.stderr.write(f"rigidid: wrote {shape} to {output}\n")


@app.command()
def simulate(
    body: Annotated[Path, typer.Argument(help="Body on mounts (body.json).", show_default=False)],
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json).", show_default=False)],
    output: Annotated[str, typer.Option("-o", "--output", help="modes.csv to write ('-': standard output).")] = "-",
    frequency_noise: Annotated[float, typer.Option(help="Relative std of frequency noise (0.001 = 0.1 %).")] = 0.0,
    damping_noise: Annotated[float, typer.Option(help="Relative std of damping-ratio noise.")] = 0.0,
    shape_noise: Annotated[float, typer.Option(help="Complex shape noise relative to each mode's RMS.")] = 0.0,
    seed: Annotated[int | None, typer.Option(help="Seed of the noise.")] = None,
    records: Annotated[
        Path | None,
        typer.Option(help="Also write impulse-response records (record-<k>.csv) into DIR.", rich_help_panel=_TIME),
    ] = None,
    impact: Annotated[
        list[str] | None,
        typer.Option(
            help="Impact as X,Y,Z:DX,DY,DZ (position, force direction); repeat for several records "
            "\\[default: two impacts at the first sensors].",
            rich_help_panel=_TIME,
        ),
    ] = None,
    sample_rate: Annotated[float, typer.Option(help="Samples per second.", rich_help_panel=_TIME)] = 512.0,
    duration: Annotated[float, typer.Option(help="Free decay per record (s).", rich_help_panel=_TIME)] = 8.0,
    pretrigger: Annotated[float, typer.Option(help="Record before the impact (s).", rich_help_panel=_TIME)] = 0.1,
    record_noise: Annotated[
        float, typer.Option(help="Noise relative to each channel's RMS.", rich_help_panel=_TIME)
    ] = 0.0,
    frf: Annotated[
        Path | None, typer.Option("--frf", help="Also write accelerance FRFs to PATH (CSV, or UFF for .uff/.unv).")
    ] = None,
    references: ReferencesPath = None,
    frf_noise: Annotated[float, typer.Option(help="Complex FRF noise relative to each value.")] = 0.0,
    frf_format: Annotated[
        str | None,
        typer.Option(
            "--frf-format",
            help="Format of --frf: csv, uff (binary 58b) or uff-ascii (58) \\[default: from the suffix].",
            show_default=False,
        ),
    ] = None,
    mounts: Annotated[
        Path | None,
        typer.Option("--mounts", help="mounts.json whose mounts (with their stiffness) replace the body's."),
    ] = None,
) -> None:
    """Write the exact (or noisy) rigid-body modes of a body on its mounts as modes.csv, and records."""
    with _reported():
        from rigidid import api
        from rigidid.io.atomic import OutputSet, write_text_atomic
        from rigidid.io.files import modes_csv_text
        from rigidid.limits import check_number

        for name, value in (
            ("--frequency-noise", frequency_noise),
            ("--damping-noise", damping_noise),
            ("--shape-noise", shape_noise),
            ("--record-noise", record_noise),
        ):
            check_number(value, name, nonnegative=True)
        _check_options(sample_rate=sample_rate, duration=duration, pretrigger=pretrigger, seed=seed)
        _check_outputs({"--output": output, "--frf": frf}, {"--records": records})
        impacts = [_parse_impact(text) for text in impact] if impact else None
        if mounts is not None:
            body = api.body_with_mounts(body, mounts)  # type: ignore[assignment]
        with named_source(str(body)):
            table = api.simulate(
                body, layout, frequency_noise=frequency_noise, damping_noise=damping_noise, shape_noise=shape_noise,
                seed=seed,
            )  # fmt: skip
        text = modes_csv_text(table)
        with OutputSet() as outs:  # every output or none
            written = []
            if records is not None:
                from rigidid.progress import terminal_progress

                try:
                    with terminal_progress() as progress:
                        written = api.simulate_records(
                            body, layout, records, impacts=impacts, sample_rate=sample_rate, duration=duration,
                            pretrigger=pretrigger, noise=record_noise, seed=seed, progress=progress,
                        )  # fmt: skip
                except InputError as exc:
                    if exc.source == "sample_rate":
                        raise InputError(exc.message, source="--sample-rate/--duration") from None
                    raise
            if frf is not None:
                _simulate_frf(body, layout, frf, references, frf_noise, seed, frf_format)
            if output == "-":
                outs.stdout(text)
            else:
                write_text_atomic(output, text)
        if records is not None:
            sys.stderr.write(f"rigidid: wrote {len(written)} records to {records}\n")
        if output != "-":
            sys.stderr.write(
                f"rigidid: wrote {len(table.labels)} modes x {len(table.sensor_ids)} sensors to {output}\n"
            )


def _modes_frf(
    layout: Path,
    records: list[Path] | None,
    frf: Path,
    references: Path | None,
    output: str,
    json_path: str | None,
    band: tuple[float, float] | None,
    max_order: int | None,
    n_modes: int,
) -> None:
    """``modes --frf``: modes fitted to FRFs (rigidid.api.frf.fit_modes_frf), shapes scaled by the force."""
    from rigidid.api import frf as api_frf
    from rigidid.io.atomic import OutputSet, write_text_atomic
    from rigidid.io.files import modes_csv_text
    from rigidid.jsonout import frf_modes_to_dict
    from rigidid.progress import terminal_progress

    if records:
        raise InputError("give records or --frf, not both", source="--frf")
    if references is None:
        raise InputError("--frf needs --references REFS.json", source="--references")
    if output == "-" and json_path == "-":
        raise InputError("standard output cannot take both modes.csv and JSON", source="--json")
    _check_outputs({"--output": output, "--json": json_path})
    with terminal_progress() as progress:
        table, fitted = api_frf.fit_modes_frf(
            layout, frf, references, band=band, n_modes=n_modes, max_order=max_order, progress=progress
        )
    scaling = ["modal_a" if s else "unit_max" for s in fitted.scaled]
    text = modes_csv_text(table, scaling=scaling)
    with OutputSet() as outs:
        if json_path is not None:
            _write_json(json_path, frf_modes_to_dict(fitted))
        if output == "-":
            outs.stdout(text)
        else:
            write_text_atomic(output, text)
    if output != "-":
        sys.stderr.write(f"rigidid: wrote {len(table.labels)} modes x {len(table.sensor_ids)} sensors to {output}\n")


def _identify_massline(
    layout: Path,
    frf: Path | None,
    references: Path | None,
    *,
    mass: float | None,
    band: tuple[float, float] | None,
    method: str,
    json_path: str | None,
    modes: list[Path] | None = None,
    modes_used: str | None = None,
) -> None:
    """``identify --method massline|residues``: mass, CG and inertia from FRFs (rigidid.api.frf)."""
    from rigidid.api import frf as api_frf
    from rigidid.jsonout import massline_to_dict

    if method not in ("massline", "residues"):
        raise InputError(f"FRFs are identified with --method massline or residues, not {method!r}", source="--method")
    if frf is None:
        raise InputError(f"--method {method} needs --frf FRF.csv", source="--frf")
    if references is None:
        raise InputError("--frf needs --references REFS.json", source="--references")
    modes_file = None
    if method == "residues" and modes:
        if len(modes) != 1:
            raise InputError("--method residues takes one modes.csv (its rigid-body poles)", source="MODES")
        modes_file = modes[0]
    parsed = _parse_modes(modes_used) if method == "residues" else None
    labels = tuple(parsed) if parsed is not None else None
    result = api_frf.identify_massline(
        layout, frf, references, mass=mass, band=band, modes=modes_file, modes_used=labels, method=method
    )
    if json_path is not None:
        _write_json(json_path, massline_to_dict(result))
    if json_path != "-":
        from rigidid.render import massline_tables

        _console().print(massline_tables(result))


def _simulate_frf(
    body: Path,
    layout: Path,
    out: Path,
    references: Path | None,
    noise: float,
    seed: int | None,
    frf_format: str | None = None,
) -> None:
    import numpy as np

    from rigidid.api import frf as api_frf
    from rigidid.io import files
    from rigidid.io.atomic import write_bytes_atomic, write_text_atomic
    from rigidid.io.frf import frf_csv_text, frf_format_from, frf_uff_bytes, load_references, reference_arrays

    if references is None:
        raise InputError("--frf needs --references REFS.json", source="--references")
    if not noise >= 0.0:
        raise InputError(f"must be zero or positive, got {noise}", source="--frf-noise")
    fmt = frf_format_from(out, frf_format)
    if fmt == "csv":
        data = api_frf.simulate_frf(body, layout, references, noise=noise, seed=seed)
        write_text_atomic(out, frf_csv_text(data.frequencies, data.frf, data.sensor_ids, data.reference_ids))
    else:
        lay = files.load_layout(layout, require_rank=False)
        refs = load_references(references)
        data = api_frf.simulate_frf(body, lay, refs, noise=noise, seed=seed)
        # UFF 58 states the abscissa as start and step in 6 digits: simulate on a grid that has them
        step = float(f"{data.frequencies[0]:.5e}")
        grid = step * np.arange(1, data.frequencies.size + 1, dtype=np.float64)
        data = api_frf.simulate_frf(body, lay, refs, frequencies=grid, noise=noise, seed=seed)
        dirs = files.layout_arrays(lay)[2]
        rdirs = reference_arrays(refs)[2]
        try:
            content = frf_uff_bytes(
                data.frequencies, data.frf, data.sensor_ids, dirs, data.reference_ids, rdirs,
                {"length": lay.units.length, "mass": lay.units.mass}, binary=fmt == "uff",
            )  # fmt: skip
        except InputError as exc:
            if exc.source in ("sensors", "references"):
                exc.source = str(layout if exc.source == "sensors" else references)
            raise
        write_bytes_atomic(out, content)
    sys.stderr.write(
        f"rigidid: wrote {len(data.sensor_ids)} x {len(data.reference_ids)} FRFs "
        f"({data.frequencies.size} lines) to {out}\n"
    )


def _parse_impact(text: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    try:
        where, along = text.split(":")
        position = tuple(float(v) for v in where.split(","))
        direction = tuple(float(v) for v in along.split(","))
    except ValueError:
        raise InputError(f"expected X,Y,Z:DX,DY,DZ, got {text!r}", source="--impact") from None
    if len(position) != 3 or len(direction) != 3:
        raise InputError(f"expected X,Y,Z:DX,DY,DZ, got {text!r}", source="--impact")
    from rigidid.limits import check_number

    for value in (*position, *direction):
        check_number(value, "--impact")
    big = max(abs(v) for v in direction)
    if big == 0.0:
        raise InputError(f"the force direction of {text!r} is the zero vector", source="--impact")
    return position, tuple(v / big for v in direction)


@app.command()
def plan(
    layout: Annotated[Path, typer.Argument(help="Planned sensor layout (layout.json or UFF).", show_default=False)],
    body: Annotated[
        Path | None, typer.Option(help="Estimate of the body and mounts (body.json) to predict the uncertainty.")
    ] = None,
    candidates: Annotated[
        Path | None,
        typer.Option(help="Candidate sensors, as a layout.json \\[default: a grid over the sensors' bounding box]."),
    ] = None,
    add: Annotated[int, typer.Option(help="Suggest this many sensors to add, one at a time (needs --body).")] = 0,
    draws: Annotated[int, typer.Option(help="Monte Carlo draws per prediction.", rich_help_panel=_UNC)] = 1000,
    frequency_noise: FrequencyNoise = None,
    damping_noise: DampingNoise = None,
    shape_noise: ShapeNoise = None,
    position_noise: PositionNoise = None,
    angle_noise: AngleNoise = None,
    seed: Seed = 0,
    json_path: JsonPath = None,
    units: Units = None,
    geometry: Geometry = None,
    references: Annotated[
        Path | None,
        typer.Option(
            help="references.json of an FRF test: do its hammer points excite all six rigid-body motions?",
            show_default=False,
        ),
    ] = None,
    mounts: Annotated[
        Path | None,
        typer.Option("--mounts", help="mounts.json: check that the mount layout determines every per-mount rate."),
    ] = None,
) -> None:
    """Check a sensor layout before the test; with a body estimate, predict and improve it."""
    with _reported():
        from rigidid import api
        from rigidid.io.atomic import OutputSet
        from rigidid.jsonout import plan_to_dict

        if draws < 2:
            raise InputError(f"need at least 2 draws, got {draws}", source="--draws")
        _check_options(draws=draws, add=add, seed=seed)
        _check_outputs({"--json": json_path})
        noise = _noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        from rigidid.progress import terminal_progress

        with named_source(str(body) if body is not None else None), terminal_progress() as progress:
            result = api.plan(
                layout, body=body, candidates=candidates, add=add, noise=noise, draws=draws, seed=seed,
                units=_parse_units(units), geometry=geometry, progress=progress, references=references,
                mounts=mounts,
            )  # fmt: skip
        with OutputSet():
            if json_path is not None:
                _write_json(json_path, plan_to_dict(result))
        if json_path != "-":
            from rigidid.render import plan_tables

            _console().print(plan_tables(result))
        if not result.report.ok or (result.references is not None and not result.references.ok):
            raise typer.Exit(EXIT_IDENTIFICATION)


@app.command()
def report(
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json), or a UFF file.", show_default=False)],
    inputs: Inputs = None,
    output: Annotated[Path, typer.Option("-o", "--output", help="The HTML report to write.")] = Path("report.html"),
    png: Annotated[Path | None, typer.Option(help="Also write the figures as PNG files into DIR.")] = None,
    body: Annotated[Path | None, typer.Option(help="body.json whose mounts (and their stiffness) to draw.")] = None,
    title: Annotated[
        str | None, typer.Option(help="Title of the report \\[default: the layout's name, else 'rigidid report'].")
    ] = None,
    records: RecordsFlag = False,
    mass: Mass = None,
    modes_used: ModesUsed = None,
    method: IdMethod = "structured",
    uncertainty: Draws = 0,
    frequency_noise: FrequencyNoise = None,
    damping_noise: DampingNoise = None,
    shape_noise: ShapeNoise = None,
    position_noise: PositionNoise = None,
    angle_noise: AngleNoise = None,
    seed: Seed = 0,
    resample: Resample = 0,
    modal_method: ModalMethod = None,
    n_modes: NModes = 6,
    band: Band = None,
    max_order: MaxOrder = None,
    decimate: Decimate = None,
    units: Units = None,
    geometry: Geometry = None,
    force_unit: ForceUnit = None,
    refine: Refine = True,
    mounts: MountsPath = None,
    torque_axis: TorqueAxis = None,
) -> None:
    """Identify, then write one self-contained HTML report with tables and pictures."""
    with _reported():
        from rigidid import api
        from rigidid.io.atomic import OutputSet, write_text_atomic
        from rigidid.io.files import load_body

        force_unit = _force_unit(force_unit)
        _check_outputs({"--output": output}, {"--png": png})
        noise = _noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        modal = {"method": modal_method, "n_modes": n_modes, "band": band, "max_order": max_order, "decimate": decimate}
        run = _identify(
            layout, inputs, records, units, modal, mass=mass, modes_used=modes_used, method=method, draws=uncertainty,
            noise=noise, seed=seed, resample=resample, geometry=geometry, spectrum=True, refine=refine, mounts=mounts,
        )  # fmt: skip
        result, estimate = run.result, run.estimate
        result = _with_mounts(result, mounts, torque_axis)
        spec = None
        if body is not None:
            spec = load_body(body)
            if dict(spec.units.model_dump()) != dict(result.units):
                raise InputError(
                    f"units {spec.units.length},{spec.units.mass} differ from the layout's "
                    f"{result.units.get('length')},{result.units.get('mass')}",
                    source=str(body),
                    location="units",
                )
        diagram = None if estimate is None else estimate.diagram
        from rigidid.progress import terminal_progress

        with terminal_progress() as progress:
            text = api.report(
                result, stabilisation=diagram, title=title, inputs=[str(p) for p in (layout, *(inputs or []))],
                force_unit=force_unit, body=spec, records=run.records, progress=progress,
                spectrum=run.spectrum,
            )  # fmt: skip
        paths: list[Any] = []
        with OutputSet() as outs:  # every output or none
            write_text_atomic(output, text)
            if png is not None:
                outs.folder(png, option="--png")
                with terminal_progress() as progress:
                    paths = api.report_pngs(
                        result, png, stabilisation=diagram, force_unit=force_unit, body=spec,
                        records=run.records, progress=progress, spectrum=run.spectrum,
                    )  # fmt: skip
        sys.stderr.write(f"rigidid: wrote {output}\n")
        if png is not None:
            sys.stderr.write(f"rigidid: wrote {len(paths)} figures to {png}\n")


@app.command()
def convert(
    uff_file: Annotated[Path, typer.Argument(help="A universal file (.uff, .unv).", show_default=False)],
    output: Annotated[Path, typer.Option("-o", "--output", help="Folder to write into.")] = Path("."),
    units: Units = None,
    geometry: Geometry = None,
    records_format: Annotated[
        str, typer.Option("--records-format", help="Format of the record files: csv, npz, mat, h5 (needs h5py) or wav.")
    ] = "csv",
) -> None:
    """Turn a UFF file into layout.json, modes.csv (dataset 55) and record-<k>.csv (dataset 58)."""
    with _reported():
        from rigidid import api
        from rigidid.io.atomic import OutputSet

        _check_outputs({}, {"--output": output})
        with OutputSet():  # every file or none
            written = api.convert(
                uff_file, output, units=_parse_units(units), geometry=geometry, records_format=records_format
            )
        for path in written:
            sys.stderr.write(f"rigidid: wrote {path}\n")


class _ClosedStdout:
    """Stands for a standard output that was closed (``>&-``): writing to it is a broken pipe."""

    encoding = "utf-8"

    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "standard output is closed")

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


def run(argv: list[str] | None = None) -> int:
    """Run the command line on `argv` (default ``sys.argv[1:]``); return the exit status.

    Every error is one line on standard error: usage errors (status 2) included.
    A standard output that is closed or whose reader has gone raises
    :class:`BrokenPipeError` out of here; :func:`main` turns it into a quiet end.
    """
    from typer import exceptions as typer_exceptions
    from typer._click import exceptions as click_exceptions

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
    except (_StdoutGone, BrokenPipeError):
        raise BrokenPipeError(32, "standard output is closed") from None
    except OSError as exc:
        sys.stderr.write(f"rigidid: error: standard output: {exc.strerror or exc}\n")
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
