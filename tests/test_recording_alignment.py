"""A recording with one table per topic, each on its own clock and rate, with a known delay between
the steering command and the yaw rate: converted by the recording importer, the delay is the same
as in the truth (by a cross-correlation written here, and by the identification from driving).

The truth: a single-track car (the F1TENTH study's mass, inertia and axle distances, linear tyres)
whose front wheels follow the command held since its last message, ``DELAY`` s late; simulated
on a 1 ms clock (classic Runge-Kutta, written here), then sampled at the gyro's and the odometry's
own jittered stamps. Command 30 Hz, gyro 27 Hz (deg/s), odometry 40 Hz: a join that shifted one
stream by half a grid step (12-20 ms) would be seen.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parent.parent
DELAY = 0.08                     # s, command to front wheels
M, I_Z, L_F, L_R = 3.33, 0.0687, 0.112, 0.208
C_F, C_R = 106.0, 57.0           # N/rad
T0 = 1_650_000_000.25            # POSIX s: the recording's clock
H = 1e-3                          # s, the truth's step
DURATION = 60.0
SIGNALS = ("delta_cmd=commandData.delta[rad]", "yaw_rate=imuData.wz[deg/s]", "v=pfOdomData.vx[m/s]")


def _stamps(rng, rate: float, offset: float) -> np.ndarray:
    """Jittered message stamps (±15 % of the period) from T0 + offset to the end of the drive."""
    n = int((DURATION - 0.5) * rate)
    return T0 + offset + (np.arange(n) + rng.uniform(-0.15, 0.15, n)) / rate


def _held(tq: np.ndarray, t: np.ndarray, x: np.ndarray) -> np.ndarray:
    return x[np.clip(np.searchsorted(t, tq, side="right") - 1, 0, len(x) - 1)]


def _truth(seed: int = 3):
    """(fine clock, speed, yaw rate on it, command stamps and values): the single-track model
    m (v_y' + v r) = F_f + F_r, I r' = l_f F_f - l_r F_r, F_f = C_f (delta - (v_y + l_f r)/v),
    F_r = -C_r (v_y - l_r r)/v, delta(t) = the command in force at t - DELAY."""
    rng = np.random.default_rng(seed)
    t_cmd = _stamps(rng, 30.0, 0.013)
    s = t_cmd - T0
    freqs, phases = rng.uniform(0.1, 1.2, 8), rng.uniform(0, 2 * np.pi, 8)
    cmd = np.clip(0.12 * np.sum(np.sin(2 * np.pi * freqs[:, None] * s + phases[:, None]), axis=0), -0.34, 0.34)
    tf = T0 + np.arange(0.0, DURATION, H)
    v = 1.8 + 0.6 * np.sin(2 * np.pi * (tf - T0) / 23.0)
    delta = np.where(tf - DELAY >= t_cmd[0], _held(tf - DELAY, t_cmd, cmd), 0.0)

    def f(z, vk, dk):
        vy, r = z
        ff = C_F * (dk - (vy + L_F * r) / vk)
        fr = -C_R * (vy - L_R * r) / vk
        return np.array([(ff + fr) / M - vk * r, (L_F * ff - L_R * fr) / I_Z])

    z, r = np.zeros(2), np.empty(len(tf))
    for k in range(len(tf)):
        r[k] = z[1]
        vk, dk = v[k], delta[k]                 # the command held over the step
        k1 = f(z, vk, dk)
        k2 = f(z + 0.5 * H * k1, vk, dk)
        k3 = f(z + 0.5 * H * k2, vk, dk)
        k4 = f(z + H * k3, vk, dk)
        z = z + H / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return tf, v, r, t_cmd, cmd, rng


def _write(folder: Path, name: str, t: np.ndarray, columns: dict) -> None:
    s = np.floor(t).astype(np.int64)
    ns = np.round((t - s) * 1e9).astype(np.int64)
    pd.DataFrame({"": 0, "s": s, "ns": ns, **columns}).to_csv(folder / f"{name}.csv", index=False)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """The three topic tables, and the truth on its fine clock."""
    folder = tmp_path_factory.mktemp("three_clocks")
    tf, v, r, t_cmd, cmd, rng = _truth()
    _write(folder, "commandData", t_cmd, {"V": 2.0, "delta": cmd})
    t_imu = _stamps(rng, 27.0, 0.021)
    wz = np.degrees(np.interp(t_imu, tf, r)) + rng.normal(0.0, 0.3, len(t_imu))
    _write(folder, "imuData", t_imu, {"wz": wz})
    t_odo = _stamps(rng, 40.0, 0.004)
    _write(folder, "pfOdomData", t_odo, {"vx": np.interp(t_odo, tf, v) + rng.normal(0.0, 0.01, len(t_odo))})
    return folder, (tf, v, r, t_cmd, cmd)


def _lag(t: np.ndarray, x: np.ndarray, y: np.ndarray, max_lag: float = 0.3, step: float = 1e-3) -> float:
    """The lag (s) by which y follows x best: both linearly interpolated onto a ``step`` clock,
    the correlation coefficient at every whole step, refined by a parabola through the peak."""
    g = np.arange(t[0], t[-1], step)
    xs, ys = np.interp(g, t, x), np.interp(g, t, y)
    n = int(round(max_lag / step))
    rho = np.array([np.corrcoef(xs[: len(g) - k], ys[k:])[0, 1] for k in range(n + 1)])
    k = int(np.argmax(rho))
    assert 0 < k < n, "the peak is at the edge of the lags searched"
    a, b, c = rho[k - 1], rho[k], rho[k + 1]
    return (k + 0.5 * (a - c) / (a - 2 * b + c)) * step


def _imported(folder: Path):
    from agrobot.measurements.recording import ImportOptions, import_recording
    from agrobot.measurements.signal_expressions import parse_signal

    return import_recording(folder, ImportOptions(signals=[parse_signal(s) for s in SIGNALS]))


def test_the_importer_keeps_command_and_yaw_rate_aligned_across_clocks(recording):
    folder, (tf, v, r, t_cmd, cmd) = recording
    log, report = _imported(folder)
    t = log["t"].to_numpy()
    T = report["used"]["utc_start_s"] + t
    # every sample is the truth at its own time: the command in force, the measurements interpolated
    assert np.mean(log["delta_cmd"].to_numpy() == _held(T, t_cmd, cmd)) > 0.97
    assert np.sqrt(np.mean((log["yaw_rate"].to_numpy() - np.interp(T, tf, r)) ** 2)) < 0.02     # rad/s (noise 0.005)
    # the lag from the kinematic yaw rate v tan(delta_cmd)/L to the gyro: the converted table's equals
    # the truth's (delay + the car's own lag), read on the 1 ms clock with the command held exactly
    kin = lambda vv, d: vv * np.tan(d) / (L_F + L_R)                                            # noqa: E731
    expected = _lag(tf, kin(v, _held(tf, t_cmd, cmd)), r)
    found = _lag(t, kin(log["v"].to_numpy(), log["delta_cmd"].to_numpy()), log["yaw_rate"].to_numpy())
    step = float(np.median(np.diff(t)))
    assert DELAY < expected < DELAY + 0.05
    assert abs(found - expected) < 0.006, (found, expected, step)                            # half a step: 12 ms


@pytest.mark.slow
def test_the_identification_finds_the_delay_through_the_importer(recording):
    from agrobot.identification.ordinary_driving import identify_driving
    from agrobot.orchestrator.study import Study

    folder, _ = recording
    log, _ = _imported(folder)
    rep = identify_driving(log, "three clocks", Study.load(ROOT / "studies" / "f1tenth.toml"))
    delay, lag = rep["delay"]["value"], rep["parameters"]["lag"]["value"]
    # a 40 ms clock cannot part 10 ms of lag from delay: each within 12 ms (half a step: 20 ms), their sum too
    assert abs(delay - DELAY) < 0.012 and lag < 0.012 and abs(delay + lag - DELAY) < 0.012, rep["parameters"]


def _circling(yaw_peak: float, with_pose: bool = True, to_degrees: bool = False) -> pd.DataFrame:
    """A car weaving at 2-3 m/s (50 Hz, 60 s), its yaw rate peaking at ``yaw_peak`` rad/s, the
    track x, y integrated from it; the gyro column written in deg/s when ``to_degrees``."""
    t = np.arange(0.0, 60.0, 0.02)
    v = 2.5 + 0.5 * np.sin(2 * np.pi * t / 17.0)
    r = yaw_peak * np.sin(2 * np.pi * t / 6.0) ** 7         # short sharp turns: the 2 s heading change within pi
    psi = np.concatenate([[0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * 0.02)])
    x = np.concatenate([[0.0], np.cumsum(v[:-1] * np.cos(psi[:-1]) * 0.02)])
    y = np.concatenate([[0.0], np.cumsum(v[:-1] * np.sin(psi[:-1]) * 0.02)])
    frame = pd.DataFrame({"t": t, "v": v, "yaw_rate": np.degrees(r) if to_degrees else r})
    return frame.assign(x=x, y=y) if with_pose else frame


@pytest.mark.parametrize("with_pose", [True, False])
def test_a_fast_yaw_rate_is_read_as_rad_per_s_when_the_motion_says_so_and_degrees_are_still_named(with_pose):
    from agrobot.measurements.log import LogError, check_log

    # 3.2 rad/s at 2-3 m/s: a 0.64 m radius, 9.5 m/s2, as a 1:10 car drives (the FrictionMaps DS4 peak is 3.1 rad/s)
    fast = check_log(_circling(3.2, with_pose), "fast car", ("t",))
    note = " ".join(fast.attrs["notes"])
    assert "read as rad/s" in note and ("track" if with_pose else "radius") in note
    # a tractor's 0.2 rad/s written in deg/s (11.5 "rad/s"): a 0.2 m radius, 29 m/s2 (or 57 times the track's turn)
    with pytest.raises(LogError, match="looks like degrees/s"):
        check_log(_circling(0.2, with_pose, to_degrees=True), "slow tractor", ("t",))


def test_a_fast_yaw_rate_in_a_log_with_gaps_is_judged_on_its_longest_stretch(tmp_path):
    from agrobot.identification.from_log import _read
    from agrobot.measurements.log import LogError

    frame = _circling(3.2)
    holed = frame.drop(index=range(1000, 1100)).reset_index(drop=True)      # a 2 s hole at t = 20 s
    holed.to_parquet(tmp_path / "fast.parquet")
    log, _ = _read(tmp_path / "fast.parquet", False, None, None)
    assert "read as rad/s" in " ".join(log.attrs["notes"])
    _circling(0.2, to_degrees=True).drop(index=range(1000, 1100)).to_parquet(tmp_path / "deg.parquet")
    with pytest.raises(LogError, match="looks like degrees/s"):
        _read(tmp_path / "deg.parquet", False, None, None)
