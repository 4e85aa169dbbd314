"""Tyre saturation whose friction lies beyond the class's range is kept, the friction reported as
"at least" the range's top, not rejected.

Independent truth: the F1TENTH study simulated with tyres of friction 2.2 (shape 1.6) at 2, 3 and 4
m/s and full steering: its turns bend the tyre curve (|a_y| to 16 m/s2) but a scale car's friction
range ends at 1.8."""
from __future__ import annotations

import pandas as pd
import pytest

from agrobot.identification.ordinary_driving import identify_driving, summary
from agrobot.orchestrator.runner import simulate
from agrobot.orchestrator.study import Study
from tests.vehicle_logs import ROOT_STUDIES

STUDY = ROOT_STUDIES / "f1tenth.toml"


@pytest.mark.slow
def test_friction_beyond_the_class_keeps_saturation_as_at_least():
    st = Study.load(STUDY).with_values({"study.stop_time": 60.0, "plan.duration": 60.0, "plan.speeds": [2.0, 3.0, 4.0],
                                        "plan.steer_scale": 1.0, "car.tyre_friction": 2.2, "car.tyre_shape": 1.6})
    rec, _ = simulate(st)
    f = rec.to_frame().iloc[::4].reset_index(drop=True)
    log = pd.DataFrame({"t": f["t"], "delta": f["steering.steer_angle_measured"], "v": f["plan.speed_cmd"],
                        "yaw_rate": f["gyro.yaw_rate_measured"]})
    rep = identify_driving(log, "friction 2.2", Study.load(STUDY))
    tyre = rep["tyre_saturation"]
    assert tyre["found"], tyre["why_not"]
    mu = tyre["parameters"]["friction"]
    assert mu["at_least"] and mu["bounds"][1] <= 2.2 and not mu["identifiable"]
    assert "friction at least 1.8" in summary(rep)


def test_diagnose_repeats_an_at_least_friction_as_at_least():
    """identify's "at least 1.8" is not told on by diagnose as a friction of 1.8."""
    import types

    from agrobot.diagnosis.pipeline import agreement

    identified = {"tyre_saturation": {"friction": 1.8, "friction_at_least": True, "shape": 1.3,
                                      "held_out_gain": 0.3}}
    lines = agreement(identified, [], types.SimpleNamespace(first_step=[]))
    assert any("friction at least 1.8," in line for line in lines), lines
    identified["tyre_saturation"]["friction_at_least"] = False
    assert any("friction 1.8," in line for line in agreement(identified, [], types.SimpleNamespace(first_step=[])))
