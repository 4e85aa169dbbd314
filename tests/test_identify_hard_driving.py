"""A sports car driven hard on a road circuit, recorded as one-column text files (a road-wheel angle,
a gyro, the speed, one time file; as the Revs vehicle-dynamics excerpts are): a linear single-track
model of a 2.4 m, 982 kg mid-engined car (l_f 1.33 m, l_r 1.07 m) at 18-40 m/s with up to 0.03 rad
of road-wheel angle, its understeer gradient known from its cornering stiffnesses
(K = m / L (l_r / C_f - l_f / C_r), Rajamani 3.3). The passenger-car study's steering ratio 15.8 is
not divided into a road-wheel angle (the turns' yaw rate is about v delta / L, not 1/15.8 of it), and
is divided into the same car's handwheel angle; an angle on the wrong scale is refused however much
the steering moves; a critical speed below the speeds driven is not a verdict; the wheelbase
`convert --wheelbase` was given is recorded beside the converted log and read back by identify."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from agrobot.identification.driving import NotEnoughDriving
from agrobot.identification.from_log import recorded_wheelbase
from agrobot.identification.ordinary_driving import characteristic_speed, identify_driving
from agrobot.measurements.recording import ImportOptions, describe, import_recording
from agrobot.orchestrator.study import load_study
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
CAR = ROOT / "studies" / "passenger_car.toml"
RATE = 100.0
M, LF, LR = 982.0, 1.33, 1.07
L = LF + LR
IZ = M * LF * LR
CF, CR = 7.0e4, 1.2e5                   # N/rad, the axle's
K_TRUE = M / L * (LR / CF - LF / CR)    # rad/(m/s2): understeer
SHAPE = 1.3                             # Magic Formula C of the saturating tyre


def drive(seconds: float = 120.0, seed: int = 7, steer: float = 0.03, friction: float | None = None,
          rear: float = CR, rear_friction: float | None = None) -> dict:
    """t, delta (road wheel), vx, yawRate of the car: speed 18-40 m/s swept slowly, steering a
    smoothed random walk of held angles up to ``steer`` rad; linear tyres, or with ``friction`` a
    Magic Formula tyre mu F_z sin(SHAPE atan(B alpha)) of the same cornering stiffness (``rear``:
    the rear axle's [N/rad]; ``rear_friction``: the rear tyres' mu where it is not ``friction``); Euler at
    1 kHz, rows at RATE."""
    rng = np.random.default_rng(seed)
    n = int(seconds * 1000)
    t = np.arange(n) / 1000.0
    v = 29.0 + 11.0 * np.sin(2 * np.pi * t / 70.0)
    held = np.repeat(rng.uniform(-steer, steer, n // 1500 + 1), 1500)[:n]
    delta = np.convolve(held, np.ones(300) / 300, mode="same")
    loads = (M * 9.81 * LR / L, M * 9.81 * LF / L)

    def force(c, alpha, fz, mu=friction):
        if mu is None:
            return c * alpha
        return mu * fz * math.sin(SHAPE * math.atan(c / (SHAPE * mu * fz) * alpha))

    vy = r = 0.0
    yaw = np.empty(n)
    for i in range(n):
        fy_f = force(CF, delta[i] - (vy + LF * r) / v[i], loads[0])
        fy_r = force(rear, -(vy - LR * r) / v[i], loads[1], friction if rear_friction is None else rear_friction)
        vy += 1e-3 * ((fy_f + fy_r) / M - v[i] * r)
        r += 1e-3 * (LF * fy_f - LR * fy_r) / IZ
        yaw[i] = r
    rows = slice(None, None, int(1000 / RATE))
    noise = np.random.default_rng(seed + 1)
    return {"t": 150.0 + t[rows], "delta": delta[rows] + noise.normal(0, 2e-4, n)[rows], "vx": v[rows],
            "yawRate": yaw[rows] + noise.normal(0, 2e-3, n)[rows]}


SIGNALS = ["delta=delta.col1[rad]", "yaw_rate=yawRate.col1[rad/s]", "v=vx.col1[m/s]"]


def write(folder: Path, channels: dict[str, np.ndarray]) -> Path:
    """One headerless one-column text file per channel (t.txt the time of all)."""
    folder.mkdir()
    [np.savetxt(folder / f"{name}.txt", x, fmt="%15.8e") for name, x in channels.items()]
    return folder


def options(**kw) -> ImportOptions:
    return ImportOptions(signals=SIGNALS, time="t.col1[s]", wheelbase=L, rate=50.0, **kw)


@pytest.fixture(scope="module")
def car():
    return drive()


def test_the_studys_ratio_is_not_divided_into_a_road_wheel_angle_and_says_so(car, tmp_path):
    frame, report = import_recording(write(tmp_path / "road", car), options().for_vehicle(load_study(CAR)))
    moving = frame["v"] > 1.0
    assert np.std(frame["delta"][moving]) == pytest.approx(np.std(car["delta"]), rel=0.05)   # as recorded
    said = report["steering_ratio"]
    assert said["applied"] == 1.0 and said["decided_from_turns"]
    assert "the study's 15.8 passed over" in said["text"] and "--steering-ratio" in said["text"]
    assert said["text"] in describe(report)                                                  # on the console


def test_the_studys_ratio_is_divided_into_a_handwheel_angle(car, tmp_path):
    handwheel = dict(car, delta=15.8 * car["delta"])
    frame, report = import_recording(write(tmp_path / "hand", handwheel), options().for_vehicle(load_study(CAR)))
    assert np.std(frame["delta"][frame["v"] > 1.0]) == pytest.approx(np.std(car["delta"]), rel=0.05)
    assert report["steering_ratio"]["applied"] == 15.8 and "applied" in report["steering_ratio"]["text"]


def test_a_ratio_given_is_taken_as_given(car, tmp_path):
    frame, report = import_recording(write(tmp_path / "given", car),
                                     options(steering_ratio=15.8).for_vehicle(load_study(CAR)))
    assert np.std(frame["delta"][frame["v"] > 1.0]) == pytest.approx(np.std(car["delta"]) / 15.8, rel=0.05)
    assert not report["steering_ratio"]["decided_from_turns"] and "(given)" in report["steering_ratio"]["text"]


def test_a_road_wheel_angle_divided_by_a_ratio_is_refused_however_much_it_steers(tmp_path):
    frame, _ = import_recording(write(tmp_path / "scaled", drive(60.0, steer=0.07)), options(steering_ratio=15.8))
    asked = np.std((frame["v"] * frame["delta"] / L)[frame["v"] > 1.0])
    assert asked > 0.02                             # the steering moves: the low-excitation path is not taken
    with pytest.raises(NotEnoughDriving, match="is not the road-wheel angle"):
        identify_driving(frame, "scaled", load_study(CAR), wheelbase=L)


def test_a_critical_speed_below_the_speeds_driven_is_not_a_verdict():
    K = -0.005                                      # sqrt(L / |K|) = 21.9 m/s
    driven = characteristic_speed(K, 0.001, L, top_speed=40.0)
    assert not driven["identifiable"] and "impossible" in driven["note"]
    beyond = characteristic_speed(K, 0.001, L, top_speed=15.0)       # never driven at it: a prediction
    assert beyond["identifiable"] and math.isclose(beyond["value"], math.sqrt(L / 0.005))


def converted_with_wheelbase(car, tmp_path: Path) -> Path:
    """The car's recording converted with ``--wheelbase L`` (recorded in car.import.json)."""
    folder = write(tmp_path / "rec", car)
    out = tmp_path / "car.csv"
    proc = cli("convert", folder, "--signal", "delta=delta.col1[rad]", "--signal", "yaw_rate=yawRate.col1[rad/s]",
               "--signal", "v=vx.col1[m/s]", "--time", "t.col1[s]", "--wheelbase", L, "--out", out)
    assert proc.returncode == 0, proc.stderr
    return out


