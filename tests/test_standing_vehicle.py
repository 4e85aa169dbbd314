"""A J1939 vehicle logged standing (ignition on, engine at 0 rpm, wheel-based speed 0 for three
minutes, its speed from another source address than the DBC's): the refusal says what the channels
hold and that the vehicle does not move, not that the file may be zeros or the logger idle; a speed
held at a constant non-zero value is named as a held value instead."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.recording import ImportOptions, import_recording

DBC = '''VERSION ""

BS_:

BU_:

BO_ 2364540158 EEC1: 8 Vector__XXX
 SG_ EngineSpeed : 24|16@1+ (0.125,0) [0|8031.875] "rpm" Vector__XXX

BO_ 2566844926 CCVS1: 8 Vector__XXX
 SG_ WheelBasedVehicleSpeed : 8|16@1+ (0.00390625,0) [0|250.996] "km/h" Vector__XXX
'''
SECONDS = 186.0


def _write(folder, kmh: float):
    """EEC1 at 100 Hz (0 rpm) and CCVS1 at 10 Hz (``kmh``) from source 0x47, for SECONDS s."""
    import cantools

    (folder / "j1939.dbc").write_text(DBC)
    db = cantools.database.load_string(DBC)
    eec, ccvs = db.get_message_by_name("EEC1"), db.get_message_by_name("CCVS1")
    lines = []
    for k, t in enumerate(np.arange(0.0, SECONDS, 0.01)):
        stamp = 1.6225e9 + t
        lines.append(f"({stamp:.6f}) can0 0CF00447#{eec.encode({'EngineSpeed': 0.0}).hex().upper()}")
        if k % 10 == 0:
            lines.append(f"({stamp:.6f}) can0 18FEF147#{ccvs.encode({'WheelBasedVehicleSpeed': kmh}).hex().upper()}")
    (folder / "standing.log").write_text("\n".join(lines) + "\n")


def _refusal(folder, kmh: float) -> str:
    pytest.importorskip("cantools")
    _write(folder, kmh)
    with pytest.raises(LogError) as err:
        import_recording(folder / "standing.log", ImportOptions(dbc=folder / "j1939.dbc"))
    return str(err.value)


def test_a_standing_vehicle_is_named_standing_with_its_channels_values(tmp_path):
    text = _refusal(tmp_path, 0.0)
    assert "v (" in text and "holds 0 m/s" in text and "does not move in the recording" in text
    assert f"over its {SECONDS:.0f} s" in text
    assert "zeros" not in text and "not recording" not in text


def test_a_speed_held_at_one_non_zero_value_is_named_held_not_standing(tmp_path):
    text = _refusal(tmp_path, 36.0)
    assert "holds 10 m/s" in text and "value held" in text and "does not move" not in text
