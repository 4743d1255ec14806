"""``rigidid convert``: a UFF file to layout.json, modes.csv and record files."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rigidid.api.load import load_uff
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.atomic import write_text_atomic
from rigidid.results import PathLike


def convert(
    path: PathLike,
    directory: PathLike,
    *,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
    records_format: str = "csv",
) -> list[Path]:
    """Turn a universal file into ``layout.json``, ``modes.csv`` and ``record-<k>.csv`` files.

    Parameters
    ----------
    path : path-like
        The ``.uff``/``.unv`` file (see :func:`load_uff`).
    directory : path-like
        Folder to write into (created if needed).
    units : dict, optional
        ``{"length", "mass"}`` when the file has no dataset 164.
    geometry : path-like, optional
        A UFF file completing `path` (see :func:`load_uff`).
    records_format : {"csv", "npz", "mat", "h5", "wav"}
        File format of the records (``record-<k>.<format>``; layouts in ``docs/FORMATS.md``).

    Returns
    -------
    list of Path
        The files written (atomically) in `directory`.
    """
    import json

    if records_format not in ("csv", "npz", "mat", "h5", "wav"):
        raise InputError(f"records format {records_format!r}: one of csv, npz, mat, h5, wav", source="records_format")
    from rigidid.io.atomic import check_folder, transaction
    from rigidid.io.records import write_record

    check_folder(directory)
    data = load_uff(path, units=units, geometry=geometry)
    with transaction() as outs:  # all files or none
        folder = outs.folder(directory)
        written = [folder / "layout.json"]
        write_text_atomic(written[0], json.dumps(data.layout.model_dump(exclude_none=True), indent=2) + "\n")
        if data.modes is not None:
            written.append(folder / "modes.csv")
            # 17 digits: the numbers the UFF file holds, unrounded (identify on the converted files
            # then matches identify on the UFF file to rounding)
            write_text_atomic(written[-1], files.modes_csv_text(data.modes, digits=17))
        ids = [s.id for s in data.layout.sensors]
        for k, (values, dt) in enumerate(data.records, start=1):
            written.append(folder / f"record-{k}.{records_format}")
            if records_format == "csv":
                write_record(written[-1], np.arange(values.shape[0]) * dt, values, ids)
            else:
                from rigidid.io.records.binary import write_binary
                from rigidid.io.uff import UFF_STEP_DIGITS

                write_binary(written[-1], np.arange(values.shape[0]) * dt, values, ids, step_digits=UFF_STEP_DIGITS)
    return written
