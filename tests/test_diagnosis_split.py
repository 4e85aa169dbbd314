"""What the diagnosis holds out: the log's last part, unless that part is driven beyond the
conditions of the first (faster, nearer the grip limit), where it holds out every third window
instead and says so (diagnosis.candidates.split_conditions)."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay, split_conditions
from harness.hidden_effects import BASELINES
from harness.truth_tractor import make_log
from agrobot.orchestrator.study import Study

GENTLE_THEN_HARD = (1.0, 1.5, 1.0, 1.5, 1.0, 1.5, 1.0, 3.0, 3.0, 3.5, 3.0, 3.5)     # m/s, 20 s each


@pytest.fixture(scope="module")
def baseline():
    return baseline_from_study(Study.load(BASELINES["tractor"]))


@pytest.fixture(scope="module")
def alike_log():
    """The clean 240 s log driven alike throughout, made once (each test replays a copy)."""
    return make_log(1000, None, duration=240.0)[0]


@pytest.fixture(scope="module")
def hard_log():
    """The 240 s log of the same seed at 1-1.5 m/s, then 3-3.5 m/s for its last 100 s (GENTLE_THEN_HARD),
    made once."""
    return make_log(1000, None, duration=240.0, speeds=GENTLE_THEN_HARD)[0]


def test_a_log_driven_alike_throughout_holds_out_its_last_part(baseline, alike_log):
    frame = alike_log.copy()
    replay = Replay(frame, baseline)
    assert replay.split == "tail" and replay.split_note is None
    t = replay.t
    assert np.array_equal(replay.masks["steering"]["test"], t >= t[0] + 0.6 * (t[-1] - t[0]))


def test_a_log_driven_harder_at_its_end_holds_out_every_third_window(baseline, hard_log):
    frame = hard_log.copy()
    replay = Replay(frame, baseline)
    assert replay.split == "blocks"
    assert "driven beyond its first" in replay.split_note and "--split tail" in replay.split_note
    # independently: the 95th percentile of the speed after the 60 % mark against before
    t, v = frame["t"].to_numpy(), frame["v"].to_numpy()
    late = t >= t[0] + 0.6 * (t[-1] - t[0])
    assert np.percentile(v[late], 95) > 1.5 * np.percentile(v[~late & (v > 0.3)], 95)
    held = replay.masks["steering"]["test"]
    block = ((t - t[0]) // 10.0).astype(int)
    assert np.array_equal(held, block % 3 == 2)
    assert not (replay.masks["yaw"]["fit"] & held).any()
    # every position window lies wholly in one part, and both parts cover the log's ends
    for part, inside in (("fit", False), ("test", True)):
        rows = replay.windows[part]
        assert len(rows) and (held[rows] == inside).all()
    assert replay.held_out_spans()[0][0] == pytest.approx(t[0] + 20.0, abs=replay.h)
    assert np.array_equal(replay.unseen(t), held)


def test_the_split_can_be_forced_either_way(baseline, alike_log, hard_log):
    hard, alike = hard_log.copy(), alike_log.copy()
    assert Replay(hard, baseline, split="tail").split == "tail"
    assert Replay(alike, baseline, split="blocks").split == "blocks"
    with pytest.raises(ValueError, match="split 'last'"):
        Replay(alike, baseline, split="last")


def test_the_conditions_rule_needs_a_material_rise():
    """1.5 x and 0.5 m/s2 (or m/s) more: a slow log that doubles its crawl is not beyond its conditions."""
    t = np.arange(0.0, 100.0, 0.05)
    late = t >= 60.0
    v = np.where(late, 0.3, 0.15) + 0.2
    r = np.full_like(t, 0.1)
    assert split_conditions(t, v, r, v > 0.1, 60.0) is None
    v = np.where(late, 3.0, 1.0)           # |a_y| 0.3 against 0.1 m/s2 is too little; the speed is not
    why = split_conditions(t, v, r, v > 0.1, 60.0)
    assert why is not None and "speed 3 m/s against 1 m/s" in why
    v = np.full_like(t, 2.0)
    r = np.where(late, 1.0, 0.2)
    why = split_conditions(t, v, r, v > 0.1, 60.0)
    assert why is not None and "lateral acceleration |v yaw_rate| 2 m/s2 against 0.4 m/s2" in why


@pytest.mark.slow
@pytest.mark.parametrize("effect", ["tyre_saturation", None])
def test_a_truth_driven_harder_at_its_end_is_diagnosed_on_blocks(tmp_path, effect):
    """A saturating tyre (the truth's F = C a / (1 + |a| / a_s)) on a log whose last 40 % is driven
    at twice the speed: held out every third window, the saturation is named with the truth's
    friction (harness.hidden_effects.recovered); the same driving without a fault is 'none'."""
    from harness.hidden_effects import expected_ids, recovered
    from agrobot.diagnosis.pipeline import diagnose

    frame, truth = make_log(1000, effect, duration=240.0, speeds=GENTLE_THEN_HARD)
    log = tmp_path / "hard_end.parquet"
    frame.to_parquet(log)
    result = diagnose(log, None, BASELINES["tractor"], identify=False)
    assert result["split"]["kind"] == "blocks" and "driven beyond its first" in result["split"]["why"]
    assert any("driven beyond its first" in w for w in result["warnings"])
    found = {e["id"] for e in result["effects"]}
    assert found == (expected_ids(truth) or set()), (found, result["selection_trace"][:3])
    if effect:
        e = next(e for e in result["effects"] if e["id"] == effect)
        est, true, tol = recovered(effect, truth, e["parameters"])
        assert abs(est - true) <= tol, (est, true, tol)
    else:
        assert result["verdict"] == "none"
