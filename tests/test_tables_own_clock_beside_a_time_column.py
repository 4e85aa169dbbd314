"""A folder of two loggers' tables, each on its own clock: an IMU logger whose clock column is not
named as one (declared with --time TABLE.COLUMN[ms]) and a phone's GNSS export with a column named
``time`` in seconds. The --time names the IMU table's clock; the GNSS table keeps its own (the
TABLE.COLUMN form is for tables without their own): it is neither refused for want of a time nor
handed the IMU's stamps row by row when both hold as many rows."""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.measurements.tables import read_tables


def _folder(root, imu_rows: int, gnss_rows: int):
    root.mkdir()
    imu_ms = 6004.0 + 534.0 * np.arange(imu_rows)               # a boot clock in ms, about 1.9 Hz
    pd.DataFrame({"Stamp": imu_ms, "Gz": np.sin(np.arange(imu_rows))}).to_csv(root / "imu.csv", index=False)
    gnss_s = 0.042 + 1.0 * np.arange(gnss_rows)                  # its own clock in s, 1 Hz
    pd.DataFrame({"time": gnss_s, "lat": 53.1 + 1e-5 * np.arange(gnss_rows),
                  "lon": np.full(gnss_rows, 8.85)}).to_csv(root / "gnss.csv", index=False)
    return sorted(root.iterdir()), imu_ms / 1e3, gnss_s


def test_a_table_with_its_own_clock_keeps_it_beside_another_tables_time(tmp_path):
    paths, imu_t, gnss_t = _folder(tmp_path / "ride", 120, 80)
    tables = {t.name: t for t in read_tables(paths, "imu.Stamp[ms]", None, tmp_path / "ride")}
    np.testing.assert_allclose(tables["imu"].t, imu_t)
    assert tables["gnss"].t is not None, "the GNSS table's own 'time' column was not taken"
    np.testing.assert_allclose(tables["gnss"].t, gnss_t)
    assert "found by name" in tables["gnss"].time_how


def test_as_many_rows_do_not_hand_it_the_time_files_clock(tmp_path):
    """The time in a file of its own (one column, as many rows): the table without a clock takes it
    row by row, the GNSS table with its own keeps its own."""
    paths, imu_t, gnss_t = _folder(tmp_path / "ride", 100, 100)
    pd.DataFrame({"Stamp": imu_t * 1e3}).to_csv(tmp_path / "ride" / "clock.csv", index=False)
    pd.read_csv(tmp_path / "ride" / "imu.csv")[["Gz"]].to_csv(tmp_path / "ride" / "imu.csv", index=False)
    paths = sorted((tmp_path / "ride").iterdir())
    tables = {t.name: t for t in read_tables(paths, "clock.Stamp[ms]", None, tmp_path / "ride")}
    np.testing.assert_allclose(tables["imu"].t, imu_t)
    assert tables["imu"].time_how.startswith("row by row from clock")
    assert not tables["gnss"].time_how.startswith("row by row"), tables["gnss"].time_how
    np.testing.assert_allclose(tables["gnss"].t, gnss_t)


def test_a_clock_without_unit_is_told_the_time_for_its_table_alone(tmp_path):
    """Both tables have a column 'Time' (the GNSS one says (s) in its header, the IMU's says nothing):
    the IMU's is taken as seconds, and the --time offered names its table, so that following it
    leaves the GNSS table's seconds alone (a bare 'Time[ms]' would make them milliseconds)."""
    root = tmp_path / "ride"
    root.mkdir()
    imu_ms = 6004.0 + 534.0 * np.arange(120)
    pd.DataFrame({"Time": imu_ms, "Gz": np.zeros(120)}).to_csv(root / "ArduinoLog.csv", index=False)
    gnss_s = 0.042 + np.arange(80.0)
    pd.DataFrame({"Time (s)": gnss_s, "Latitude (deg)": np.full(80, 53.1)}).to_csv(root / "Location.csv", index=False)
    paths = sorted(root.iterdir())
    tables = {t.name: t for t in read_tables(paths, None, None, root)}
    said = tables["ArduinoLog"].time_how
    assert "no unit stated" in said and "--time 'ArduinoLog.Time[ms]'" in said, said
    tables = {t.name: t for t in read_tables(paths, "ArduinoLog.Time[ms]", None, root)}
    np.testing.assert_allclose(tables["ArduinoLog"].t, imu_ms / 1e3)
    np.testing.assert_allclose(tables["Location"].t, gnss_s)


def test_a_time_unit_against_the_header_is_said(tmp_path):
    """A bare --time 'Time[ms]' declares ms in every table with a column Time, also in one whose
    header states (s): taken (the user's word), and said with the TABLE.COLUMN that names one."""
    root = tmp_path / "ride"
    root.mkdir()
    pd.DataFrame({"Time": 6004.0 + 534.0 * np.arange(50), "Gz": np.zeros(50)}).to_csv(root / "ArduinoLog.csv", index=False)
    pd.DataFrame({"Time (s)": 0.042 + np.arange(40.0), "Latitude (deg)": np.full(40, 53.1)}).to_csv(
        root / "Location.csv", index=False)
    tables = {t.name: t for t in read_tables(sorted(root.iterdir()), "Time[ms]", None, root)}
    assert not [n for n in tables["ArduinoLog"].notes if "header states" in n]
    said = [n for n in tables["Location"].notes if "header states Time in s" in n]
    assert said and "--time 'TABLE.Time[ms]'" in said[0], tables["Location"].notes
    np.testing.assert_allclose(tables["Location"].t, 1e-3 * (0.042 + np.arange(40.0)))
