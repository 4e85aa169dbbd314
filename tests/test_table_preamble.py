"""A table below a preamble, as motion-capture exports write one (OptiTrack Motive's CSV): a
metadata line of keys and values holding numbers, a blank line, a header of several rows with
the axis names X, Y, Z repeated under a group row (Rotation, Position) and rows naming the
tracked body, then the data. The metadata line is a preamble (named as such, never the first
data row), the header's rows give names a --signal can address, and the data read are the
generated positions. A plain CSV and a header-less numeric CSV read as before."""
from __future__ import annotations

import numpy as np

from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording
from agrobot.measurements.signal_expressions import parse_signal
from agrobot.measurements.tables import read_table

RATE = 120.0


def path_of(seconds: float = 20.0) -> dict:
    """Known truth: a body driving a circle of 2 m radius at 0.5 m/s on the floor (x, z; y up)."""
    t = np.arange(0.0, seconds, 1.0 / RATE)
    a = 0.25 * t
    return {"t": t, "x": 2.0 * np.sin(a), "y": np.full_like(t, 0.21), "z": -2.0 * np.cos(a)}


def write_capture(path, bodies=("RigidBody 1",), ids=("8392B20CF49E35731",)) -> dict:
    truth = path_of()
    n = len(truth["t"])
    meta = ("Format Version,1.21,Take Name,Field_2018_05_17,Capture Frame Rate,120.000000,Export Frame Rate,"
            f"120.000000,Total Frames in Take,{n},Total Exported Frames,{n},Rotation Type,Quaternion,Length Units,"
            "Meters,Coordinate Space,Global")
    per = ["Rotation"] * 4 + ["Position"] * 3 + ["Error Per Marker"]
    axes = ["X", "Y", "Z", "W", "X", "Y", "Z", ""]
    rows = [meta, "",
            ",," + ",".join("Rigid Body" for _ in bodies for _ in per),
            ",," + ",".join(b for b in bodies for _ in per),
            ",," + ",".join(f'"{i}"' for i in ids for _ in per),
            ",," + ",".join(per * len(bodies)),
            "Frame,Time," + ",".join(axes * len(bodies))]
    for k in range(n):
        cells = []
        for b in range(len(bodies)):
            cells += ["0.0", "1.0", "0.0", "0.0", f"{truth['x'][k] + b:.6f}", f"{truth['y'][k]:.6f}",
                      f"{truth['z'][k]:.6f}", "0.000817"]
        rows.append(f"{k},{truth['t'][k]:.6f}," + ",".join(cells))
    path.write_text("\n".join(rows) + "\n")
    return truth


def test_a_metadata_line_above_a_header_of_five_rows_is_a_preamble_and_the_names_are_addressable(tmp_path):
    truth = write_capture(tmp_path / "take.csv")
    table = read_table(tmp_path / "take.csv")
    assert not table.headerless and len(table.frame) == len(truth["t"])
    assert list(table.frame.columns) == ["Frame", "Time", "Rotation_X", "Rotation_Y", "Rotation_Z", "Rotation_W",
                                         "Position_X", "Position_Y", "Position_Z", "Error Per Marker"]
    notes = " ".join(table.notes)
    assert "1 line(s) above the header taken as a preamble" in notes and "'Format Version,1.21," in notes
    assert "header: 5 row(s) above the data" in notes
    assert "left out of the names: 'Rigid Body', 'RigidBody 1', '8392B20CF49E35731'" in notes
    signals = [parse_signal(s) for s in ("x=Position_X[m]", "y=-1*Position_Z[m]")]
    frame, report = import_recording(tmp_path / "take.csv", ImportOptions(signals=signals, time="Time[s]"))
    t = frame["t"].to_numpy()
    assert t[-1] > 19.0
    assert np.allclose(frame["x"], np.interp(t, truth["t"], truth["x"]), atol=2e-6)
    assert np.allclose(frame["y"], np.interp(t, truth["t"], -truth["z"]), atol=2e-6)
    assert any("preamble" in n for n in report["notes"])


def test_two_bodies_with_numeric_ids_are_told_apart_by_the_header_rows_that_differ(tmp_path):
    truth = write_capture(tmp_path / "two.csv", bodies=("Mower", "Base"), ids=("1", "2"))
    table = read_table(tmp_path / "two.csv")
    columns = list(table.frame.columns)
    assert columns[:2] == ["Frame", "Time"] and len(set(columns)) == len(columns) == 18
    assert "Mower_1_Position_X" in columns and "Base_2_Position_X" in columns
    assert table.units == {}                     # the row of IDs (1, 2) is names, never units
    assert np.allclose(table.frame["Base_2_Position_X"] - table.frame["Mower_1_Position_X"], 1.0, atol=2e-6)
    assert np.allclose(table.frame["Mower_1_Position_Z"], truth["z"], atol=1e-6)
    assert "left out of the names: 'Rigid Body'" in " ".join(table.notes)


def test_a_plain_csv_and_a_headerless_numeric_csv_read_as_before(tmp_path):
    truth = path_of(5.0)
    lines = [f"{float(t)!r},{float(x)!r},{float(z)!r}" for t, x, z in zip(truth["t"], truth["x"], truth["z"])]
    (tmp_path / "plain.csv").write_text("t,x,z\n" + "\n".join(lines) + "\n")
    (tmp_path / "bare.csv").write_text("\n".join(lines) + "\n")
    plain, bare = read_table(tmp_path / "plain.csv"), read_table(tmp_path / "bare.csv")
    assert list(plain.frame.columns) == ["t", "x", "z"] and not plain.headerless
    assert list(bare.frame.columns) == ["col1", "col2", "col3"] and bare.headerless
    assert len(plain.frame) == len(bare.frame) == len(truth["t"])
    assert np.allclose(bare.frame["col2"], truth["x"]) and np.allclose(plain.frame["z"], truth["z"])
    assert not any("preamble" in n for n in plain.notes + bare.notes)
    ragged = ["t,x,z"] + [line.rsplit(",", 1)[0] if k in (1, 3) else line for k, line in enumerate(lines)]
    (tmp_path / "ragged.csv").write_text("\n".join(ragged) + "\n")        # rows 2 and 4 short of their z
    table = read_table(tmp_path / "ragged.csv")
    assert list(table.frame.columns) == ["t", "x", "z"] and len(table.frame) == len(truth["t"])
    assert np.allclose(table.frame["x"], truth["x"]) and table.frame["z"].isna().sum() == 2
