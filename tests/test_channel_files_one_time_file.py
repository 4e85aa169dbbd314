"""A folder of one-column text files at 100 Hz, one of them the time of all (an INS export saved
channel by channel, as the Revs vehicle-dynamics excerpts are): the default 50 Hz grid says what it
thins and the --rate that keeps it, and the clock is named as the time file's, taken row by row,
not as the tables' own time columns (they have none); without --time, the error names the time
file beside and the --time that takes it; channels of one time file share its clock; a gyro in
deg/s declared in rad/s is named with the unit that fits it; each spike named has its value."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.log import LogError
from agrobot.measurements.recording import ImportOptions, import_recording

RATE = 100.0


def _folder(root, seconds: float = 30.0):
    t = 150.0 + np.arange(0.0, seconds, 1.0 / RATE)
    delta = 0.05 * np.sin(2 * np.pi * 0.3 * (t - t[0]))
    v = np.full_like(t, 25.0)
    columns = {"t": t, "delta": delta, "vx": v, "yawRate": v * np.tan(delta) / 2.4}
    root.mkdir()
    for name, x in columns.items():
        np.savetxt(root / f"{name}.txt", x, fmt="%15.7e")
    return root


def _options(**kw) -> ImportOptions:
    return ImportOptions(signals=["delta=delta.col1[rad]", "yaw_rate=yawRate.col1[rad/s]", "v=vx.col1[m/s]"],
                         time="t.col1[s]", wheelbase=2.4, **kw)


def test_the_default_grid_below_the_channels_rate_is_said(tmp_path):
    folder = _folder(tmp_path / "run")
    frame, report = import_recording(folder, _options())
    assert abs(report["rate_hz"] - 50.0) < 0.01
    notes = [n for n in report["notes"] if n.startswith("rows at 50 Hz")]
    assert notes and "yaw_rate (100 Hz)" in notes[0] and "--rate 100 " in notes[0] + " "
    frame, report = import_recording(folder, _options(rate=RATE))
    assert abs(report["rate_hz"] - RATE) < 0.01
    assert not [n for n in report["notes"] if n.startswith("rows at ")]


def test_the_clock_is_named_as_the_time_files(tmp_path):
    frame, report = import_recording(_folder(tmp_path / "run"), _options(rate=RATE))
    reference = report["clocks"]["reference"]
    assert "own time columns" not in reference
    assert reference.startswith("row by row from t (--time) for ")
    assert all(name in reference for name in ("delta", "vx", "yawRate"))


def test_without_time_the_time_file_beside_is_named(tmp_path):
    folder = _folder(tmp_path / "run")
    options = ImportOptions(signals=["delta=delta.col1[rad]", "yaw_rate=yawRate.col1[rad/s]", "v=vx.col1[m/s]"],
                            wheelbase=2.4)
    with pytest.raises(LogError, match=r"no time column.*t\.txt holds one rising column over the same 3000 rows: "
                                       r"--time 't\.col1\[s\]'"):
        import_recording(folder, options)


def test_channels_of_one_time_file_share_its_clock(tmp_path):
    """A second gyro 0.3 s behind the first (a filtered copy), both clocked by t.txt: a sensor's own
    latency on one clock, never a clock offset for --align auto to move."""
    folder = _folder(tmp_path / "run", seconds=120.0)
    t = np.loadtxt(folder / "t.txt")
    rate = 0.2 * np.sin(0.7 * (t - t[0])) + 0.1 * np.sin(2.3 * (t - t[0]) + 1.0)
    np.savetxt(folder / "yawRate.txt", rate, fmt="%15.7e")
    np.savetxt(folder / "yawRateFilt.txt", np.interp(t - 0.3, t, rate), fmt="%15.7e")
    options = ImportOptions(signals=["yaw_rate=yawRate.col1[rad/s]", "yaw_rate_2=yawRateFilt.col1[rad/s]",
                                     "v=vx.col1[m/s]"], time="t.col1[s]", wheelbase=2.4, rate=RATE)
    frame, report = import_recording(folder, options)
    gyros = [f for f in report["audit"]["findings"] if f["channels"] == ["yaw_rate", "yaw_rate_2"]]
    assert gyros and gyros[0]["kind"] == "sensor_latency" and abs(gyros[0]["value"] - 0.3) < 0.03
    assert report["audit"]["alignment"]["channels_moved"] == []


def test_a_gyro_in_degrees_declared_in_radians_is_named(tmp_path):
    """The filtered gyro of such an export is in deg/s beside a raw one in rad/s: declared [rad/s],
    half its samples pass 10 rad/s, and the finding names deg/s as the unit that fits them all."""
    folder = _folder(tmp_path / "run")
    rate = np.loadtxt(folder / "yawRate.txt")
    np.savetxt(folder / "yawRateFilt.txt", np.degrees(rate), fmt="%15.7e")     # up to 0.52 rad/s, in deg/s
    options = ImportOptions(signals=["delta=delta.col1[rad]", "yaw_rate=yawRateFilt.col1[rad/s]", "v=vx.col1[m/s]"],
                            time="t.col1[s]", wheelbase=2.4, rate=RATE)
    frame, report = import_recording(folder, options)
    found = [f for f in report["audit"]["findings"] if f["kind"] == "out_of_range" and f["channels"] == ["yaw_rate"]]
    assert found and "--signal yaw_rate=COLUMN[deg/s]" in found[0]["meaning"]


def test_every_spike_named_has_its_value(tmp_path):
    """Four single-sample glitches of a road-wheel angle (the largest last): the quirk line gives the
    value of each time it names."""
    folder = _folder(tmp_path / "run")
    delta = np.loadtxt(folder / "delta.txt")
    glitches = {500: 0.1356, 1200: 0.1496, 1900: 0.2366, 2600: 0.4783}
    for i, value in glitches.items():
        delta[i] = value
    np.savetxt(folder / "delta.txt", delta, fmt="%15.7e")
    frame, report = import_recording(folder, _options(rate=RATE))
    line = next(q for q in report["quirks"] if "spike(s) in delta" in q)
    assert all(f"{value:.4g}" in line for value in glitches.values()), line
