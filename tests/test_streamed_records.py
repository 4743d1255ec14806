"""Records read block by block and decimated as they arrive (io/records/streamed.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.core.timedomain import streaming
from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH, channel_energy, decimate
from rigidid.errors import InputError
from rigidid.io.records import read_record, sources, write_record
from rigidid.io.records import streamed as streamed_records
from rigidid.io.records.binary import write_binary
from rigidid.io.records.streamed import read_record_streamed

from .tolerances import STREAMED_DECIMATION, STREAMED_VS_WHOLE_FREQUENCY

ROOT = Path(__file__).resolve().parents[1]
ENGINE = ROOT / "samples" / "engine-on-mounts"


@pytest.fixture(scope="module")
def engine(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str], list[Path]]:
    folder = tmp_path_factory.mktemp("streamed")
    paths = api.simulate_records(
        ENGINE / "body.json", ENGINE / "layout.json", folder, sample_rate=16384.0, duration=2.0, noise=0.01, seed=3
    )
    ids = [s.id for s in api.load_layout(ENGINE / "layout.json").sensors]
    return folder, ids, paths


@pytest.fixture
def small_blocks(monkeypatch: pytest.MonkeyPatch) -> None:
    """Pre-decimate records of a few thousand rows (the defaults need 2^18 rows)."""
    monkeypatch.setattr(streaming, "HEAD_ROWS", 4096)
    monkeypatch.setattr(sources, "BLOCK_ROWS", 1000)


def test_short_record_is_read_as_read_record_reads_it(engine: tuple[Path, list[str], list[Path]]) -> None:
    _, ids, paths = engine
    data, dt = read_record(paths[0], ids)
    streamed = read_record_streamed(paths[0], ids)
    assert streamed.factor == 1 and streamed.offset == 0 and streamed.rows == data.shape[0]
    np.testing.assert_array_equal(streamed.data, data)
    assert streamed.dt == pytest.approx(dt, rel=1e-15)
    np.testing.assert_allclose(streamed.energy, channel_energy(data), rtol=1e-15)


@pytest.mark.parametrize("factor", [3, 7])
def test_given_factor_equals_whole_record_decimation(engine: tuple[Path, list[str], list[Path]], factor: int) -> None:
    _, ids, paths = engine
    data, dt = read_record(paths[0], ids)
    streamed = read_record_streamed(paths[0], ids, factor=factor)
    assert streamed.offset == FIR_HALF_LENGTH * factor
    np.testing.assert_allclose(streamed.data, decimate(data, factor), rtol=0.0, atol=STREAMED_DECIMATION)
    assert streamed.dt == pytest.approx(dt * factor, rel=1e-12)


def test_pre_decimated_modes_are_the_same_whatever_the_format(
    engine: tuple[Path, list[str], list[Path]], small_blocks: None
) -> None:
    folder, ids, paths = engine
    _, whole = api.estimate_modes(
        ENGINE / "layout.json", api.load_records(paths, api.load_layout(ENGINE / "layout.json"))
    )
    _, from_csv = api.estimate_modes(ENGINE / "layout.json", paths)
    assert from_csv.decimation > 1 and from_csv.decimation % read_record_streamed(paths[0], ids).factor == 0
    assert read_record_streamed(paths[0], ids).factor > 1
    converted = []
    for path in paths:
        data, dt = read_record(path, ids)
        target = folder / f"{path.stem}.npz"
        write_binary(target, np.arange(data.shape[0]) * dt, data, ids)
        converted.append(target)
    _, from_npz = api.estimate_modes(ENGINE / "layout.json", converted)
    np.testing.assert_allclose(from_npz.frequency_hz, from_csv.frequency_hz, rtol=1e-9, atol=0)
    np.testing.assert_allclose(from_npz.damping_ratio, from_csv.damping_ratio, rtol=1e-9, atol=0)
    np.testing.assert_allclose(np.abs(from_npz.shapes), np.abs(from_csv.shapes), rtol=1e-9, atol=1e-12)
    # two-stage decimation against the whole-record path: the same modes within the noise
    np.testing.assert_allclose(from_csv.frequency_hz, whole.frequency_hz, rtol=STREAMED_VS_WHOLE_FREQUENCY)
    # impacts are reported in the file's rows
    for impact, path in zip(from_csv.impacts, paths, strict=True):
        data, dt = read_record(path, ids)
        raw = api.estimate_modes(ENGINE / "layout.json", [(data, dt)])[1].impacts[0]
        assert abs(impact.onset - raw.onset) <= 2 * from_csv.decimation


def _bad_copy(folder: Path, ids: list[str], source: Path, row: int, column: int, value: float) -> Path:
    data, dt = read_record(source, ids)
    time = np.arange(data.shape[0]) * dt
    data[row, column] = value
    target = folder / f"bad_{row}_{column}.csv"
    write_record(target, time, data, ids)
    return target


def test_a_bad_value_late_in_the_file_names_line_and_column(
    engine: tuple[Path, list[str], list[Path]], small_blocks: None
) -> None:
    folder, ids, paths = engine
    rows = read_record(paths[0], ids)[0].shape[0]
    target = _bad_copy(folder, ids, paths[0], rows - 100, 2, np.nan)
    with pytest.raises(InputError) as err:
        read_record_streamed(target, ids)
    assert str(target) in str(err.value)
    assert f"row {rows - 100 + 2}" in str(err.value) and ids[2] in str(err.value)


def test_a_time_jump_late_in_the_file_names_its_line(
    engine: tuple[Path, list[str], list[Path]], small_blocks: None
) -> None:
    folder, ids, paths = engine
    data, dt = read_record(paths[0], ids)
    time = np.arange(data.shape[0]) * dt
    k = data.shape[0] - 300
    time[k:] += 0.5 * dt
    target = folder / "jump.csv"
    write_record(target, time, data, ids)
    with pytest.raises(InputError, match="differs from the sample interval") as err:
        read_record_streamed(target, ids)
    assert f"row {k + 2}" in str(err.value)
    with pytest.raises(InputError, match="differs from the sample interval") as whole:
        read_record(target, ids)
    assert whole.value.location == err.value.location


def test_reading_reports_progress_to_the_end(engine: tuple[Path, list[str], list[Path]], small_blocks: None) -> None:
    _, ids, paths = engine
    calls: list[tuple[str, float, float | None]] = []
    read_record_streamed(paths[0], ids, progress=lambda task, done, total: calls.append((task, done, total)))
    assert calls and all(task == f"reading {paths[0].name}" for task, _, _ in calls)
    assert [done for _, done, _ in calls] == sorted(done for _, done, _ in calls)
    assert calls[-1][1] == calls[-1][2] == paths[0].stat().st_size


def test_spectrum_while_reading_is_the_estimations(
    engine: tuple[Path, list[str], list[Path]], small_blocks: None
) -> None:
    """The content spectrum accumulated block by block is content_spectrum of the decay."""
    from rigidid.core.timedomain.preprocess import content_spectrum, find_impact

    _, ids, paths = engine
    streamed = read_record_streamed(paths[0], ids)
    data, dt = read_record(paths[0], ids)
    freqs, total = content_spectrum([data[find_impact(data, dt).start :]], dt)
    assert streamed.spectrum is not None
    np.testing.assert_allclose(streamed.spectrum[0], freqs, rtol=1e-15)
    np.testing.assert_allclose(streamed.spectrum[1], total, rtol=1e-9)


def test_npy_is_read_in_blocks_to_the_same_record(
    engine: tuple[Path, list[str], list[Path]], small_blocks: None
) -> None:
    folder, ids, paths = engine
    data, dt = read_record(paths[0], ids)
    target = folder / "blocks.npy"
    np.save(target, np.column_stack([np.arange(data.shape[0]) * dt, data]))
    from_npy = read_record_streamed(target, ids)
    from_csv = read_record_streamed(paths[0], ids)
    assert from_npy.factor == from_csv.factor > 1
    np.testing.assert_allclose(from_npy.data, from_csv.data, rtol=0, atol=STREAMED_DECIMATION)
    bad = data.copy()
    bad[5000, 3] = np.inf
    np.save(target, np.column_stack([np.arange(data.shape[0]) * dt, bad]))
    with pytest.raises(InputError, match="NaN or infinite") as err:
        read_record_streamed(target, ids)
    assert "row 5001" in str(err.value) and ids[3] in str(err.value)


def test_a_layout_with_a_sensor_id_twice_is_refused_by_both_readers(
    engine: tuple[Path, list[str], list[Path]],
) -> None:
    _, ids, paths = engine
    twice = [*ids[:-1], ids[0]]
    for reader in (read_record, read_record_streamed):
        with pytest.raises(InputError, match="sensor id twice"):
            reader(paths[0], twice)


def test_a_universal_file_beside_a_layout_is_named_not_parsed_as_csv(tmp_path: Path) -> None:
    uff = tmp_path / "hit1.uff"
    uff.write_text("    -1\n    58\n")
    for reader in (read_record, read_record_streamed):
        with pytest.raises(InputError, match="universal file is not a record beside a layout"):
            reader(uff, ["1", "2"])


@pytest.fixture
def cascade_blocks(monkeypatch: pytest.MonkeyPatch, small_blocks: None) -> None:
    """Let the content spectrum complete (and the second stage start) within a record of 32768 rows."""
    monkeypatch.setattr(streaming.ContentWelch, "SPAN", 8192)
    monkeypatch.setattr("rigidid.core.timedomain.estimate.MIN_DECIMATED_SAMPLES", 200)


def test_second_stage_is_decimation_of_the_pre_decimated_record(
    engine: tuple[Path, list[str], list[Path]], cascade_blocks: None
) -> None:
    _, ids, paths = engine
    data, dt = read_record(paths[0], ids)
    cascaded = read_record_streamed(paths[0], ids, cascade=True)
    q0, q2 = cascaded.stages
    assert q0 > 1 and q2 > 1 and cascaded.factor == q0 * q2
    assert q0 == read_record_streamed(paths[0], ids).factor  # the same pre-factor as without the second stage
    expected = decimate(decimate(data, q0), q2)
    np.testing.assert_allclose(cascaded.data, expected, rtol=0.0, atol=STREAMED_DECIMATION)
    assert cascaded.offset == FIR_HALF_LENGTH * q0 + FIR_HALF_LENGTH * q0 * q2
    assert cascaded.dt == pytest.approx(dt * q0 * q2, rel=1e-12)
    # the second stage is the factor the estimation chooses on the pre-decimated record
    assert cascaded.spectrum is not None
    from rigidid.core.timedomain.preprocess import content_from_spectrum

    f_high = content_from_spectrum(*cascaded.spectrum, 0.5 / dt)[1]
    assert q2 == streaming.second_factor(f_high, dt, q0)
    # a record read with the first record's stages fixed is the same
    fixed = read_record_streamed(paths[0], ids, factor=q0, second=q2)
    np.testing.assert_allclose(fixed.data, cascaded.data, rtol=0.0, atol=STREAMED_DECIMATION)


def test_modes_through_the_second_stage_match_the_whole_record(
    engine: tuple[Path, list[str], list[Path]], cascade_blocks: None
) -> None:
    _, ids, paths = engine
    layout = api.load_layout(ENGINE / "layout.json")
    _, whole = api.estimate_modes(layout, api.load_records(paths, layout))
    records, content = streamed_records.read_records_streamed(paths, ids, cascade=True)
    assert content is not None and all(r.stages == records[0].stages for r in records)
    assert records[0].stages[1] > 1
    _, streamed = api.estimate_modes(layout, paths)
    # the estimation judges the content again at the second stage's rate and may decimate further
    assert streamed.decimation % records[0].factor == 0
    np.testing.assert_allclose(streamed.frequency_hz, whole.frequency_hz, rtol=STREAMED_VS_WHOLE_FREQUENCY)
    for impact, path in zip(streamed.impacts, paths, strict=True):
        data, dt = read_record(path, ids)
        raw = api.estimate_modes(layout, [(data, dt)])[1].impacts[0]
        assert abs(impact.onset - raw.onset) <= 2 * streamed.decimation


@pytest.mark.parametrize("suffix", [".npz", ".h5"])
def test_named_binary_records_are_read_in_row_blocks(
    engine: tuple[Path, list[str], list[Path]], small_blocks: None, suffix: str
) -> None:
    """.npz and .h5 records stream in blocks to the same record, in the data/channels or one-array-per-sensor layout."""
    if suffix == ".h5":
        pytest.importorskip("h5py")
    from rigidid.io.records.binary import named_blocks

    folder, ids, paths = engine
    data, dt = read_record(paths[0], ids)
    target = folder / f"named{suffix}"
    order = list(reversed(range(len(ids))))  # columns in another order than the layout's
    shuffled = np.ascontiguousarray(data[:, order])
    write_binary(target, np.arange(data.shape[0]) * dt, shuffled, [ids[i] for i in order])
    blocks = named_blocks(target, 1000)
    assert blocks is not None and blocks.rows == data.shape[0] and blocks.names == [ids[i] for i in order]
    parts = list(blocks.blocks)
    assert max(values.shape[0] for _, values in parts) == 1000
    np.testing.assert_array_equal(np.concatenate([values for _, values in parts]), data[:, order])
    from_blocks = read_record_streamed(target, ids)
    np.testing.assert_allclose(from_blocks.data, read_record_streamed(paths[0], ids).data, rtol=0, atol=1e-12)
    # one array per sensor (no 'data'): also read in row blocks, the same record
    columns = {s: data[:, i] for i, s in enumerate(ids)}
    np.savez(folder / "per_sensor.npz", time=np.arange(data.shape[0]) * dt, **columns)
    per_sensor = named_blocks(folder / "per_sensor.npz", 1000)
    assert per_sensor is not None and per_sensor.names == ids
    assert max(values.shape[0] for _, values in per_sensor.blocks) == 1000
    np.testing.assert_allclose(
        read_record_streamed(folder / "per_sensor.npz", ids).data, from_blocks.data, rtol=0, atol=1e-12
    )


def test_missing_modes_after_the_second_stage_read_again_without_it(
    engine: tuple[Path, list[str], list[Path]], cascade_blocks: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The smaller factors the estimation retries need the records before the second stage: read again."""
    import rigidid.core.timedomain as timedomain
    from rigidid.errors import IdentificationError

    _, _, paths = engine
    real = timedomain.estimate_modes
    calls: list[dict[str, object]] = []

    def first_fails(records: list[np.ndarray], dt: float, **options: object) -> object:
        calls.append({"rows": records[0].shape[0], **options})
        if len(calls) == 1:
            raise IdentificationError("found 5 stable modes, 6 needed")
        return real(records, dt, **options)  # type: ignore[arg-type]

    monkeypatch.setattr(timedomain, "estimate_modes", first_fails)
    _, estimate = api.estimate_modes(ENGINE / "layout.json", paths)
    assert len(calls) == 2
    assert calls[0]["settle"] == FIR_HALF_LENGTH and calls[0]["decimate"] is None and calls[0]["content"] is None
    assert calls[1]["settle"] == 0 and calls[1]["decimate"] is None
    assert int(calls[1]["rows"]) > int(calls[0]["rows"])  # type: ignore[call-overload]
    assert estimate.frequency_hz.shape == (6,)
