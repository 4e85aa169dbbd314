"""A noise floor read on a channel the import interpolated onto its even grid (diagnosis.noise_floor):
a gyro of known white noise sigma on its own jittered stamps (1-5 % of a step), linearly
interpolated onto rows offset from them, at another rate or four times faster, on a slow yaw motion the model predicts
exactly. Linear interpolation damps the top band the white level is read from more than the rest,
so read on the rows the level comes out at 0.5-0.8 sigma; corrected by the interpolation's own
effect it is sigma, and the floor is the RMS the interpolated noise has on the held-out rows. A
noise that grows with speed (the held-out part faster) is judged on the held-out rows."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.diagnosis.noise_floor import stage_floors

SIGMA, H, SECONDS = 0.01, 0.02, 120.0


class InterpolatedGyro:
    """The parts of a replay (diagnosis.candidates.Replay) the yaw stage's floor reads: the gyro
    interpolated onto the rows ``t`` from its own stamps, the model's yaw rate the truth's."""

    stages = ("yaw",)

    def __init__(self, t, own_t, own_v, truth, test):
        self.t, self.h, self.truth = t, float(np.median(np.diff(t))), truth
        self.frame = pd.DataFrame({"t": t, "yaw_rate": np.interp(t, own_t, own_v)})
        self.frame.attrs["own_samples"] = {"yaw_rate": (own_t.tolist(), own_v.tolist())}
        self.masks = {"yaw": {"fit": ~test, "test": test}}

    def measured(self, stage):
        return self.frame["yaw_rate"].to_numpy(float)

    def seen(self, stage, pred):
        return pred

    def predicted(self, stage, values):
        return self.truth

    def scored(self, stage):
        return self.masks[stage]["fit"] | self.masks[stage]["test"]

    def residual_series(self, stage, values):
        keep = self.scored(stage)
        return self.t[keep], (self.measured(stage) - self.truth)[keep]


def slow(t):
    return 0.2 * np.sin(2 * np.pi * 0.1 * t)


def gyro_on_grid(jitter: float, grid: str, seed: int = 4, sigma_of=lambda t: SIGMA + 0 * t):
    """(the replay, the noise the rows carry): white noise of sigma_of(t) on stamps k P + jitter P N(0, 1),
    interpolated onto rows of step H 0.3 H after them: P = H ('offset'), P = 4 H ('slower'), or rows
    at 1.01 x their rate ('rate')."""
    rng = np.random.default_rng(seed)
    own = 4 * H if grid == "slower" else H
    own_t = own * np.arange(int(SECONDS / own)) + jitter * own * rng.standard_normal(int(SECONDS / own))
    noise = sigma_of(own_t) * rng.standard_normal(len(own_t))
    step = H / 1.01 if grid == "rate" else H
    t = own_t[0] + H + 0.3 * H + step * np.arange(int((own_t[-1] - own_t[0] - 3 * H) / step))
    test = t >= 0.6 * t[-1]
    replay = InterpolatedGyro(t, own_t, slow(own_t) + noise, slow(t), test)
    return replay, np.interp(t, own_t, noise)


@pytest.mark.parametrize("jitter", [0.01, 0.05])
@pytest.mark.parametrize("grid", ["offset", "rate", "slower"])
def test_the_floor_of_an_interpolated_gyro_is_its_sigma(jitter, grid):
    replay, on_rows = gyro_on_grid(jitter, grid)
    floors = stage_floors(replay, {})
    assert abs(floors["_sensors"]["yaw_rate"] - SIGMA) < 0.1 * SIGMA, floors
    rms_test = float(np.sqrt(np.mean(on_rows[replay.masks["yaw"]["test"]] ** 2)))   # what the verdict compares
    assert abs(floors["yaw"] - rms_test) < 0.1 * rms_test, (floors, rms_test)


def test_a_noise_growing_with_speed_is_judged_on_the_held_out_rows():
    replay, on_rows = gyro_on_grid(0.0, "offset", sigma_of=lambda t: np.where(t >= 0.6 * SECONDS, 2 * SIGMA, SIGMA))
    floors = stage_floors(replay, {})
    rms_test = float(np.sqrt(np.mean(on_rows[replay.masks["yaw"]["test"]] ** 2)))
    assert abs(floors["yaw"] - rms_test) < 0.1 * rms_test, (floors, rms_test)


def test_a_clean_log_with_jittered_stamps_is_not_unexplained(tmp_path):
    """A clean generated log (harness.truth_tractor) re-stamped with a 3 % jitter, imported onto rows
    at 20.2 Hz (the import's grid at another rate than the 20 Hz samples): the gyro's white level
    is the truth's, and the yaw stage is not above its floor."""
    from agrobot.diagnosis.pipeline import diagnose
    from agrobot.measurements.options import ImportOptions
    from agrobot.measurements.signal_expressions import parse_signal
    from harness.truth_tractor import VEHICLES, make_log

    frame, _ = make_log(5, None, duration=120.0)
    h = float(np.median(np.diff(frame["t"])))
    frame["t"] = frame["t"] + 0.03 * h * np.random.default_rng(7).standard_normal(len(frame))
    frame.to_csv(tmp_path / "log.csv", index=False)
    columns = ("delta_cmd=delta_cmd[rad]", "delta=delta[rad]", "v=v[m/s]", "yaw_rate=yaw_rate[rad/s]", "x=x[m]", "y=y[m]")
    res = diagnose(tmp_path / "log.csv", None, identify=False, plots=False,
                   recording=ImportOptions(signals=[parse_signal(s) for s in columns], rate=1.01 / h))
    sigma = VEHICLES["tractor"]["gyro_noise"]
    assert abs(res["noise_floor"]["sensors"]["yaw_rate"] - sigma) < 0.1 * sigma, res["noise_floor"]
    assert not res["stages"]["yaw"]["misfit"] and res["stages"]["yaw"]["ratio"] < 1.25, res["stages"]["yaw"]
    assert res["verdict"] != "unexplained", res["selection_trace"]