def test_convert_records_the_wheelbase_and_identify_reads_it_back(car, tmp_path):
    out = converted_with_wheelbase(car, tmp_path)
    assert json.loads((tmp_path / "car.import.json").read_text())["wheelbase"]["value"] == L
    value, said = recorded_wheelbase(out, None)
    assert value == L and "car.import.json" in said
    value, said = recorded_wheelbase(out, 2.0)                       # given on the command line: it wins, said
    assert value == 2.0 and f"the {L:.3g} m that convert --wheelbase recorded in car.import.json passed over" in said


def sports_car_study(folder: Path) -> Path:
    """The passenger-car study with this car's numbers: class sports_car, 2.4 m, 982 kg, its axles."""
    text = CAR.read_text().replace('class = "car"', 'class = "sports_car"').replace("steering_ratio = 15.8", "steering_ratio = 1.0")
    text = text.replace("wheelbase = 2.7", f"wheelbase = {L}").replace(
        "m = 1500.0, I = 2500.0, l_f = 1.2, l_r = 1.5", f"m = {M}, I = {IZ:.1f}, l_f = {LF}, l_r = {LR}")
    (folder / "sports_car.toml").write_text(text)
    return folder / "sports_car.toml"


@pytest.mark.slow
def test_a_rear_axle_stiffer_than_the_class_range_is_fitted_not_left_on_its_bound(tmp_path):
    rear = 2.2e5                                    # N/rad: 41 per unit rear-axle load, beyond the class's 30
    frame, _ = import_recording(write(tmp_path / "stiff", drive(90.0, rear=rear)), options())
    study = load_study(sports_car_study(tmp_path))
    report = identify_driving(frame, "stiff", study, wheelbase=L)
    found = report["cornering_stiffness"]["rear"]
    assert found["identifiable"], found
    assert found["value"] == pytest.approx(rear, rel=0.15)
    assert any("fitted again within their physical limits" in n for n in report["notes"])
    # planted without a delay: a model that lags more than the car (its relaxation length held on its
    # bound) makes the delay go below zero, which is then not a clock offset
    assert report["delay"]["verdict"] != "clock offset", report["delay"]["note"]


@pytest.mark.slow
def test_diagnose_stands_on_the_wheelbase_convert_recorded(car, tmp_path):
    """diagnose's identification on the same log takes the recorded wheelbase as identify does, and says so."""
    out = converted_with_wheelbase(car, tmp_path)
    proc = cli("diagnose", out, "--study", CAR, "--out", tmp_path / "diag", "--no-plots", "--time-range", 0, 40)
    said = proc.stdout + proc.stderr
    assert proc.returncode == 0, said
    assert f"wheelbase {L:.4g} m for the identification on the same log: recorded by convert --wheelbase" in said
