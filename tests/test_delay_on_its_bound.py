"""A delay that ends on its zero bound is not concluded: it is searched below zero and judged
there. Truths: the small Ackermann machine (harness.small_ackermann), whose measured wheel angle
drives the yaw with no delay, once as logged and once with its steering channels stamped 0.3 s
late (a clock offset: the yaw then answers 0.3 s before its input); and the tractor of
harness.truth_tractor with its steering stamped 0.2 s late (its 'steering_clock' effect)."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.identification.ordinary_driving import identify_driving
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from harness.small_ackermann import make_small_log, write_study
from harness.truth_tractor import make_log


def stamped_late(frame, late: float):
    t = frame["t"].to_numpy(float)
    out = frame.copy()
    for c in ("delta", "delta_cmd"):
        out[c] = np.interp(t - late, t, frame[c].to_numpy(float))
    return out


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    return Study.load(write_study(tmp_path_factory.mktemp("delay"))), make_small_log(1, duration=120.0)[0]


def test_no_delay_is_not_a_value_on_its_bound(small):
    study, frame = small
    d = identify_driving(frame.drop(columns=["x", "y", "delta_cmd"]), "small.csv", study)["delay"]
    assert np.isfinite(d["std"]) and d["interval"][0] < 0.0 < d["interval"][1], d
    assert d["verdict"] == "below its upper limit" and not d["identifiable"] and "at most" in d["note"]


def test_a_steering_stamped_late_is_a_clock_offset(small):
    study, frame = small
    d = identify_driving(stamped_late(frame, 0.3).drop(columns=["x", "y", "delta_cmd"]), "late.csv", study)["delay"]
    assert d["verdict"] == "clock offset" and "clock offset" in d["note"], d
    assert d["interval"][0] <= -0.3 <= d["interval"][1], d


@pytest.mark.slow
def test_the_dynamic_fit_finds_the_clock_offset_too():
    frame, _ = make_log(4, "steering_clock", duration=60.0, values={"steering_clock": 0.2})
    rep = identify_driving(frame.drop(columns="delta_cmd"), "tractor.csv", Study.load(shipped("figure8.toml")),
                           max_fit_seconds=30.0)
    d = rep["delay"]
    assert rep["final_model"] != "kinematic" and d["verdict"] == "clock offset", d
    assert d["interval"][0] <= -0.2 <= d["interval"][1], d
