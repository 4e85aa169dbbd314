"""A lever arm the diagnosis fits from a recording is judged against the declared outline: an antenna
planted inside the paper tractor (2.6 m x 1.2 m, rear axle to front axle 1.4 m) is concluded where it
is and passes; one planted ahead of its front or beyond its side is fitted where it is and named as
outside the outline (no antenna is mounted there).

Truth: harness.truth_tractor's paper tractor driven 60 s with the antenna planted at the point given
(from the rear axle); fitted by the diagnosis's own refit of the position stage (candidates._fit, the
lever arm freed as the selection frees it) on the shipped figure8.toml study. Inside or outside is
decided here from the outline alone: 3.4 m ahead is past the front whatever the overhangs' split
(2.6 m of length from any point behind the rear axle), 0.8 m aside is past the 0.6 m half-width."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay, _fit, fit_baseline, refit_free
from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.diagnosis.verdict import conclude, judge_values
from agrobot.orchestrator.study import load_study
from agrobot.studies import shipped
from harness.truth_tractor import make_log

LEVER = next(e for e in CATALOGUE if e.id == "antenna_lever_arm")


def fitted_lever_arm(forward: float, left: float):
    """(the fitted lever arm's parameters, their std, the baseline, the log's median speed)."""
    frame, truth = make_log(4, "antenna_lever_arm", duration=60.0, values={"forward": forward, "left": left})
    assert (truth["forward"], truth["left"]) == (forward, left)
    base = baseline_from_study(load_study(shipped("figure8.toml")))
    replay = Replay(frame, base)
    start, sigma = fit_baseline(replay)
    fit = _fit(replay, dict(start.values), refit_free(replay, ("position",), [LEVER]), ("position",), [{}], sigma)
    values = {k: fit.values[k] for k in ("antenna_forward", "antenna_left")}
    return values, {k: fit.std(k) for k in values}, base, float(np.median(frame["v"]))


@pytest.mark.parametrize("forward, left, inside", [(1.0, 0.3, True), (3.4, 0.3, False), (1.0, 0.8, False)])
def test_a_planted_antenna_is_judged_inside_or_outside_the_outline(forward, left, inside):
    values, sd, base, speed = fitted_lever_arm(forward, left)
    assert abs(values["antenna_forward"] - forward) < max(3 * sd["antenna_forward"], 0.05), values
    assert abs(values["antenna_left"] - left) < max(3 * sd["antenna_left"], 0.05), values
    p = base.tractor
    effect = {"id": LEVER.id, "parameters": values, "hypothesis": "h", "not_identifiable": None,
              "parameters_display": {f"{k} [m]": v for k, v in values.items()}}
    notes = judge_values(effect, base.vehicle, p.l_f + p.l_r, p.l_r, speed)
    if inside:
        assert notes == []
        return
    assert len(notes) == 1 and "outside its outline" in notes[0] and f"{values['antenna_forward']:.2f} m ahead" in notes[0]
    verdict = conclude([effect], None, [], [], [], base.vehicle, p.l_f + p.l_r, p.l_r, speed)
    assert verdict["status"] == "implausible", verdict
