"""Impact records: files read as blocks of rows and checked; no signal processing here.

One record per impact, in any of the formats of ``docs/FORMATS.md``:

- :mod:`~rigidid.io.records.sources`: :func:`open_source`, the one block-source interface
  (rows, sample interval, blocks of rows) over every format;
- :mod:`~rigidid.io.records.checks`: the checks every record passes (time, finite, decay);
- :mod:`~rigidid.io.records.read`: :func:`read_record` (a record read whole and checked),
  :func:`write_record`;
- :mod:`~rigidid.io.records.csv`: CSV records, parsed in chunks (pandas' C engine);
- :mod:`~rigidid.io.records.binary`: ``.npy``/``.npz``/``.mat``/``.h5``/``.wav``/``.tdms``;
  :mod:`~rigidid.io.records.arrays` (named arrays of npz/mat/h5 in row blocks),
  :mod:`~rigidid.io.records.tdms`;
- :mod:`~rigidid.io.records.columns`: the record's columns matched to the layout's sensor ids;
- :mod:`~rigidid.io.records.streamed`, :mod:`~rigidid.io.records.refit`,
  :mod:`~rigidid.io.records.spectrum`: record files opened as block sources for the modal
  estimate, the refit and the report's spectrum, whose numbers
  :mod:`rigidid.core.timedomain.streaming` computes.
"""

from rigidid.io.records.checks import DECAY_RATIO, MIN_ROWS, TIME_TOLERANCE, layout_ids
from rigidid.io.records.read import read_record, write_record
from rigidid.io.records.sources import BlockSource, is_binary_record, open_source

__all__ = [
    "DECAY_RATIO",
    "MIN_ROWS",
    "TIME_TOLERANCE",
    "BlockSource",
    "is_binary_record",
    "layout_ids",
    "open_source",
    "read_record",
    "write_record",
]
