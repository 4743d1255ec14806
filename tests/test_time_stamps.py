"""Records' sample intervals compared at the resolution their time stamps are written with (issue 23)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.core.timedomain.stamps import common_interval, interval_uncertainty, token_resolution
from rigidid.errors import InputError
from rigidid.io.records import read_record

ROOT = Path(__file__).resolve().parents[1]
ENGINE = ROOT / "samples" / "engine-on-mounts"


def _rewrite(source: Path, target: Path, ids: list[str], start: float, rate: float, decimals: int) -> Path:
    """The record of `source` with its time column starting at `start`, at `rate`, written with `decimals`."""
    data, _ = read_record(source, ids)
    time = start + np.arange(data.shape[0]) / rate
    with target.open("w", encoding="utf-8") as fh:
        fh.write(",".join(["time", *ids]) + "\n")
        for t, row in zip(time, data, strict=True):
            fh.write(f"{t:.{decimals}f}," + ",".join(f"{v:.10g}" for v in row) + "\n")
    return target


@pytest.fixture(scope="module")
def engine(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str], list[Path]]:
    folder = tmp_path_factory.mktemp("stamps")
    paths = api.simulate_records(
        ENGINE / "body.json", ENGINE / "layout.json", folder, sample_rate=1024.0, duration=4.0, noise=0.01, seed=5
    )
    ids = [s.id for s in api.load_layout(ENGINE / "layout.json").sensors]
    return folder, ids, paths


def test_time_starting_elsewhere_with_seven_decimals_gives_the_modes_of_exact_time(
    engine: tuple[Path, list[str], list[Path]],
) -> None:
    folder, ids, paths = engine
    exported = [
        _rewrite(p, folder / f"exported_{k}.csv", ids, start, 1024.0, 7)
        for k, (p, start) in enumerate(zip(paths, [0.0, 101.00000004321, 12.34567891234], strict=False))
    ]
    naive = [float(np.ptp(np.loadtxt(p, delimiter=",", skiprows=1, usecols=0)[[0, -1]])) for p in exported]
    assert np.ptp(naive) > 1e-9 * max(naive)  # the stamps as written disagree beyond a tight relative check
    _, exact = api.estimate_modes(ENGINE / "layout.json", paths)
    _, stamped = api.estimate_modes(ENGINE / "layout.json", exported)
    # the interval is known to 1e-7 / 4095 s: 1.2e-8 relative, far below the modes' own scatter
    np.testing.assert_allclose(stamped.frequency_hz, exact.frequency_hz, rtol=1e-6)
    assert stamped.sample_interval / stamped.decimation == pytest.approx(1 / 1024.0, rel=3e-8)


def test_records_of_different_rates_are_still_refused_with_the_digits_that_tell_them_apart(
    engine: tuple[Path, list[str], list[Path]],
) -> None:
    folder, ids, paths = engine
    a = _rewrite(paths[0], folder / "rate_a.csv", ids, 0.0, 1024.0, 9)
    b = _rewrite(paths[1], folder / "rate_b.csv", ids, 5.0, 1024.0 * (1 + 2e-6), 9)
    message = r"different sample intervals \(0\.00097656\d+ to 0\.00097656\d+ s, 2e-06 apart"
    with pytest.raises(InputError, match=message):
        api.estimate_modes(ENGINE / "layout.json", [a, b])


def test_common_interval_allows_each_intervals_rounding_and_no_more() -> None:
    n, r = 4096, 1e-7
    u = interval_uncertainty(r, n)
    assert u == pytest.approx(r / (n - 1))
    dt = 1 / 1024
    assert common_interval([dt, dt + 1.9 * u], [u, u]) == (dt, True)
    assert not common_interval([dt, dt + 2.1 * u], [u, u])[1]
    # the most precise record's interval is the common one
    assert common_interval([dt + 0.5 * u, dt], [u, 0.1 * u]) == (dt, True)
    # exact intervals: only the relative floor
    assert not common_interval([dt, dt * (1 + 1e-8)])[1]
    assert common_interval([dt, dt * (1 + 1e-10)])[1]


@pytest.mark.parametrize(("token", "unit"), [("0.125", 1e-3), ("1.5e-3", 1e-4), ("12", 1.0), ("3.0000001", 1e-7)])
def test_token_resolution(token: str, unit: float) -> None:
    assert token_resolution(token) == pytest.approx(unit)
