"""The receiver's outage modes: each one's error against its model, by Monte Carlo over independent
receivers (seeds), at 1, 5 and 20 minutes into the outage.

- bridging (satellite-delivered corrections, xFill / RTK ASSIST): RTK quality reported for its
  timeout, the correction age counting, and the horizontal RMS error
  sqrt(2 sigma_w^2 + (s0 + r a)^2) (white noise sigma_w per axis plus the bridged error growing
  with the age a), with s0, r the least-squares line through the vendor's table, recomputed here;
- RTK float and DGPS: sqrt(2 sigma_w^2 + 2 sigma_q^2) at every age (a stationary wander);
- no fix: no position at all (what the estimator does then: tests/test_ground.py).
A mode that does not exist exits 2 naming it."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.gps_sensor import GPSSensor, bridging_error
from agrobot.components.models.sensor_grades import FIX_ERROR_STD
from agrobot.orchestrator.cli import main

AGES = (60.0, 300.0, 1200.0)          # s into the outage
DT, DRAWS, WHITE = 5.0, 120, 0.02      # s a step (the Gauss-Markov is exact at any step), receivers, m


def receiver_errors(mode, parameters=None) -> dict[float, np.ndarray]:
    """age -> (draws, 5): east and north error, quality, correction age, fix valid."""
    out = {a: [] for a in AGES}
    for seed in range(DRAWS):
        g = GPSSensor("gps", {"position_noise_std": WHITE, "outages": [[0.0, 1500.0, mode]], **(parameters or {})},
                      rng=np.random.default_rng(seed))
        g.initialize(0.0, DT)
        for k in range(int(max(AGES) / DT) + 1):
            g.step(k * DT, DT)
            if k * DT in out:
                y = g.y
                out[k * DT].append((y["x"], y["y"], y["fix_quality"], y["correction_age"], y["fix_valid"]))
    return {a: np.array(v) for a, v in out.items()}


def horizontal_rms(rows: np.ndarray) -> float:
    return float(np.sqrt(np.mean(rows[:, 0] ** 2 + rows[:, 1] ** 2)))


def test_the_default_bridging_line_is_the_vendors_table_fitted():
    """Trimble TMX-2050: 1-5 cm after 1-5 min, 5-9 cm after 6-10 min, 10-15 cm after 11-20 min:
    the midpoints' least-squares line."""
    minutes = np.array([3.0, 8.0, 15.5])
    cm = np.array([3.0, 7.0, 12.5])
    rate, start = np.polyfit(minutes, cm, 1)
    assert bridging_error(0.0) == pytest.approx(start / 100, abs=5e-4)
    assert bridging_error(600.0) - bridging_error(0.0) == pytest.approx(10 * rate / 100, rel=0.02)


def test_bridging_reports_rtk_with_the_correction_age_and_drifts_as_its_model():
    e = receiver_errors("bridging")
    for age in AGES:
        rows = e[age]
        assert (rows[:, 2] == 4).all() and (rows[:, 4] == 1).all()
        assert rows[:, 3] == pytest.approx(age)
        model = math.sqrt(2 * WHITE ** 2 + float(bridging_error(age)) ** 2)
        assert horizontal_rms(rows) == pytest.approx(model, rel=0.15), age
    assert horizontal_rms(e[1200.0]) > 2.5 * horizontal_rms(e[60.0])       # it grows with the age


def test_after_its_timeout_bridging_falls_to_dgps():
    e = receiver_errors("bridging", {"bridging_timeout": 200.0})
    assert (e[60.0][:, 2] == 4).all() and (e[300.0][:, 2] == 2).all()
    assert horizontal_rms(e[1200.0]) == pytest.approx(math.sqrt(2 * WHITE ** 2 + 2 * FIX_ERROR_STD[2] ** 2), rel=0.15)


@pytest.mark.parametrize("mode,quality", [("float", 5), ("dgps", 2)])
def test_float_and_dgps_keep_their_error_at_every_age(mode, quality):
    e = receiver_errors(mode)
    model = math.sqrt(2 * WHITE ** 2 + 2 * FIX_ERROR_STD[quality] ** 2)
    for age in AGES:
        assert (e[age][:, 2] == quality).all() and (e[age][:, 3] == 0).all()
        assert horizontal_rms(e[age]) == pytest.approx(model, rel=0.15), age


def test_without_any_fix_the_receiver_gives_no_position():
    e = receiver_errors("none")
    for age in AGES:
        assert (e[age][:, 4] == 0).all() and (e[age][:, 2] == 0).all()


@pytest.mark.parametrize("value,named", [('[[60, 120, "xfil"]]', "outage mode 'xfil' does not exist"),
                                         ("[[60, 120, 12]]", "quality 12")])
def test_an_unknown_outage_mode_exits_2_naming_it(tmp_path, capsys, value, named):
    out = tmp_path / "out"
    code = main(["run", "studies/figure8.toml", "--out", str(out), "--set", f"gps.outages={value}"])
    err = capsys.readouterr().err
    assert code == 2 and named in err and "Traceback" not in err, err[-400:]
    assert not out.exists()
