"""TDMS records (npTDMS, optional): one group, channels named by sensor id, read in row blocks; bad files named."""

from __future__ import annotations

from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest

from rigidid.errors import InputError
from rigidid.io.records import read_record
from rigidid.io.records.binary import named_blocks, read_binary

nptdms = pytest.importorskip("nptdms")

IDS = ["a", "b", "c"]


def _write(path: Path, x: np.ndarray, *, time: np.ndarray | None = None, dt: float | None = 1e-3,
           group: str = "impact", segments: int = 3, extra_group: bool = False) -> None:  # fmt: skip
    from nptdms import ChannelObject, TdmsWriter

    bounds = np.linspace(0, x.shape[0], segments + 1).astype(int)
    with TdmsWriter(path) as writer:
        for k, (lo, hi) in enumerate(pairwise(bounds)):
            props = {"wf_increment": dt} if dt is not None and k == 0 else {}
            objects = [ChannelObject(group, s, x[lo:hi, i], properties=props) for i, s in enumerate(IDS[: x.shape[1]])]
            if time is not None:
                objects.append(ChannelObject(group, "time", time[lo:hi]))
            if extra_group:
                objects.append(ChannelObject("other", "a", x[lo:hi, 0]))
            writer.write_segment(objects)


def _decay(n: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) * 1e-3
    x = np.exp(-3 * t)[:, None] * np.sin(2 * np.pi * np.array([20.0, 31.0, 47.0]) * t[:, None])
    return t, x


@pytest.mark.parametrize("with_time", [False, True])
def test_tdms_blocks_equal_the_written_channels(tmp_path: Path, with_time: bool) -> None:
    t, x = _decay()
    path = tmp_path / "rec.tdms"
    _write(path, x, time=t if with_time else None, dt=None if with_time else 1e-3)
    blocks = named_blocks(path, 300)
    assert blocks is not None and blocks.names == IDS and blocks.rows == t.size
    parts = list(blocks.blocks)
    assert max(v.shape[0] for _, v in parts) == 300 and len(parts) == -(-t.size // 300)
    np.testing.assert_array_equal(np.concatenate([v for _, v in parts]), x)
    if with_time:
        np.testing.assert_array_equal(np.concatenate([tt for tt, _ in parts]), t)
    else:
        assert blocks.dt == 1e-3
    data, dt = read_record(path, ["c", "a", "b"])  # matched by name, any order
    np.testing.assert_array_equal(data, x[:, [2, 0, 1]])
    assert dt == pytest.approx(1e-3, rel=1e-12)


@pytest.mark.parametrize(
    ("fault", "message", "location"),
    [
        ("two-groups", "a record is one group", "groups"),
        ("no-sampling", "no sampling", "group 'impact'"),
        ("lengths", "samples, others", "channel 'b'"),
        ("not-tdms", "not a TDMS file", ""),
        ("truncated", "", "rec.tdms"),
    ],
)
def test_bad_tdms_is_one_line_naming_file_and_place(tmp_path: Path, fault: str, message: str, location: str) -> None:
    from nptdms import ChannelObject, TdmsWriter

    x = _decay()[1]
    path = tmp_path / "rec.tdms"
    if fault == "two-groups":
        _write(path, x, extra_group=True)
    elif fault == "no-sampling":
        _write(path, x, dt=None)
    elif fault == "lengths":
        with TdmsWriter(path) as writer:
            props = {"wf_increment": 1e-3}
            writer.write_segment([ChannelObject("impact", "a", x[:, 0], properties=props),
                                  ChannelObject("impact", "b", x[:-7, 1], properties=props)])  # fmt: skip
    elif fault == "not-tdms":
        path.write_text("time,a,b\n0,1,2\n")
    else:
        _write(path, x, segments=1)
        path.write_bytes(path.read_bytes()[:-5000])
    with pytest.raises(InputError) as info:
        read_binary(path)
    text = str(info.value)
    assert "\n" not in text and str(path) in text and message in text and location in text, text
