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
from rigidid.errors import InputError, RigididError

if TYPE_CHECKING:
    from rigidid.api import IdentifyResult, TestData
    from rigidid.core.timedomain import ModalEstimate

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
    str, typer.Option(help="structured (default, robust) or paper (the paper's eqs. 25-26 and 36-40).")
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
    typer.Option(help="Relative std of natural frequencies [default: 0.001].", rich_help_panel=_UNC),
]
DampingNoise = Annotated[
    float | None, typer.Option(help="Relative std of damping ratios [default: 0.05].", rich_help_panel=_UNC)
]
ShapeNoise = Annotated[
    float | None,
    typer.Option(
        help="Std of shape values relative to each mode's RMS [default: from the rigid-body fit with more than "
        "six sensors, else 0.01].",
        rich_help_panel=_UNC,
    ),
]
PositionNoise = Annotated[
    float | None, typer.Option(help="Std of sensor positions (length unit) [default: 0].", rich_help_panel=_UNC)
]
AngleNoise = Annotated[
    float | None, typer.Option(help="Std of sensor directions (degrees) [default: 0].", rich_help_panel=_UNC)
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
    str | None, typer.Option(help="Modal estimator for records: era or ar [default: era].", rich_help_panel=_TIME)
]
Band = Annotated[
    tuple[float, float] | None,
    typer.Option(help="Frequency band of the modes (Hz).", metavar="FMIN FMAX", rich_help_panel=_TIME),
]
MaxOrder = Annotated[int | None, typer.Option(help="Highest model order of the sweep.", rich_help_panel=_TIME)]
Decimate = Annotated[
    int | None, typer.Option(help="Decimation factor [default: from the spectrum].", rich_help_panel=_TIME)
]
NModes = Annotated[
    int, typer.Option(help="Modes to estimate from records (more than 6 when elastic modes share the band).")
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


# ----------------------------------------------------------------------------- helpers


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
                if text not in seen and issubclass(w.category, UserWarning):
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


def _parse_units(text: str | None) -> dict[str, str] | None:
    if text is None:
        return None
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2:
        raise InputError(f"expected LENGTH,MASS like in,lb, got {text!r}", source="--units")
    return {"length": parts[0], "mass": parts[1]}


def _noise_overrides(**given: float | None) -> dict[str, float]:
    names = {"angle_deg": "--angle-noise"}
    out: dict[str, float] = {}
    for key, value in given.items():
        if value is None:
            continue
        if not value >= 0.0:
            raise InputError(f"must be zero or positive, got {value}", source=names.get(key, f"--{key}-noise"))
        out[key] = value
    return out


def _write_json(target: str, data: dict[str, Any]) -> None:
    from rigidid.io.atomic import write_text_atomic

    text = json.dumps(data, indent=2) + "\n"
    if target == "-":
        sys.stdout.write(text)
    else:
        write_text_atomic(target, text)


def _test_data(layout: Path, inputs: list[Path], records: bool, units: str | None) -> TestData:
    """The layout and its modes or records, from JSON/CSV files or one UFF file."""
    from rigidid import api

    if layout.suffix.lower() in UFF_SUFFIXES:
        if inputs:
            raise InputError("with a UFF file, give no other input files", source=str(inputs[0]))
        data = api.load_uff(layout, units=_parse_units(units))
        if records and not data.records:
            raise InputError("no time records (dataset 58) in the file", source=str(layout))
        if not records and data.modes is None:
            raise InputError("no modes (dataset 55) in the file; with time records pass --records", source=str(layout))
        return data
    lay = api.load_layout(layout)
    if records:
        if not inputs:
            raise InputError("no records: give one records.csv per impact", source="RECORDS")
        return api.TestData(lay, None, api.load_records(inputs, lay), [str(p) for p in inputs])
    if len(inputs) != 1:
        message = "give one modes.csv" if not inputs else "give one modes.csv (several files: records? pass --records)"
        raise InputError(message, source="MODES")
    return api.TestData(lay, api.load_modes(inputs[0], lay))


def _estimate(
    data: TestData,
    method: str | None,
    n_modes: int,
    band: tuple[float, float] | None,
    max_order: int | None,
    decimate: int | None,
) -> ModalEstimate:
    from rigidid import api
    from rigidid.core.timedomain import METHODS

    if method is not None and method not in METHODS:
        raise InputError(f"unknown method {method!r}; choose {' or '.join(METHODS)}", source="--modal-method")
    from rigidid.progress import terminal_progress

    with terminal_progress() as progress:
        _, estimate = api.estimate_modes(
            data.layout, data.records, method=method, n_modes=n_modes, band=band, max_order=max_order,
            decimate=decimate, progress=progress,
        )  # fmt: skip
    return estimate


def _identify(
    layout: Path,
    inputs: list[Path] | None,
    records: bool,
    units: str | None,
    modal: dict[str, Any],
    *,
    mass: float | None,
    modes_used: str | None,
    method: str,
    draws: int,
    noise: dict[str, float],
    seed: int,
    resample: int = 0,
    refine: bool = True,
) -> tuple[IdentifyResult, ModalEstimate | None]:
    """Load the test, estimate its modes from records if asked, identify: what identify and report share."""
    from rigidid import api
    from rigidid.core.identify import METHODS
    from rigidid.io.files import ModeTable

    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; choose {' or '.join(METHODS)}", source="--method")
    if draws < 0:
        raise InputError(f"must be zero or positive, got {draws}", source="--uncertainty")
    data = _test_data(layout, inputs or [], records, units)
    estimate = _estimate(data, **modal) if records else None
    modes = data.modes
    if estimate is not None:
        ids = tuple(s.id for s in data.layout.sensors)
        labels = tuple(range(1, len(estimate.frequency_hz) + 1))
        modes = ModeTable(labels, estimate.frequency_hz, estimate.damping_ratio, ids, estimate.shapes)
    assert modes is not None
    result = api.identify(
        data.layout,
        modes,
        mass=mass,
        modes_used=_parse_modes(modes_used),
        method=method,  # type: ignore[arg-type]
        uncertainty=draws,
        noise=noise,
        seed=seed,
    )
    if refine and estimate is not None and method == "structured":
        from rigidid.progress import terminal_progress

        with terminal_progress() as progress:
            result = api.with_refinement(result, data.records, estimate, progress=progress)
    if resample:
        if not records:
            raise InputError("data-driven intervals need impact records (--records)", source="--resample")
        options = {key: modal[key] for key in ("method", "band", "max_order") if modal[key] is not None}
        result = api.with_record_spread(
            result, data.records, segments=resample, n_modes=modal["n_modes"], estimate_options=options
        )
    return result, estimate


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
    refine: Refine = True,
) -> None:
    """Identify CG, inertia tensor, stiffness and damping from a layout and its modes (or impact records)."""
    with _reported():
        from rigidid.render import result_to_dict

        noise = _noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        modal = {"method": modal_method, "n_modes": n_modes, "band": band, "max_order": max_order, "decimate": decimate}
        result, estimate = _identify(
            layout, inputs, records, units, modal, mass=mass, modes_used=modes_used, method=method, draws=uncertainty,
            noise=noise, seed=seed, resample=resample, refine=refine,
        )  # fmt: skip
        if json_path is not None:
            out = result_to_dict(result)
            if estimate is not None:
                from rigidid.render import estimate_to_dict

                out["modal_estimation"] = estimate_to_dict(estimate)
            _write_json(json_path, out)
        if uff is not None:
            from rigidid.io.uff import write_uff

            write_uff(uff, result.positions, result.directions, result.sensor_ids, result.identification, result.units)
        if json_path != "-":
            from rigidid.render import result_tables

            console = _console()
            if estimate is not None:
                from rigidid.render import estimate_tables

                console.print(estimate_tables(estimate))
            console.print(result_tables(result))


