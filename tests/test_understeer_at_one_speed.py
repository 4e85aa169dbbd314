"""A commanded steering angle at one speed: the steering gain g and the understeer gradient K give
the same steady yaw rate g v / (L + K v^2), so identify does not conclude K (nor a critical speed).

Independent truth: the F1TENTH study simulated at one speed (1.3 m/s) and logged with its command
only; its gain and K are those of the study, but a log at one speed cannot tell them apart."""
from __future__ import annotations

import pandas as pd

from agrobot.identification.ordinary_driving import identify_driving, summary
from agrobot.orchestrator.runner import simulate
from agrobot.orchestrator.study import Study
from tests.vehicle_logs import ROOT_STUDIES

STUDY = ROOT_STUDIES / "f1tenth.toml"


def one_speed_log(speed: float = 1.3, stop: float = 90.0) -> pd.DataFrame:
    st = Study.load(STUDY).with_values({"study.stop_time": stop, "plan.duration": stop, "plan.speeds": [speed],
                                        "plan.steer_scale": 1.0})
    rec, _ = simulate(st)
    f = rec.to_frame().iloc[::4].reset_index(drop=True)          # 50 Hz
    return pd.DataFrame({"t": f["t"], "delta_cmd": f["plan.steer_angle_cmd"], "v": f["plan.speed_cmd"],
                         "yaw_rate": f["gyro.yaw_rate_measured"]})


def test_one_speed_with_a_commanded_angle_concludes_no_understeer_gradient():
    study = Study.load(STUDY)
    rep = identify_driving(one_speed_log(), "one speed", study)
    assert rep["final_model"] != "kinematic", rep.get("regime")
    K = rep["understeer_gradient"]
    assert not K["identifiable"] and "one speed" in K["note"]
    assert not rep["characteristic_speed"]["identifiable"] and "one speed" in rep["characteristic_speed"]["note"]
    text = summary(rep)
    assert "critical speed:" not in text and "characteristic speed:" not in text
