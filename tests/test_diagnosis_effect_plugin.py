"""An effect is one class: defined here, registered, planted in a generated log, found.

The effect below exists in no file of the package: a gain on the gyro's reading, carried into the
replay by its own declaration (``enters``: the gyro's gain), its parameter named as nowhere else. The
catalogue's own gyro_scale (the same physics) is taken out for the run, so the two are not twins.
The log is harness.truth_tractor's gyro scale factor (the gyro reads s x the yaw rate, s drawn
there): found with s only if the replay reads the new class.
"""
from __future__ import annotations

import pytest

from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.diagnosis.effect import Effect, Parameter
from agrobot.diagnosis.pipeline import diagnose
from harness.truth_tractor import make_log

SEED = 7002


class YawRateGain(Effect):
    id = "yaw_rate_gain"
    subsystem = "gyro (a gain defined by a test)"
    stages = ("yaw", "position")
    parameters = (Parameter("yaw_rate_reading_gain", "1", 0.1, 0.75, 1.3, "-", 1.0, (0.3, 3.0)),)
    starts = ((1.0,), (0.9,), (1.1,))
    enters = {"gyro.gain": "yaw_rate_reading_gain"}
    threshold = "|g - 1| >= 0.04"
    hypothesis = "the gyro reads g x the yaw rate"
    experiment = "a full circle: the integrated gyro turns g x 360 deg"

    def baseline(self, study):
        return {"yaw_rate_reading_gain": 1.0}

    def material(self, fitted, base):
        return abs(fitted["yaw_rate_reading_gain"] - 1.0) >= 0.04

    def options(self, fitted, base, study):
        raise KeyError("gyro gain (divide the log's yaw_rate by it)")


@pytest.mark.slow
def test_an_effect_defined_outside_the_package_is_found_with_its_value(tmp_path):
    frame, truth = make_log(SEED, "gyro_scale_factor")
    frame.to_parquet(tmp_path / "log.parquet")
    with CATALOGUE.registered(YawRateGain(), replacing=("gyro_scale",)):
        res = diagnose(tmp_path / "log.parquet", None, plots=False, identify=False, workers=1)
    assert [e["id"] for e in res["effects"]] == ["yaw_rate_gain"], res["selection_trace"]
    assert abs(res["effects"][0]["parameters"]["yaw_rate_reading_gain"] - truth["gyro_scale"]) <= 0.02
    assert "gyro_scale" in {e.id for e in CATALOGUE} and "yaw_rate_gain" not in {e.id for e in CATALOGUE}


def test_the_catalogue_refuses_an_effect_it_cannot_replay():
    class Nowhere(YawRateGain):
        id = "nowhere"
        enters = {"gyro.drift": "yaw_rate_reading_gain"}

    class Twice(YawRateGain):
        id = "twice"
        enters = {"yaw.friction": "another_friction"}

    with pytest.raises(ValueError, match="gyro.drift"):
        CATALOGUE.register(Nowhere())
    with pytest.raises(ValueError, match="yaw.friction"):
        CATALOGUE.register(Twice())
    with pytest.raises(ValueError, match="registered already"):
        CATALOGUE.register(next(iter(CATALOGUE)))
    assert {e.id for e in CATALOGUE}.isdisjoint({"nowhere", "twice"})
