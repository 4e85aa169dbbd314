"""identify fits the single-track model on the wheelbase it uses: a wheelbase given with the
recording (--wheelbase) that differs from the study's yaw plant's l_f + l_r scales the plant's
axles to it, so that the dynamic fit's understeer gradient and the steady turns' stand on one
wheelbase. Truth: the passenger-car study simulated with its axles at l_f 1.32 m, l_r 1.65 m
(wheelbase 2.97 m, the size of a racecar), K = m (l_r / C_f - l_f / C_r) / L in closed form,
identified with the 2.7 m study and --wheelbase 2.97."""
from __future__ import annotations

import pandas as pd
import pytest

from agrobot.identification.ordinary_driving import identify_driving
from agrobot.orchestrator.runner import simulate
from agrobot.orchestrator.study import Study
from tests.vehicle_logs import ROOT_STUDIES

STUDY = ROOT_STUDIES / "passenger_car.toml"
L_F, L_R, M, C_F, C_R = 1.32, 1.65, 1500.0, 80000.0, 100000.0
K_TRUE = M * (L_R / C_F - L_F / C_R) / (L_F + L_R)


@pytest.fixture(scope="module")
def longer_car():
    study = Study.load(STUDY)
    sim = study.with_values({"car.l_f": L_F, "car.l_r": L_R, "study.stop_time": 120.0, "plan.duration": 120.0})
    f = simulate(sim)[0].to_frame().iloc[::5].reset_index(drop=True)          # 20 Hz
    log = pd.DataFrame({"t": f["t"], "delta": f["steering.steer_angle_measured"], "v": f["plan.speed_cmd"],
                        "yaw_rate": f["gyro.yaw_rate_measured"]})
    return log, study


@pytest.mark.slow
def test_the_dynamic_fit_stands_on_the_given_wheelbase(longer_car):
    log, study = longer_car
    rep = identify_driving(log, "longer car", study, wheelbase=L_F + L_R)
    veh = rep["vehicle"]
    assert veh["l_f"] + veh["l_r"] == pytest.approx(L_F + L_R, rel=1e-6)
    assert veh["l_f"] / (veh["l_f"] + veh["l_r"]) == pytest.approx(1.2 / 2.7, rel=1e-6)    # the study's ratio kept
    assert "scaled to it" in veh["wheelbase_from"]
    K = rep["understeer_gradient"]["value"]
    # on the study's 2.7 m the fitted K absorbs part of (L - 2.7) / v^2 (0.27 / 400 at 20 m/s)
    assert abs(K - K_TRUE) < 0.04 * K_TRUE, (K, K_TRUE)          # without the scaling: 0.00411, 9.5 % high


def test_a_plant_on_the_wheelbase_already_is_left_alone():
    from agrobot.components.models.yaw_dynamics import TractorParameters
    from agrobot.identification.ordinary_driving import plant_on_wheelbase

    p = TractorParameters(l_f=1.2, l_r=1.5)
    same, said = plant_on_wheelbase(p, 2.7, "the study's")
    assert same is p and said == "the study's"
    longer, said = plant_on_wheelbase(p, 3.0, "given")
    assert (longer.l_f, longer.l_r) == pytest.approx((1.2 * 3.0 / 2.7, 1.5 * 3.0 / 2.7))
    assert "2.7 m" in said and "scaled" in said