@app.command()
def modes(
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json), or a UFF file.", show_default=False)],
    records: Annotated[
        list[Path] | None, typer.Argument(help="One records.csv per impact.", show_default=False)
    ] = None,
    output: Annotated[str, typer.Option("-o", "--output", help="modes.csv to write ('-': standard output).")] = "-",
    method: Annotated[str | None, typer.Option(help="era or ar [default: era].")] = None,
    n_modes: NModes = 6,
    band: Band = None,
    max_order: MaxOrder = None,
    decimate: Decimate = None,
    json_path: Annotated[
        str | None,
        typer.Option("--json", help="Write the estimation and stabilisation data as JSON to PATH.", metavar="PATH"),
    ] = None,
    units: Units = None,
) -> None:
    """Estimate modal parameters from impact records (free decays) and write modes.csv."""
    with _reported():
        from rigidid.io.atomic import write_text_atomic
        from rigidid.io.files import ModeTable, modes_csv_text
        from rigidid.render import estimate_to_dict

        data = _test_data(layout, records or [], True, units)
        estimate = _estimate(data, method, n_modes, band, max_order, decimate)
        ids = tuple(s.id for s in data.layout.sensors)
        labels = tuple(range(1, len(estimate.frequency_hz) + 1))
        text = modes_csv_text(ModeTable(labels, estimate.frequency_hz, estimate.damping_ratio, ids, estimate.shapes))
        if json_path is not None:
            _write_json(json_path, estimate_to_dict(estimate))
        if output == "-":
            if json_path == "-":
                raise InputError("standard output cannot take both modes.csv and JSON", source="--json")
            sys.stdout.write(text)
        else:
            write_text_atomic(output, text)
            if json_path != "-":
                from rigidid.render import estimate_tables

                _console().print(estimate_tables(estimate))
            sys.stderr.write(f"rigidid: wrote {len(labels)} modes x {len(ids)} sensors to {output}\n")


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
            "[default: two impacts at the first sensors].",
            rich_help_panel=_TIME,
        ),
    ] = None,
    sample_rate: Annotated[float, typer.Option(help="Samples per second.", rich_help_panel=_TIME)] = 512.0,
    duration: Annotated[float, typer.Option(help="Free decay per record (s).", rich_help_panel=_TIME)] = 8.0,
    pretrigger: Annotated[float, typer.Option(help="Record before the impact (s).", rich_help_panel=_TIME)] = 0.1,
    record_noise: Annotated[
        float, typer.Option(help="Noise relative to each channel's RMS.", rich_help_panel=_TIME)
    ] = 0.0,
) -> None:
    """Write the exact (or noisy) rigid-body modes of a body on its mounts as modes.csv, and records."""
    with _reported():
        from rigidid import api
        from rigidid.io.atomic import write_text_atomic
        from rigidid.io.files import modes_csv_text

        for name, value in (
            ("--frequency-noise", frequency_noise),
            ("--damping-noise", damping_noise),
            ("--shape-noise", shape_noise),
            ("--record-noise", record_noise),
        ):
            if not value >= 0.0:
                raise InputError(f"must be zero or positive, got {value}", source=name)
        table = api.simulate(
            body, layout, frequency_noise=frequency_noise, damping_noise=damping_noise, shape_noise=shape_noise,
            seed=seed,
        )  # fmt: skip
        if records is not None:
            written = api.simulate_records(
                body,
                layout,
                records,
                impacts=[_parse_impact(text) for text in impact] if impact else None,
                sample_rate=sample_rate,
                duration=duration,
                pretrigger=pretrigger,
                noise=record_noise,
                seed=seed,
            )
            sys.stderr.write(f"rigidid: wrote {len(written)} records to {records}\n")
        text = modes_csv_text(table)
        if output == "-":
            sys.stdout.write(text)
        else:
            write_text_atomic(output, text)
            sys.stderr.write(
                f"rigidid: wrote {len(table.labels)} modes x {len(table.sensor_ids)} sensors to {output}\n"
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
    return position, direction


@app.command()
def plan(
    layout: Annotated[Path, typer.Argument(help="Planned sensor layout (layout.json or UFF).", show_default=False)],
    body: Annotated[
        Path | None, typer.Option(help="Estimate of the body and mounts (body.json) to predict the uncertainty.")
    ] = None,
    candidates: Annotated[
        Path | None,
        typer.Option(help="Candidate sensors, as a layout.json [default: a grid over the sensors' bounding box]."),
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
) -> None:
    """Check a sensor layout before the test; with a body estimate, predict and improve it."""
    with _reported():
        from rigidid import api
        from rigidid.render import plan_to_dict

        if draws < 2:
            raise InputError(f"need at least 2 draws, got {draws}", source="--draws")
        noise = _noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        result = api.plan(layout, body=body, candidates=candidates, add=add, noise=noise, draws=draws, seed=seed)
        if json_path is not None:
            _write_json(json_path, plan_to_dict(result))
        if json_path != "-":
            from rigidid.render import plan_tables

            _console().print(plan_tables(result))
        if not result.report.ok:
            raise typer.Exit(EXIT_IDENTIFICATION)


@app.command()
def report(
    layout: Annotated[Path, typer.Argument(help="Sensor layout (layout.json), or a UFF file.", show_default=False)],
    inputs: Inputs = None,
    output: Annotated[Path, typer.Option("-o", "--output", help="The HTML report to write.")] = Path("report.html"),
    png: Annotated[Path | None, typer.Option(help="Also write the figures as PNG files into DIR.")] = None,
    body: Annotated[Path | None, typer.Option(help="body.json whose mounts to draw.")] = None,
    title: Annotated[str, typer.Option(help="Title of the report.")] = "rigidid report",
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
    refine: Refine = True,
) -> None:
    """Identify, then write one self-contained HTML report with tables and pictures."""
    with _reported():
        from rigidid import api
        from rigidid.io.atomic import write_text_atomic
        from rigidid.io.files import load_body

        noise = _noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        modal = {"method": modal_method, "n_modes": n_modes, "band": band, "max_order": max_order, "decimate": decimate}
        result, estimate = _identify(
            layout, inputs, records, units, modal, mass=mass, modes_used=modes_used, method=method, draws=uncertainty,
            noise=noise, seed=seed, resample=resample, refine=refine,
        )  # fmt: skip
        mounts = None
        if body is not None:
            mounts = [m.position for m in load_body(body).mounts]
        diagram = None if estimate is None else estimate.diagram
        write_text_atomic(output, api.report(result, mounts=mounts, stabilisation=diagram, title=title))
        sys.stderr.write(f"rigidid: wrote {output}\n")
        if png is not None:
            from rigidid.reporting import save_pngs

            png.mkdir(parents=True, exist_ok=True)
            paths = save_pngs(
                png, result.identification, result.positions, result.directions, result.sensor_ids, result.units,
                mounts=mounts, stabilisation=diagram,
            )  # fmt: skip
            sys.stderr.write(f"rigidid: wrote {len(paths)} figures to {png}\n")


@app.command()
def convert(
    uff_file: Annotated[Path, typer.Argument(help="A universal file (.uff, .unv).", show_default=False)],
    output: Annotated[Path, typer.Option("-o", "--output", help="Folder to write into.")] = Path("."),
    units: Units = None,
) -> None:
    """Turn a UFF file into layout.json, modes.csv (dataset 55) and record-<k>.csv (dataset 58)."""
    with _reported():
        from rigidid import api

        for path in api.convert(uff_file, output, units=_parse_units(units)):
            sys.stderr.write(f"rigidid: wrote {path}\n")


def main() -> None:
    """Entry point of the ``rigidid`` console script."""
    app(prog_name="rigidid")
