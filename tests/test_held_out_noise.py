"""A held-out gain net of the measurement's own noise: a yaw rate differenced from a heading carries
0.05 rad/s of noise where a steering map's signal is a few thousandths, so a gain judged on the
gross RMS is a few thousandths whatever the map explains; judged net of the noise's realised power
(diagnosis.noise_floor.HeldOutNoise), on the part of the error a model can explain. Checked on a
heading generated with a known yaw rate and noise (the model errors planted), and on the small
Ackermann class's logs (harness.diagnosis_classes: a nonlinear steering map and a left/right
asymmetry planted, and a clean log)."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.ndimage import convolve1d

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.selection import Selector
from agrobot.identification.yaw_measurement import with_yaw_rate
from agrobot.orchestrator.study import Study
from harness.diagnosis_classes import baseline_study, class_log, within
from harness.steering_maps import MAP_IDS

DEG = math.pi / 180
H = 0.05                     # s: the rows
MAPS = tuple(MAP_IDS.values())


def heading_log(seed: int, heading_hz: float, duration: float = 120.0):
    """(t, the yaw rate derived from a heading of 0.2 deg noise updated at ``heading_hz`` in 20 Hz rows
    and its YawMeasurement, the true yaw rate as the derivation sees it): the yaw rate six slow
    sines (0.02-0.3 Hz) of 0.03-0.08 rad/s."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration / H)) * H
    r = sum(rng.uniform(0.03, 0.08) * np.sin(2 * math.pi * rng.uniform(0.02, 0.3) * t + rng.uniform(0, 2 * math.pi))
            for _ in range(6))
    psi = np.concatenate(([0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * H))) + 0.2 * DEG * rng.standard_normal(len(t))
    held = np.round(np.floor(t * heading_hz + 1e-9) / heading_hz / H).astype(int)
    frame, measured = with_yaw_rate(pd.DataFrame({"t": t, "heading": np.angle(np.exp(1j * psi[held]))}), "heading.csv")
    kernel = measured.kernel(H)
    seen = r if kernel is None else convolve1d(r, kernel[::-1], mode="nearest")
    return t, frame["yaw_rate"].to_numpy(float), measured, seen


def gains(seed: int, heading_hz: float, before: float, after: float) -> tuple[float, float]:
    """(the net held-out gain, the gross one) of a model whose yaw rate is off by ``after`` of the
    truth's against one off by ``before``, on the last 40 % of a heading_log."""
    from agrobot.diagnosis.noise_floor import residual_noise
    from agrobot.diagnosis.reading_noise import held_out_gain

    t, measured, how, seen = heading_log(seed, heading_hz)
    test = (t >= 0.6 * t[-1]) & np.isfinite(measured)
    r_before, r_after = ((measured - (1 - k) * seen)[test] for k in (before, after))
    noise = residual_noise(r_before, ((1 - before) * seen)[test], t[test], H, how)
    rms_before, rms_after = (float(np.sqrt(np.mean(r * r))) for r in (r_before, r_after))
    return held_out_gain(rms_before, rms_after, 0.0, noise), 1.0 - rms_after / rms_before


@pytest.mark.parametrize("heading_hz", [20.0, 5.0])
def test_a_model_error_under_the_differencing_noise_is_judged_on_what_it_explains(heading_hz):
    """The baseline's yaw rate 3 % short of the truth's (0.003 rad/s RMS under 0.05 of noise at 20 Hz,
    0.018 at 5 Hz), the effect's 1.5 % short: it removes half the RMS a model can explain (truth
    0.5), which the net gain reads within 0.15 on every seed, where the gross gain stays under 2 %
    (and the 5 % min_gain)."""
    for seed in range(6):
        net, gross = gains(seed, heading_hz, 0.03, 0.015)
        assert abs(net - 0.5) < 0.15, (seed, net, gross)
        assert 0.0 < gross < 0.02, (seed, net, gross)


@pytest.mark.parametrize("heading_hz", [20.0, 5.0])
def test_a_right_baseline_gives_no_effect_a_gain(heading_hz):
    """The baseline's yaw rate the truth's: a model 2 % off it loses, net as gross, on every seed."""
    for seed in range(6):
        net, gross = gains(seed, heading_hz, 0.0, 0.02)
        assert net < 0.0 and gross < 0.0, (seed, net, gross)


def named(effect: str, seed: int, tmp_path) -> tuple[list, dict]:
    """(the selection's effects, the truth) of the small Ackermann class's 120 s log, the steering maps
    its only candidates, judged as diagnose judges it (its heading differenced into the yaw rate)."""
    frame, truth = class_log(effect, seed, "small_ackermann", 120.0)
    frame, _ = with_yaw_rate(frame, "small.parquet")
    baseline = baseline_from_study(Study.load(baseline_study("small_ackermann", tmp_path)))
    selector = Selector(Replay(frame, baseline), 0.05, screen=False)
    selector.catalogue = [e for e in selector.catalogue if e.id in MAPS]
    return selector.run().effects, truth


@pytest.mark.slow
@pytest.mark.parametrize("effect, seed, expected", [("steering_map_curve", 2000, "steering_ratio_curve"),
                                                    ("steering_map_asymmetry", 2001, "steering_asymmetry"),
                                                    ("none", 2000, None)])
def test_a_steering_map_under_the_heading_noise_is_named(effect, seed, expected, tmp_path):
    """A ratio curve (1.62 1/rad2) and an asymmetry (0.124) that the log's first 60 % pins (dBIC
    about -200) but whose signal on the held-out 40 %, steered half as far, is under the differenced
    heading's noise: named with their values within the class's tolerances, their net held-out gain
    over 5 % and several times the gross one (4 % and 0.3 % when each is tried alone against the
    baseline: missed on the gross RMS); the clean log names nothing."""
    effects, truth = named(effect, seed, tmp_path)
    assert [f.effect.id for f in effects] == ([expected] if expected else []), [f.effect.id for f in effects]
    for f in effects:
        assert within(f.effect.id, f.fit.values, truth), (f.fit.values, truth)
        gross = 1.0 - f.rmse_after["yaw_rate"] / f.rmse_before["yaw_rate"]
        assert f.gain >= max(0.05, 3 * gross), (f.gain_by_signal, gross)


@pytest.mark.slow
def test_diagnose_says_what_the_yaw_gains_are_net_of(tmp_path):
    """diagnose on the ratio-curve log: the curve named, and the report says that its yaw-rate gains are
    net of the derived yaw rate's noise, with that noise, the band it was read above and what was
    passed over (the gross RMS)."""
    from agrobot.diagnosis.pipeline import diagnosis

    frame, truth = class_log("steering_map_curve", 2000, "small_ackermann", 120.0)
    log = tmp_path / "small.parquet"
    frame.to_parquet(log)
    result, _ = diagnosis(log, baseline_study("small_ackermann", tmp_path), plots=False, identify=False, workers=1)
    assert [e["id"] for e in result["effects"]] == ["steering_ratio_curve"], result["effects"]
    assert within("steering_ratio_curve", result["effects"][0]["parameters"], truth)
    held = result["held_out_noise"]["yaw"]
    assert 0.9 * held["gross_rms"] < held["rms"] < held["gross_rms"] and 0.0 < held["band_hz"] < 2.0, held
    said = [w for w in result["warnings"] if "net of the derived yaw rate's noise" in w]
    assert said and "passed over: the gross RMS" in said[0] and f"above {held['band_hz']:.3g} Hz" in said[0], said
