"""A skid-steered robot's yaw against its wheel odometry, two ways: the project and numpy.

    python3 benchmarks/skid_steer.py [--bag /work/corpus_data/clearpath_husky_rl_test1/test1.bag]

The recording: a Clearpath Husky (skid-steer, 4 wheels) from robot_localization's tests
(github cra-ros-pkg/robot_localization @ 1cb9533, test/test1.bag, BSD-3-Clause: LICENSE.robot_localization
beside it; benchmarks only). Its IMU is mounted with y up (gravity on linear_acceleration.y), so the
yaw rate is angular_velocity.y; the input is the husky_velocity_controller's odometry yaw rate
(twist.twist.angular.z, (v_R - v_L) / B_odom); no turn-rate command is recorded.

Per run of the recording (stops of 3 s or more at |v| < 0.2 m/s split them):

* the project: agrobot.api.identify on the bag (ImportOptions: the three channels above, 10 Hz rows,
  that run): K, tau, T, b with 95 % intervals, held-out RMSE, plausibility (identification.skid_steer);
* numpy on the raw bag (rosbags, no agrobot): the gyro averaged onto the odometry's 10 Hz stamps;
  (a) least squares of r on [w(t - tau), 1] over a grid of tau (-1..1 s, 0.02 s): K, b, tau;
  (b) the same over a grid of tau and T (0..1 s, 0.05 s), w passed through a first-order lag
  y_n = a y_n-1 + (1 - a) w_n, a = exp(-h / T) (a discretisation other than the project's).

K is against the odometry's own track: Husky's husky_control/config/control.yaml (husky/husky) sets
wheel_separation_multiplier 1.875, so K / 1.875 is K against the geometric track -- if the 2015
robot ran that configuration, which its publisher does not say.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from scipy.signal import lfilter

ROOT = Path(__file__).resolve().parent.parent
BAG = Path("/work/corpus_data/clearpath_husky_rl_test1/test1.bag")
GYRO = ("/imu/data", "angular_velocity.y")
ODOM = "/husky_velocity_controller/odom"
MULTIPLIER = 1.875        # husky_control/config/control.yaml: wheel_separation_multiplier


def read_bag(path: Path) -> dict:
    """{topic: (header times [s], values)} of the gyro's vertical axis, the odometry's yaw rate and speed."""
    from rosbags.highlevel import AnyReader

    out = {"r": ([], []), "w": ([], []), "v": ([], [])}
    with AnyReader([path]) as reader:
        for conn, _, raw in reader.messages(connections=[c for c in reader.connections if c.topic in (GYRO[0], ODOM)]):
            msg = reader.deserialize(raw, conn.msgtype)
            t = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
            if conn.topic == GYRO[0]:
                out["r"][0].append(t), out["r"][1].append(msg.angular_velocity.y)
            else:
                out["w"][0].append(t), out["w"][1].append(msg.twist.twist.angular.z)
                out["v"][0].append(t), out["v"][1].append(msg.twist.twist.linear.x)
    return {k: (np.array(a), np.array(b)) for k, (a, b) in out.items()}


def runs(t: np.ndarray, v: np.ndarray, min_stop: float = 3.0, min_run: float = 10.0) -> list[tuple[float, float]]:
    """Spans between stops (|v| < 0.2 m/s for min_stop s or more), at least min_run s long."""
    still = np.abs(v) < 0.2
    cuts, start = [], None
    for i, s in enumerate(still):
        if s and start is None:
            start = i
        if not s and start is not None:
            if t[i - 1] - t[start] >= min_stop:
                cuts.append((t[start], t[i - 1]))
            start = None
    edges = [t[0]] + [x for c in cuts for x in c] + [t[-1]]
    return [(a, b) for a, b in zip(edges[::2], edges[1::2]) if b - a >= min_run]


def on_grid(ch: dict, span: tuple[float, float]):
    """(h, w, r): the odometry's yaw rate on its own 10 Hz stamps inside ``span``, the gyro averaged
    over each stamp's interval."""
    tw, w = ch["w"]
    keep = (tw >= span[0]) & (tw <= span[1])
    tw, w = tw[keep], w[keep]
    tr, r = ch["r"]
    edges = np.r_[tw[0] - 0.05, 0.5 * (tw[1:] + tw[:-1]), tw[-1] + 0.05]
    which = np.searchsorted(edges, tr) - 1
    ok = (which >= 0) & (which < len(tw))
    sums = np.bincount(which[ok], r[ok], len(tw))
    counts = np.bincount(which[ok], minlength=len(tw))
    good = counts > 0
    return float(np.median(np.diff(tw))), tw[good], w[good], sums[good] / counts[good]


