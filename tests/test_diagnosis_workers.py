"""The diagnosis's candidate fits on worker processes (diagnosis.parallel_fits): the same
diagnosis.json on one worker and on two, with the fits really computed by the workers, and the
planted effect found either way; a bad worker count is refused."""
from __future__ import annotations

import json

import pytest

import agrobot
from agrobot.diagnosis import parallel_fits
from agrobot.orchestrator.study import StudyError
from harness.truth_tractor import make_log


def test_one_worker_and_two_give_the_same_diagnosis(tmp_path, monkeypatch):
    frame, truth = make_log(1000, "actuator_delay", duration=120.0)
    log = tmp_path / "log.csv"
    frame.to_csv(log, index=False)
    computed = []
    ahead = parallel_fits.FitPool.ahead

    def counted(self, batch, first_only):
        before = set(self.replay.__dict__.get("fits_ahead") or {})
        ahead(self, batch, first_only)
        computed.append(len(set(self.replay.__dict__.get("fits_ahead") or {}) - before))
    monkeypatch.setattr(parallel_fits.FitPool, "ahead", counted)
    out = {}
    for workers in (1, 2):
        computed.clear()
        agrobot.diagnose(log, out=tmp_path / f"w{workers}", identify=False, plots=False, workers=workers)
        out[workers] = json.loads((tmp_path / f"w{workers}" / "diagnosis.json").read_text())
        assert (sum(computed) > 4) == (workers == 2)         # the workers fitted candidates
    assert out[1]["verdict"] == truth["effect"] == "actuator_delay"
    assert out[1] == out[2]


@pytest.mark.parametrize("workers", [0, -2, 1.5])
def test_a_worker_count_below_one_is_refused(tmp_path, workers):
    with pytest.raises(StudyError, match="--workers"):
        agrobot.diagnose(tmp_path / "missing.csv", workers=workers)
