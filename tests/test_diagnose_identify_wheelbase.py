"""``diagnose --wheelbase`` reaches the identify step it runs first, as ``identify --wheelbase`` takes
it: on the passenger-car study (2.7 m) a log of a 2.97 m car identified on 2.7 m puts part of
(L - 2.7) / v^2 into its understeer gradient. Truth: the wheelbase handed over on the command line
and, on the car simulated with axles l_f 1.32 m, l_r 1.65 m, the closed-form
K = m (l_r / C_f - l_f / C_r) / L."""
from __future__ import annotations

import pandas as pd
import pytest

from agrobot.diagnosis import pipeline
from agrobot.orchestrator.cli import main
from agrobot.orchestrator.runner import simulate
from agrobot.orchestrator.study import Study
from tests.vehicle_logs import ROOT_STUDIES

STUDY = ROOT_STUDIES / "passenger_car.toml"
L_F, L_R, M, C_F, C_R = 1.32, 1.65, 1500.0, 80000.0, 100000.0
K_TRUE = M * (L_R / C_F - L_F / C_R) / (L_F + L_R)


class Stopped(Exception):
    """Raised in place of the identification, to stop diagnose once it has been called."""


@pytest.fixture(scope="module")
def longer_car(tmp_path_factory):
    study = Study.load(STUDY)
    sim = study.with_values({"car.l_f": L_F, "car.l_r": L_R, "study.stop_time": 120.0, "plan.duration": 120.0})
    f = simulate(sim)[0].to_frame().iloc[::5].reset_index(drop=True)          # 20 Hz
    log = pd.DataFrame({"t": f["t"], "delta": f["steering.steer_angle_measured"], "v": f["plan.speed_cmd"],
                        "yaw_rate": f["gyro.yaw_rate_measured"]})
    path = tmp_path_factory.mktemp("car") / "car.csv"
    log.to_csv(path, index=False)
    return path, log


def test_the_command_lines_wheelbase_reaches_identify(longer_car, tmp_path, monkeypatch):
    path, _ = longer_car
    seen = {}

    def identify_driving(frame, where, study, **options):
        seen.update(options)
        raise Stopped

    monkeypatch.setattr(pipeline, "identify_driving", identify_driving)
    with pytest.raises(Stopped):
        main(["diagnose", str(path), "--study", str(STUDY), "--wheelbase", "2.97", "--out", str(tmp_path / "dx"),
              "--no-plots", "--no-progress"])
    assert seen["wheelbase"] == pytest.approx(2.97)


def test_the_identified_gradient_stands_on_the_given_wheelbase(longer_car):
    _, log = longer_car
    study = Study.load(STUDY)
    baseline = pipeline.baseline_from_study(study)
    given = pipeline.identified_vehicle(log, "longer car", study, baseline, wheelbase=L_F + L_R)
    K = given["identified"]["understeer_gradient"]["value"]
    assert abs(K - K_TRUE) < 0.04 * K_TRUE, (K, K_TRUE)           # on the study's 2.7 m: 9.5 % high