def grid_fit(t, w, r, lags, lags_T) -> dict:
    """Least squares of r on [lag_T(w(t - tau)), 1] for every (tau, T): the best's K, b, tau, T, RMSE."""
    best = {"rss": math.inf}
    h = float(np.median(np.diff(t)))
    for tau in lags:
        wd = np.interp(t - tau, t, w)
        for T in lags_T:
            a = math.exp(-h / T) if T > 0 else 0.0
            y = lfilter([1.0 - a], [1.0, -a], wd, zi=[a * wd[0]])[0]      # from the steady state of w[0]
            A = np.c_[y, np.ones_like(y)]
            coef, *_ = np.linalg.lstsq(A, r, rcond=None)
            rss = float(np.sum((r - A @ coef) ** 2))
            if rss < best["rss"]:
                best = {"rss": rss, "K": float(coef[0]), "b": float(coef[1]), "tau": float(tau), "T": float(T),
                        "rmse": math.sqrt(rss / len(r))}
    return best


def project(bag: Path, run: int) -> dict:
    """identify's skid-steer report on run ``run`` of the bag."""
    sys.path.insert(0, str(ROOT / "src"))
    from agrobot.api import identify
    from agrobot.measurements.options import ImportOptions
    from agrobot.measurements.signal_expressions import parse_signal

    signals = [parse_signal(s) for s in (f"yaw_rate={GYRO[0]}.{GYRO[1]}", f"odom_yaw_rate={ODOM}.twist.twist.angular.z",
                                         f"v={ODOM}.twist.twist.linear.x")]
    found = identify(bag, method="driving", recording=ImportOptions(signals=signals, rate=10.0, run=run), plots=False)
    return found.report


def _q(d: dict, f: str = "{:.3g}") -> str:
    if not d["identifiable"]:
        return f.format(d["value"] if abs(d["value"]) > 1e-9 else 0.0) + " (not concluded)"
    return f.format(d["value"]) + " [" + ", ".join(f.format(x) for x in d["interval"]) + "]"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bag", type=Path, default=BAG)
    args = ap.parse_args()
    if not args.bag.is_file():
        ap.error(f"--bag {args.bag}: no such file (a ROS 1 bag with an IMU and a wheel odometry topic; the default is "
                 f"{BAG}, fetched as benchmarks/real_corpus.toml says)")
    ch = read_bag(args.bag)
    t0 = min(ch["r"][0][0], ch["w"][0][0])
    spans = runs(*ch["v"])
    print(f"{args.bag}: {len(spans)} run(s): " + ", ".join(f"{a - t0:.1f}-{b - t0:.1f} s" for a, b in spans))
    print(f"{'run':>3} {'method':<34} {'K':>22} {'tau [s]':>24} {'T [s]':>22} {'b [rad/s]':>26} {'RMSE':>8}")
    for k, span in enumerate(spans, start=1):
        h, t, w, r = on_grid(ch, span)
        tau_only = grid_fit(t, w, r, np.arange(-1.0, 1.0001, 0.02), [0.0])
        both = grid_fit(t, w, r, np.arange(-1.0, 1.0001, 0.02), np.arange(0.0, 1.0001, 0.05))
        rep = project(args.bag, k)
        p = rep["parameters"]
        print(f"{k:>3} {'agrobot identify (held-out RMSE)':<34} {_q(p['yaw_gain'], '{:.3f}'):>22} {_q(p['delay']):>24} "
              f"{_q(p['lag']):>22} {_q(p['gyro_bias'], '{:.2g}'):>26} {rep['held_out_fit']['rmse']:8.4f}")
        for name, g in (("numpy r ~ w(t - tau), tau grid", tau_only), ("numpy r ~ lag_T w(t - tau), grid", both)):
            print(f"{k:>3} {name:<34} {g['K']:>22.3f} {g['tau']:>24.3g} {g['T']:>22.3g} {g['b']:>26.2g} {g['rmse']:8.4f}")
        pl = rep["plausibility"]
        print(f"    plausible: {'yes' if pl['plausible'] else 'no: ' + '; '.join(pl['findings'])}")
        print(f"    K against the geometric track, if the odometry used wheel_separation_multiplier {MULTIPLIER}: "
              f"{p['yaw_gain']['value'] / MULTIPLIER:.3f}; turn-rate dependence kept: "
              f"{rep['turn_rate_dependence']['kept']} (dBIC {rep['turn_rate_dependence']['delta_bic']:.1f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
