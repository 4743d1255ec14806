"""``rigidid convert``: a UFF file to layout.json, modes.csv and record files."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from rigidid.cli.common import check_outputs, parse_units, reported
from rigidid.cli.options import Geometry, Units


def convert(
    uff_file: Annotated[Path, typer.Argument(metavar="UFF", help="A universal file (.uff, .unv).", show_default=False)],
    output: Annotated[Path, typer.Option("-o", "--output", metavar="DIR", help="Folder to write into.")] = Path("."),
    units: Units = None,
    geometry: Geometry = None,
    records_format: Annotated[
        str,
        typer.Option(
            "--records-format",
            metavar="FORMAT",
            help="Format of the record files: csv, npz, mat, h5 (needs h5py) or wav.",
        ),
    ] = "csv",
) -> None:
    """Turn a UFF file into layout.json, modes.csv (dataset 55) and record-<k>.csv (dataset 58)."""
    with reported():
        from rigidid import api
        from rigidid.io.atomic import OutputSet

        check_outputs({}, {"--output": output})
        with OutputSet():  # every file or none
            written = api.convert(
                uff_file, output, units=parse_units(units), geometry=geometry, records_format=records_format
            )
        for path in written:
            sys.stderr.write(f"rigidid: wrote {path}\n")
