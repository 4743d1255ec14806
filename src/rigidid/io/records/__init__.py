"""Impact records: files read as blocks of rows and checked; no signal processing here.

One record per impact, in any of the formats of ``docs/FORMATS.md``:

- :mod:`~rigidid.io.records.read`: :func:`read_record` (a record read whole and checked),
  :func:`write_record`;
- :mod:`~rigidid.io.records.csv`: CSV records, parsed in chunks (pandas' C engine);
- :mod:`~rigidid.io.records.binary`: ``.npy``/``.npz``/``.mat``/``.h5``/``.wav``/``.tdms``;
  :mod:`~rigidid.io.records.arrays` (named arrays of npz/mat/h5 in row blocks),
  :mod:`~rigidid.io.records.tdms`;
- :mod:`~rigidid.io.records.columns`: the record's columns matched to the layout's sensor ids;
- :mod:`~rigidid.io.records.streamed`, :mod:`~rigidid.io.records.refit`,
  :mod:`~rigidid.io.records.spectrum`: record files read in row blocks for the modal estimate,
  the refit and the report's spectrum.
"""

from rigidid.io.records.read import (
    DECAY_RATIO,
    MIN_ROWS,
    TIME_TOLERANCE,
    is_binary_record,
    layout_ids,
    read_record,
    write_record,
)

__all__ = [
    "DECAY_RATIO",
    "MIN_ROWS",
    "TIME_TOLERANCE",
    "is_binary_record",
    "layout_ids",
    "read_record",
    "write_record",
]
