"""A steering input held between its rows (``--input-hold zoh``): the yaw model reads it as a
zero-order hold (identification.driving: DrivingLog.hold_phases, the exact augmented step; the C
kernel alike). Truth: a single-track car (linear tyres) whose wheels follow a 10 Hz command held
from its own stamps, 0.08 s late, simulated here on a 1 ms clock (classic Runge-Kutta); the log's
rows are the command's stamps. A continuous input is still interpolated."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.components.models.tyre import axle_loads
from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.estimation import Parameter
from agrobot.identification.driving import (BadInputHold, HeldInput, YawModel, cut_segments, even_grid, fit,
                                            input_hold)

M, I_Z, L_F, L_R, C_F, C_R = 3.33, 0.0687, 0.112, 0.208, 106.0, 57.0
DELAY, ROW, FINE = 0.08, 0.1, 1e-3
P = TractorParameters(m=M, I=I_Z, l_f=L_F, l_r=L_R, C_f=C_F, C_r=C_R)
FZF, FZR = axle_loads(M, L_F, L_R)


def _truth(seconds: float = 40.0) -> pd.DataFrame:
    """The log: rows every ROW s, the command sent at each row and held, the yaw rate at the rows."""
    rng = np.random.default_rng(5)
    t = np.arange(0.0, seconds, ROW)
    f, ph = rng.uniform(0.1, 1.0, 6), rng.uniform(0, 2 * np.pi, 6)
    cmd = 0.1 * np.sum(np.sin(2 * np.pi * f[:, None] * t + ph[:, None]), axis=0)
    tf = np.arange(0.0, seconds, FINE)
    v = 1.8 + 0.4 * np.sin(2 * np.pi * tf / 17.0)
    delta = cmd[np.clip(np.floor((tf - DELAY) / ROW + 1e-9).astype(int), 0, len(t) - 1)]

    def f_(z, vk, dk):
        ff = C_F * (dk - (z[0] + L_F * z[1]) / vk)
        fr = -C_R * (z[0] - L_R * z[1]) / vk
        return np.array([(ff + fr) / M - vk * z[1], (L_F * ff - L_R * fr) / I_Z])

    z, r = np.zeros(2), np.empty(len(tf))
    for k in range(len(tf)):
        r[k] = z[1]
        k1 = f_(z, v[k], delta[k])
        k2 = f_(z + 0.5 * FINE * k1, v[k], delta[k])
        k3 = f_(z + 0.5 * FINE * k2, v[k], delta[k])
        k4 = f_(z + FINE * k3, v[k], delta[k])
        z = z + FINE / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return pd.DataFrame({"t": t, "delta_cmd": cmd, "v": np.interp(t, tf, v), "yaw_rate": np.interp(t, tf, r)})


def _fitted(hold: str) -> dict:
    log = even_grid(_truth(), "delta_cmd", max_rate=1 / ROW, hold=hold)
    segs = cut_segments(log, 0.5, length=10.0)
    model = YawModel("bicycle", P, log, segs)
    free = [Parameter("delay", "s", 0.05, -0.2, 0.4), Parameter("lag", "s", 0.05, 0.0, 0.5)]
    return fit(model, free, {"delay": 0.05, "lag": 0.02}, {"c_f": C_F / FZF, "c_r": C_R / FZR}, segs).values


def test_a_held_command_gives_its_pure_delay_and_no_lag():
    found = _fitted("zoh")
    assert abs(found["delay"] - DELAY) < ROW / 4 and found["lag"] < 0.01, found


def test_the_linear_reading_of_the_held_command_misses_the_delay():
    """The same log read linearly between rows: the ramp to each value starts a row early, taken for delay."""
    found = _fitted("linear")
    assert abs(found["delay"] + found["lag"] - DELAY) > ROW / 4, found


def test_a_continuous_input_is_interpolated_and_said():
    frame = pd.DataFrame({"t": [0.0, 0.1, 0.2, 0.3], "delta": [0.0, 0.1, 0.2, 0.3], "v": 1.0, "yaw_rate": 0.0})
    log = even_grid(frame, "delta", max_rate=100.0)
    assert log.held is None
    assert np.allclose(log.delayed_input(0.05), [0.0, 0.05, 0.15, 0.25])
    assert any("delta read linearly" in n and "--input-hold zoh" in n for n in log.notes)
    held = even_grid(frame, "delta", max_rate=100.0, hold="zoh")
    assert np.allclose(held.delayed_input(0.05), [0.0, 0.0, 0.1, 0.2])
    assert any("delta taken as held" in n for n in held.notes)


def test_a_bad_input_hold_is_refused():
    with pytest.raises(BadInputHold, match="--input-hold 'step'"):
        input_hold(pd.DataFrame({"delta": [0.0]}), "delta", "step")
    from agrobot.api import identify
    from agrobot.orchestrator.errors import InputError
    with pytest.raises(InputError, match="--input-hold step"):
        identify("log.csv", input_hold="step")


@pytest.mark.parametrize("model", ["bicycle", "rlf", "rlfr"])
def test_the_kernel_equals_the_python_path_on_a_held_input(model):
    t = np.arange(0.0, 16.0, 0.05)
    tk = np.arange(0.013, 16.0, 1 / 7)
    held = HeldInput(tk, 0.25 * np.sin(0.9 * tk) + 0.1 * np.sign(np.sin(0.31 * tk)))
    log = even_grid(pd.DataFrame({"t": t, "delta_cmd": held.at(t), "v": 2.6 + 2.4 * np.sin(0.2 * t),
                                  "yaw_rate": 0.0}), "delta_cmd", max_rate=20.0, hold="zoh")
    log.held, log.u = held, held.at(t)            # updates between the rows: each step's switch inside it
    segs = cut_segments(log, 0.02, length=4.0)
    m = YawModel(model, P, log, segs, min_sim_speed=0.3)
    sets = [{"c_f": C_F / FZF, "c_r": C_R / FZR, "lag": lag, "delay": delay, "friction": mu}
            for lag, delay, mu in ((0.12, 0.1, np.inf), (0.0, 0.037, np.inf), (0.05, -0.02, 0.6), (0.0, 0.06, 0.6))]
    m.kernel = "python"
    ref = m.simulate_many(sets, lateral=True)
    m.kernel = "c"
    got = m.simulate_many(sets, lateral=True)
    for a, b in zip(ref, got):
        assert np.max(np.abs(a)) > 0.05
        assert np.max(np.abs(a - b)) / np.max(np.abs(a)) < 1e-9


def test_a_recordings_own_samples_set_the_hold_and_the_gyros_reading():
    """A set-point with its own stamps (frame.attrs["own_samples"], as the importer gives them) is held
    on them; a gyro whose rows interpolate its own samples: the model's yaw rate read alike, here
    against np.interp twice (the importer's reading of the truth)."""
    from agrobot.measurements.runs import OwnSamples

    rows = np.arange(0.0, 6.0, 0.025)
    cmd_t, gyro_t = np.arange(0.013, 6.0, 1 / 30), np.arange(0.004, 6.0, 1 / 27)     # updates faster than 25 Hz
    cmd = np.round(np.sin(cmd_t), 3)
    frame = pd.DataFrame({"t": rows, "delta_cmd": HeldInput(cmd_t, cmd).at(rows), "v": 1.0,
                          "yaw_rate": np.interp(rows, gyro_t, np.cos(gyro_t))})
    frame.attrs["own_samples"] = OwnSamples({"delta_cmd": (cmd_t.tolist(), cmd.tolist()),
                                             "yaw_rate": (gyro_t.tolist(), np.cos(gyro_t).tolist())})
    log = even_grid(frame, "delta_cmd", max_rate=25.0, hold="auto")
    assert log.h == pytest.approx(0.025) and np.array_equal(log.held.times, cmd_t)      # the rows: one switch a step
    assert np.allclose(log.delayed_input(0.08), np.sin(cmd_t)[np.clip(np.searchsorted(cmd_t, rows - 0.08, "right") - 1,
                                                                     0, None)], atol=1e-3)
    assert any(f"own {len(cmd_t)} updates" in n for n in log.notes), log.notes
    y = np.sin(3.0 * rows) + rows ** 2                                   # any model output on the rows
    assert np.allclose(log.as_measured(y), np.interp(rows, gyro_t, np.interp(gyro_t, rows, y)), atol=1e-12)
    assert pd.concat([frame, frame]).attrs["own_samples"] is frame.attrs["own_samples"]


def test_a_set_point_stamped_in_bursts_is_read_linearly_and_said():
    """Stamps of receipt (bursts: 10-90 % of the intervals far from the median) do not say when the
    command took effect: auto reads it between rows; zoh still holds it on them."""
    from agrobot.measurements.runs import OwnSamples

    rng = np.random.default_rng(2)
    stamps = np.cumsum(rng.choice([0.003, 0.01, 0.04, 0.1, 0.2], 200))
    rows = np.arange(0.0, stamps[-1], 0.044)
    cmd = np.round(np.sin(stamps), 4)
    frame = pd.DataFrame({"t": rows, "delta_cmd": HeldInput(stamps, cmd).at(rows), "v": 1.0, "yaw_rate": 0.0})
    frame.attrs["own_samples"] = OwnSamples({"delta_cmd": (stamps.tolist(), cmd.tolist())})
    log = even_grid(frame, "delta_cmd", max_rate=25.0, hold="auto")
    assert log.held is None and any("come in bursts" in n for n in log.notes), log.notes
    assert np.array_equal(even_grid(frame, "delta_cmd", max_rate=25.0, hold="zoh").held.times, stamps)
