"""``rigidid plan``: check a sensor layout (and hammer points) before the test, predict and improve it."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rigidid.cli.common import (
    EXIT_IDENTIFICATION,
    check_options,
    check_outputs,
    noise_overrides,
    old_name,
    one_line,
    parse_units,
    reported,
    stage_tables,
    write_json,
)
from rigidid.cli.options import (
    RECORDS_PANEL,
    UNCERTAINTY_PANEL,
    AngleNoise,
    DampingNoise,
    FrequencyNoise,
    Geometry,
    Impacts,
    JsonPath,
    PositionNoise,
    Seed,
    ShapeNoise,
    Units,
)
from rigidid.errors import InputError, named_source

if TYPE_CHECKING:
    from rigidid.results import PlanResult


PlanMounts = Annotated[
    Path | None,
    typer.Option(
        "--mounts", metavar="FILE", help="mounts.json: check that the mount layout determines every per-mount rate."
    ),
]
PlanRecords = Annotated[
    bool,
    typer.Option(
        "--records",
        help="The test will be impact records: with --body, predict the sensor budget identify --records will "
        "report (the refit's own) for the impacts, rate and duration given.",
        rich_help_panel=RECORDS_PANEL,
    ),
]
PlannedRate = Annotated[
    float | None,
    typer.Option(
        help="Samples per second of the planned records (implies --records) \\[default: 512].",
        metavar="HZ",
        rich_help_panel=RECORDS_PANEL,
        show_default=False,
    ),
]
PlannedNoise = Annotated[
    float | None,
    typer.Option(
        help="Noise of the planned records, relative to each channel's RMS over the free decay (implies --records) "
        "\\[default: 0.01].",
        metavar="X",
        rich_help_panel=RECORDS_PANEL,
        show_default=False,
    ),
]
PlannedDuration = Annotated[
    float | None,
    typer.Option(
        help="Free decay per planned record, s (implies --records) \\[default: 8].",
        metavar="S",
        rich_help_panel=RECORDS_PANEL,
        show_default=False,
    ),
]


def plan(
    layout: Annotated[
        Path, typer.Argument(metavar="LAYOUT", help="Planned sensor layout (layout.json or UFF).", show_default=False)
    ],
    body: Annotated[
        Path | None,
        typer.Option(metavar="FILE", help="Estimate of the body and mounts (body.json) to predict the uncertainty."),
    ] = None,
    candidates: Annotated[
        Path | None,
        typer.Option(
            metavar="FILE",
            help="Candidate sensors, as a layout.json \\[default: a grid over the sensors' bounding box].",
        ),
    ] = None,
    add: Annotated[
        int, typer.Option(metavar="K", help="Suggest this many sensors to add, one at a time (needs --body).")
    ] = 0,
    draws: Annotated[
        int,
        typer.Option(
            "--uncertainty", help="Monte Carlo draws per prediction.", metavar="N", rich_help_panel=UNCERTAINTY_PANEL
        ),
    ] = 1000,
    draws_old: Annotated[int | None, typer.Option("--draws", hidden=True)] = None,
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
            metavar="FILE",
            help="references.json of an FRF test: do its hammer points excite all six rigid-body motions?",
            show_default=False,
        ),
    ] = None,
    mounts: PlanMounts = None,
    records: PlanRecords = False,
    impact: Impacts = None,
    sample_rate: PlannedRate = None,
    duration: PlannedDuration = None,
    record_noise: PlannedNoise = None,
) -> None:
    """Check a sensor layout before the test; with a body estimate, predict and improve it."""
    with reported():
        from rigidid import api
        from rigidid.io.atomic import OutputSet
        from rigidid.jsonout import plan_to_dict

        draws = _checked_draws(draws_old, draws)
        check_options(add=add, seed=seed)
        check_outputs({"--json": json_path})
        test = _planned_test(records, impact, sample_rate, duration, record_noise)
        noise = noise_overrides(
            frequency=frequency_noise, damping=damping_noise, shape=shape_noise, position=position_noise,
            angle_deg=angle_noise,
        )  # fmt: skip
        from rigidid.progress import terminal_progress

        with named_source(str(body) if body is not None else None), terminal_progress() as progress:
            result = api.plan(
                layout, body=body, candidates=candidates, add=add, noise=noise, draws=draws, seed=seed,
                units=parse_units(units, layout), geometry=geometry, progress=progress, references=references,
                mounts=mounts, **test,
            )  # fmt: skip
        with OutputSet():  # a verdict (exit 1) writes its report too: standard output first, then the file
            if json_path is not None:
                write_json(json_path, plan_to_dict(result))
            if json_path != "-":
                from rigidid.render import plan_tables

                stage_tables(plan_tables(result))
        if not result.report.ok or (result.references is not None and not result.references.ok):
            _verdict(result, layout, references)
            raise typer.Exit(EXIT_IDENTIFICATION)


def _checked_draws(draws_old: int | None, draws: int) -> int:
    """``--uncertainty`` (or its old name ``--draws``), at least 2."""
    from rigidid.limits import check_count

    draws = old_name("plan", "--draws", "--uncertainty", draws_old, draws, 1000)
    if draws < 2:
        raise InputError(f"need at least 2 draws, got {draws}", source="--uncertainty")
    check_count(draws, "--uncertainty", low=2, high=1_000_000)
    return draws


def _planned_test(
    records: bool, impact: list[str] | None, sample_rate: float | None, duration: float | None, noise: float | None
) -> dict[str, Any]:
    """The planned records test's options checked, as :func:`rigidid.api.plan`'s arguments (impacts parsed)."""
    from rigidid.limits import check_number

    for value, flag in ((sample_rate, "--sample-rate"), (duration, "--duration"), (noise, "--record-noise")):
        check_number(value, flag, positive=True)
    impacts = [parse_impact(text) for text in impact] if impact else None
    return {"records": records, "impacts": impacts, "sample_rate": sample_rate, "duration": duration,
            "record_noise": noise}  # fmt: skip


def _verdict(result: PlanResult, layout: Path, references: Path | None) -> None:
    """One line on stderr for plan's exit-1 verdict, naming the file at fault (its report is written too)."""
    if not result.report.ok:
        first = next(f for f in result.report.findings if f.severity == "error")
        sys.stderr.write(f"rigidid: error: {one_line(f'{layout}: the layout is not usable: {first.message}')}\n")
    elif result.references is not None:
        statement = result.references.statement.split(". ")[0].rstrip(".")
        sys.stderr.write(f"rigidid: error: {one_line(f'{references}: the references are not usable: {statement}')}\n")


def parse_impact(text: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
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
