"""ASAM MDF4 in: a signal file (channel groups on their own clocks, units, a conversion rule) gives
the same log as the same data written as CSV tables, and the truth it was made from; bus logging
(CAN frames in MDF4) decodes as the same frames in a candump; a damaged file or one that is not MDF
is a named error."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements.log import LogError
from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording
from agrobot.measurements.signal_expressions import parse_signal
from harness.generated_recordings import write_candump
from tests.commands import cli

asammdf = pytest.importorskip("asammdf")
ROOT = Path(__file__).resolve().parent.parent
SIGNALS = ["yaw_rate=YawRate", "v=VehSpeed", "delta=WheelAngle"]


def _truth(t):
    return 0.2 * np.sin(0.5 * t), 3.0 + 0.5 * np.sin(0.1 * t), 0.1 * np.sin(0.5 * t)


@pytest.fixture(scope="module")
def signal_files(tmp_path_factory):
    """The same recording as MDF4 (an IMU group at 100 Hz, yaw rate stored as int16 counts of 0.01 deg/s
    with a linear conversion; a vehicle group at 20 Hz, speed in km/h) and as two CSV tables."""
    from asammdf import MDF, Signal

    where = tmp_path_factory.mktemp("mdf")
    t1, t2 = np.arange(0.0, 40.0, 0.01), np.arange(0.005, 40.0, 0.05)
    yaw, _, _ = _truth(t1)
    _, v, delta = _truth(t2)
    counts = np.round(np.degrees(yaw) * 100).astype(np.int16)
    mdf = MDF(version="4.10")
    mdf.append([Signal(counts, t1, name="YawRate", unit="deg/s", conversion={"a": 0.01, "b": 0.0})], acq_name="IMU")
    mdf.append([Signal(v * 3.6, t2, name="VehSpeed", unit="km/h"), Signal(delta, t2, name="WheelAngle", unit="rad")],
               acq_name="Vehicle")
    mdf.save(where / "drive.mf4", overwrite=True)
    mdf.close()
    tables = where / "tables"
    tables.mkdir()
    pd.DataFrame({"time": t1, "YawRate [deg/s]": counts * 0.01}).to_csv(tables / "IMU.csv", index=False)
    pd.DataFrame({"time": t2, "VehSpeed [km/h]": v * 3.6, "WheelAngle [rad]": delta}).to_csv(tables / "Vehicle.csv",
                                                                                              index=False)
    return where


def _log(source: Path) -> pd.DataFrame:
    return import_recording(source, ImportOptions(signals=[parse_signal(s) for s in SIGNALS]))[0]


def test_an_mdf4_signal_file_gives_the_log_of_the_same_data_as_csv(signal_files):
    mdf_log, csv_log = _log(signal_files / "drive.mf4"), _log(signal_files / "tables")
    assert list(mdf_log.columns) == list(csv_log.columns) and len(mdf_log) == len(csv_log) > 1000
    for column in ("t", "yaw_rate", "v", "delta"):
        # the MDF's clock adds the header's date (POSIX s ~1.8e9, steps of 2.4e-7 s): interpolation differs by 1e-8
        np.testing.assert_allclose(mdf_log[column], csv_log[column], rtol=0, atol=1e-7)
    # and the truth, whatever the log's time origin: yaw rate 0.2 sin(0.5 t) is twice the wheel angle 0.1 sin(0.5 t)
    # within one count of 0.01 deg/s (the conversion rule applied); the speed peaks at 3.5 m/s (12.6 km/h)
    assert np.max(np.abs(mdf_log["yaw_rate"] - 2 * mdf_log["delta"])) < np.radians(0.01) + 1e-4
    assert mdf_log["v"].max() == pytest.approx(3.5, abs=2e-3) and mdf_log["v"].min() > 2.4


def test_mdf4_bus_logging_decodes_as_the_same_frames_in_a_candump(tmp_path):
    import can

    candump = write_candump(tmp_path / "bus.log", seconds=30.0)
    writer = can.MF4Writer(str(tmp_path / "bus.mf4"))
    for message in can.CanutilsLogReader(str(candump)):
        writer.on_message_received(message)
    writer.stop()
    from_mdf, from_candump = import_recording(tmp_path / "bus.mf4")[0], import_recording(candump)[0]
    assert len(from_mdf) == len(from_candump) > 500
    for column in from_candump.columns:
        np.testing.assert_allclose(from_mdf[column], from_candump[column], rtol=0, atol=1e-9)
    # the candump's truth (harness.generated_recordings.candump_lines): wheel angle 0.2 sin(0.5 t), 2 m/s
    assert np.max(np.abs(from_mdf["v"] - 2.0)) < 1e-9
    assert np.max(np.abs(from_mdf["delta"])) == pytest.approx(0.2, abs=2e-4)


def test_list_names_the_groups_channels_units_and_rates(signal_files):
    from agrobot.measurements.listing import list_source

    out = "\n".join(list_source(signal_files / "drive.mf4", ImportOptions()))
    assert "(IMU)" in out and "(Vehicle)" in out
    assert "YawRate [deg/s]" in out and "VehSpeed [km/h]" in out and "WheelAngle [rad]" in out
    assert "(100 Hz)" in out and "(20 Hz)" in out


@pytest.mark.parametrize("content, expected", [(b"hello, not an MDF file\n", "not an MDF file"),
                                               (None, "a damaged MDF file")])
def test_a_damaged_or_foreign_mdf4_is_a_named_error(signal_files, tmp_path, content, expected):
    bad = tmp_path / "bad.mf4"
    bad.write_bytes(content if content is not None else (signal_files / "drive.mf4").read_bytes()[:4000])
    with pytest.raises(LogError, match=expected) as err:
        _log(bad)
    assert str(bad) in str(err.value)
    if content is None:
        return
    proc = cli("convert", str(bad), "--out", str(tmp_path / "x.csv"), timeout=120)
    assert proc.returncode == 2 and expected in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "x.csv").exists()
