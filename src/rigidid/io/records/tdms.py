"""Impact records in NI TDMS files (LabVIEW, NI DAQ), read in row blocks through npTDMS.

Layout (also in ``docs/FORMATS.md``): the file holds **one group**; its
channels are the sensors, named by sensor id, plus optionally a channel
``time`` (s). Without ``time`` the sampling is the channels' waveform
property ``wf_increment`` (s, the same for every channel; time starts at 0).
Values are those npTDMS returns: scaled by the file's own scaling properties
when it has any (DAQmx raw data), else as stored.

``npTDMS`` is an optional dependency (the ``tdms`` extra), imported only when
a ``.tdms`` file is read. :meth:`nptdms.TdmsFile.open` reads the metadata
only; each block is read with :meth:`nptdms.TdmsChannel.read_data`, so the
memory held is one block whatever the file's size.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError

__all__ = ["open_tdms"]

Array = NDArray[np.float64]


@contextmanager
def _quiet() -> Iterator[None]:
    """npTDMS's logged warnings (a short last segment) off: they would be lines of their own on stderr."""
    import nptdms  # noqa: F401  (its module loggers exist once it is imported)

    # npTDMS gives each module's logger (nptdms.reader, nptdms.tdms_segment...) a level of its own
    names = ["nptdms"] + [n for n in logging.root.manager.loggerDict if n.startswith("nptdms.")]
    loggers = [logging.getLogger(n) for n in names]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.ERROR)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels, strict=True):
            lg.setLevel(level)


def _channel(name: str) -> str:
    return f"channel {name!r}"


def open_tdms(path: Path, rows: int) -> tuple[list[str], int, float | None, Iterator[tuple[Array | None, Array]]]:
    """Channel names, samples, sample interval (None with a ``time`` channel) and row blocks of a TDMS record.

    Parameters
    ----------
    path : Path
    rows : int
        Samples per block.

    Returns
    -------
    names, n, dt, blocks
        `blocks` yields ``(time[start:stop] or None, data[start:stop])``
        (float64, ``(count, len(names))``) and closes the file when it ends
        or is closed.

    Raises
    ------
    InputError
        One line naming the file and the group or channel: npTDMS not
        installed, not a TDMS file, not one group, channels of different
        lengths or not numeric, no sampling.
    """
    src = str(path)
    try:
        from nptdms import TdmsFile
    except ImportError:
        raise InputError("reading TDMS needs npTDMS: pip install 'rigidid[tdms]'", source=src) from None
    try:
        with path.open("rb") as raw:
            lead_in = raw.read(4)
    except OSError as exc:
        raise InputError(f"cannot be read ({exc.strerror})", source=src) from None
    if lead_in != b"TDSm":
        raise InputError("not a TDMS file (no 'TDSm' segment lead-in)", source=src)
    try:
        with _quiet():
            fh = TdmsFile.open(path)
    except Exception as exc:  # npTDMS raises ValueError, struct.error, KeyError... on a bad file
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"not a TDMS file ({reason})", source=src) from None
    with _quiet():
        try:
            groups = [g for g in fh.groups() if g.channels()]
            if len(groups) != 1:
                names = ", ".join(repr(g.name) for g in groups) or "none"
                raise InputError(
                    f"has {len(groups)} groups with channels ({names}): a record is one group",
                    source=src,
                    location="groups",
                )
            channels = groups[0].channels()
            lengths = {}
            for ch in channels:
                if ch.dtype is None or np.dtype(ch.dtype).kind not in "fiu":
                    raise InputError(f"is not numeric ({ch.dtype})", source=src, location=_channel(ch.name))
                lengths[ch.name] = len(ch)
            n = lengths[channels[0].name]
            for name, length in lengths.items():
                if length != n:
                    raise InputError(f"has {length} samples, others {n}", source=src, location=_channel(name))
            time = next((ch for ch in channels if ch.name.strip() == "time"), None)
            sensors = [ch for ch in channels if ch is not time]
            if not sensors:
                raise InputError("no channels but 'time'", source=src, location=f"group {groups[0].name!r}")
            dt = None
            if time is None:
                steps = {float(ch.properties.get("wf_increment", math.nan)) for ch in sensors}
                step = steps.pop() if len(steps) == 1 else math.nan
                if not (math.isfinite(step) and step > 0.0):
                    raise InputError(
                        "no sampling: give a channel 'time' or the same positive wf_increment to every channel",
                        source=src,
                        location=f"group {groups[0].name!r}",
                    )
                dt = step
        except BaseException:
            fh.close()
            raise

    def blocks() -> Iterator[tuple[Array | None, Array]]:
        try:
            for start in range(0, n, rows):
                count = min(rows, n - start)
                out = np.empty((count, len(sensors)))
                with _quiet():
                    for j, ch in enumerate(sensors):
                        out[:, j] = _read(ch, start, count, src)
                    t = _read(time, start, count, src) if time is not None else None
                yield t, out
        finally:
            fh.close()

    return [ch.name.strip() for ch in sensors], n, dt, blocks()


def _read(channel: Any, start: int, count: int, src: str) -> Array:
    try:
        values = np.asarray(channel.read_data(start, count), dtype=np.float64)
    except Exception as exc:  # a truncated segment: npTDMS raises several types
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"cannot be read ({reason})", source=src, location=_channel(channel.name)) from None
    if values.shape[0] != count:
        raise InputError("the file is shorter than its header says", source=src, location=_channel(channel.name))
    return values
