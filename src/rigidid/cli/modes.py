"""``rigidid modes``: modal parameters from impact records or FRFs, written as modes.csv."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from rigidid.cli.common import check_options, check_outputs, parse_units, reported, stage_tables, write_json
from rigidid.cli.options import Band, Decimate, Geometry, MaxOrder, ModalMethod, NModes, ReferencesPath, Units
from rigidid.errors import InputError


def modes(
    layout: Annotated[
        Path, typer.Argument(metavar="LAYOUT", help="Sensor layout (layout.json), or a UFF file.", show_default=False)
    ],
    records: Annotated[
        list[Path] | None, typer.Argument(metavar="RECORDS", help="One records.csv per impact.", show_default=False)
    ] = None,
    output: Annotated[
        str, typer.Option("-o", "--output", metavar="FILE", help="modes.csv to write ('-': standard output).")
    ] = "-",
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
        Path | None,
        typer.Option(
            "--frf", metavar="FILE", help="Fit the modes to FRFs (CSV or UFF 58) instead.", show_default=False
        ),
    ] = None,
    references: ReferencesPath = None,
) -> None:
    """Estimate modal parameters from impact records (free decays) or FRFs and write modes.csv."""
    with reported():
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
        check_outputs({"--output": output, "--json": json_path})
        check_options(n_modes=n_modes, band=band, max_order=max_order, decimate=decimate)
        from rigidid import api
        from rigidid.api.records import ModalOptions
        from rigidid.progress import terminal_progress

        modal = ModalOptions(modal_method, n_modes, band, max_order, decimate)
        try:
            with terminal_progress() as progress:
                table, estimate = api.estimate_records_modes(
                    layout, records or [], modal, units=parse_units(units, layout), geometry=geometry, progress=progress
                )
        except InputError as exc:  # name the option the user typed, the deprecated one included
            if exc.source == "modal_method" and method is not None:
                exc.source = "--method"
            raise
        text = modes_csv_text(table)
        with OutputSet() as outs:  # every output or none
            if json_path is not None:
                write_json(json_path, estimate_to_dict(estimate))
            if output == "-":
                outs.stdout(text)
            else:
                write_text_atomic(output, text)
                if json_path != "-":
                    from rigidid.render import estimate_tables

                    stage_tables(estimate_tables(estimate))
        if output != "-":
            shape = f"{len(table.labels)} modes x {len(table.sensor_ids)} sensors"
            sys.stderr.write(f"rigidid: wrote {shape} to {output}\n")


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
    if output == "-" and json_path == "-":
        raise InputError("standard output cannot take both modes.csv and JSON", source="--json")
    check_options(n_modes=n_modes, band=band, max_order=max_order)
    check_outputs({"--output": output, "--json": json_path})
    with terminal_progress() as progress:
        table, fitted = api_frf.fit_modes_frf(
            layout, frf, references, band=band, n_modes=n_modes, max_order=max_order, progress=progress
        )
    scaling = ["modal_a" if s else "unit_max" for s in fitted.scaled]
    text = modes_csv_text(table, scaling=scaling)
    with OutputSet() as outs:
        if json_path is not None:
            write_json(json_path, frf_modes_to_dict(fitted))
        if output == "-":
            outs.stdout(text)
        else:
            write_text_atomic(output, text)
    if output != "-":
        sys.stderr.write(f"rigidid: wrote {len(table.labels)} modes x {len(table.sensor_ids)} sensors to {output}\n")
