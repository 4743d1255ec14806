"""``rigidid simulate``: modes, impact records or FRFs of a body on mounts."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rigidid.cli.common import check_options, check_outputs, old_name, reported
from rigidid.cli.options import (
    Duration,
    FrfFormat,
    Impacts,
    Pretrigger,
    RecordNoise,
    RecordsOut,
    ReferencesPath,
    SampleRate,
)
from rigidid.cli.plan import parse_impact
from rigidid.errors import InputError, named_source

if TYPE_CHECKING:
    from rigidid.io.files import ModeTable


def simulate(
    body: Annotated[Path, typer.Argument(metavar="BODY", help="Body on mounts (body.json).", show_default=False)],
    layout: Annotated[Path, typer.Argument(metavar="LAYOUT", help="Sensor layout (layout.json).", show_default=False)],
    output: Annotated[
        str, typer.Option("-o", "--output", help="modes.csv to write ('-': standard output).", metavar="FILE")
    ] = "-",
    frequency_noise: Annotated[
        float, typer.Option("--add-frequency-noise", help="Add noise: relative std of frequencies.", metavar="X")
    ] = 0.0,
    damping_noise: Annotated[
        float, typer.Option("--add-damping-noise", help="Add noise: relative std of damping ratios.", metavar="X")
    ] = 0.0,
    shape_noise: Annotated[
        float, typer.Option("--add-shape-noise", help="Add complex shape noise (of each mode RMS).", metavar="X")
    ] = 0.0,
    seed: Annotated[int | None, typer.Option(help="Seed of the noise.", metavar="N")] = None,
    records: RecordsOut = None,
    impact: Impacts = None,
    sample_rate: SampleRate = 512.0,
    duration: Duration = 8.0,
    pretrigger: Pretrigger = 0.1,
    record_noise: RecordNoise = 0.0,
    frf: Annotated[
        Path | None,
        typer.Option(
            "--write-frf", help="Also write accelerance FRFs to FILE (CSV, or UFF for .uff/.unv).", metavar="FILE"
        ),
    ] = None,
    references: ReferencesPath = None,
    frf_noise: Annotated[
        float, typer.Option("--add-frf-noise", help="Add complex FRF noise relative to each value.", metavar="X")
    ] = 0.0,
    frf_format: FrfFormat = None,
    mounts: Annotated[
        Path | None,
        typer.Option(
            "--mounts", help="mounts.json whose mounts (with their stiffness) replace the body's.", metavar="FILE"
        ),
    ] = None,
    old_frequency: Annotated[float | None, typer.Option("--frequency-noise", hidden=True)] = None,
    old_damping: Annotated[float | None, typer.Option("--damping-noise", hidden=True)] = None,
    old_shape: Annotated[float | None, typer.Option("--shape-noise", hidden=True)] = None,
    old_records: Annotated[Path | None, typer.Option("--records", hidden=True)] = None,
    old_record_noise: Annotated[float | None, typer.Option("--record-noise", hidden=True)] = None,
    old_frf: Annotated[Path | None, typer.Option("--frf", hidden=True)] = None,
    old_frf_noise: Annotated[float | None, typer.Option("--frf-noise", hidden=True)] = None,
) -> None:
    """Write the exact (or noisy) rigid-body modes of a body on its mounts as modes.csv, and records."""
    with reported():
        renamed = _old_names(
            (old_frequency, frequency_noise, "frequency"), (old_damping, damping_noise, "damping"),
            (old_shape, shape_noise, "shape"), (old_record_noise, record_noise, "record"),
            (old_frf_noise, frf_noise, "frf"),
        )  # fmt: skip
        frequency_noise, damping_noise, shape_noise, record_noise, frf_noise = renamed
        records = old_name("simulate", "--records", "--write-records", old_records, records, None)
        frf = old_name("simulate", "--frf", "--write-frf", old_frf, frf, None)
        from rigidid import api
        from rigidid.limits import check_number

        for kind, value in zip(("frequency", "damping", "shape", "record", "frf"), renamed, strict=True):
            check_number(value, f"--add-{kind}-noise", nonnegative=True)
        check_options(sample_rate=sample_rate, duration=duration, pretrigger=pretrigger, seed=seed)
        check_outputs({"--output": output, "--write-frf": frf}, {"--write-records": records})
        impacts = [parse_impact(text) for text in impact] if impact else None
        if mounts is not None:
            body = api.body_with_mounts(body, mounts)  # type: ignore[assignment]
        with named_source(str(mounts if mounts is not None else body)):
            table = api.simulate(
                body, layout, frequency_noise=frequency_noise, damping_noise=damping_noise, shape_noise=shape_noise,
                seed=seed,
            )  # fmt: skip
        _publish(
            table, body, layout, output=output, records=records, frf=frf, references=references, frf_noise=frf_noise,
            seed=seed, frf_format=frf_format,
            record_options={"impacts": impacts, "sample_rate": sample_rate, "duration": duration,
                            "pretrigger": pretrigger, "noise": record_noise, "seed": seed},
        )  # fmt: skip


def _publish(
    table: ModeTable,
    body: Path,
    layout: Path,
    *,
    output: str,
    records: Path | None,
    frf: Path | None,
    references: Path | None,
    frf_noise: float,
    seed: int | None,
    frf_format: str | None,
    record_options: dict[str, Any],
) -> None:
    """Every output of ``simulate`` or none: modes.csv, the records, the FRFs."""
    from rigidid.io.atomic import OutputSet, write_text_atomic
    from rigidid.io.files import modes_csv_text

    text = modes_csv_text(table)
    with OutputSet() as outs:  # every output or none
        written = []
        if records is not None:
            written = _simulate_records(body, layout, records, **record_options)
        if frf is not None:
            _simulate_frf(body, layout, frf, references, frf_noise, seed, frf_format)
        if output == "-":
            outs.stdout(text)
        else:
            write_text_atomic(output, text)
    if records is not None:
        sys.stderr.write(f"rigidid: wrote {len(written)} records to {records}\n")
    if output != "-":
        sys.stderr.write(f"rigidid: wrote {len(table.labels)} modes x {len(table.sensor_ids)} sensors to {output}\n")


def _old_names(*given: tuple[float | None, float, str]) -> list[float]:
    """The noise options by their old names (``--frequency-noise``...), with a warning: now ``--add-...-noise``."""
    return [
        old_name("simulate", f"--{kind}-noise", f"--add-{kind}-noise", old_value, value, 0.0)
        for old_value, value, kind in given
    ]


def _simulate_records(body: Path, layout: Path, records: Path, **options: Any) -> list[Path]:
    """``simulate --records DIR``: the impact records written; a record length the rate cannot fill blames both."""
    from rigidid import api
    from rigidid.progress import terminal_progress

    try:
        with terminal_progress() as progress:
            written: list[Path] = api.simulate_records(body, layout, records, progress=progress, **options)
            return written
    except InputError as exc:
        if exc.source == "sample_rate":
            raise InputError(exc.message, source="--sample-rate/--duration") from None
        raise


def _simulate_frf(
    body: Path,
    layout: Path,
    out: Path,
    references: Path | None,
    noise: float,
    seed: int | None,
    frf_format: str | None = None,
) -> None:
    """``simulate --write-frf FILE``: the API writes the FRFs; the options named in its refusals."""
    from rigidid.api.simulation import write_simulated_frf

    try:
        data = write_simulated_frf(body, layout, references, out, noise=noise, seed=seed, frf_format=frf_format)
    except InputError as exc:
        if exc.source in ("references", "frf_noise"):
            flag = "--references" if exc.source == "references" else "--add-frf-noise"
            message = "--write-frf needs --references REFS.json" if exc.source == "references" else exc.message
            raise InputError(message, source=flag) from None
        raise
    sys.stderr.write(
        f"rigidid: wrote {len(data.sensor_ids)} x {len(data.reference_ids)} FRFs "
        f"({data.frequencies.size} lines) to {out}\n"
    )
