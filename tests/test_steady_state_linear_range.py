"""The steady-state understeer gradient is taken only where the tyres are linear, a limit read from
the steady turns themselves; where identify's dynamic K and its steady-state K disagree, no single K
is concluded and the report gives both numbers and why.

Independent truth: steady turns of a single-track car whose axles carry Magic Formula tyres, F =
mu F_z sin(C atan(B alpha)) with B = c F_z / (C mu F_z): at a lateral acceleration a_y each axle
carries F = m a_y (other axle's arm) / L, the slip angle is the formula inverted, and the wheel
angle is delta = L r / v + alpha_f - alpha_r; in the linear range K = (1/c_f - 1/c_r) / g."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.identification.steady_state import in_linear_range, regression

G = 9.81
L, L_F, L_R = 0.32, 0.112, 0.208
C_F, C_R = 5.0, 10.0                 # cornering stiffness per unit axle load [1/rad]
K_TRUE = (1 / C_F - 1 / C_R) / G


def slip(share: np.ndarray, c: float, mu: float, shape: float) -> np.ndarray:
    """The slip angle at which the Magic Formula tyre carries ``share`` of its load laterally."""
    B = c / (shape * mu)
    return np.tan(np.arcsin(np.clip(share / mu, -1, 1)) / shape) / B


def steady_turns(mu: float = 0.7, shape: float = 1.6, n: int = 160, seed: int = 0) -> dict[str, np.ndarray]:
    """Steady windows (means of u, v, r) of the car turning at 1-4 m/s up to 0.6 g (0.85 of the peak
    force of tyres of friction 0.7), the wheel angle measured, the gyro's window means with 0.004
    rad/s of noise."""
    rng = np.random.default_rng(seed)
    v = rng.uniform(1.0, 4.0, n)
    a_y = rng.choice([-1, 1], n) * rng.uniform(0.02, 0.85, n) ** 1.5 * 0.7 * G
    r = a_y / v
    delta = L * r / v + slip(a_y / G, C_F, mu, shape) - slip(a_y / G, C_R, mu, shape)
    r_m = r + 0.004 * rng.standard_normal(n)
    return {"u": delta, "v": v, "r": r_m, "a_y": v * r_m}


def test_steady_state_k_in_the_linear_range_holds_the_truth():
    """Every window (what identify took when it found no saturation) reads the tyres' bend as
    understeer; the windows inside the limit read from the turns come within 6 % of the truth (the
    Magic Formula bends from its first degree: the limit is where the bend shows above the noise)."""
    w = steady_turns()
    cap = float(np.percentile(np.abs(w["a_y"]), 99))
    whole = regression(w, L, max_lateral=cap, fixed_gain=1.0)
    assert whole.K > 1.1 * K_TRUE and not whole.K - 1.96 * whole.K_std <= K_TRUE
    fit = in_linear_range(w, L, 0.15 * G, cap, fixed_gain=1.0)
    assert abs(fit.K - K_TRUE) < 0.06 * K_TRUE, (fit.K, fit.K_std, fit.limit_how)
    assert 0.15 * G <= fit.max_lateral < 0.7 * cap and fit.passed_over > 0
    assert "turn" in fit.limit_how and "3 standard errors" in fit.limit_how


def test_linear_tyres_keep_every_window():
    """Tyres of friction 50 at the same accelerations: nothing bends, every window is kept."""
    w = steady_turns(mu=50.0)
    cap = float(np.abs(w["a_y"]).max())
    fit = in_linear_range(w, L, 0.15 * G, cap, fixed_gain=1.0)
    assert fit.passed_over == 0 and fit.max_lateral == pytest.approx(cap)
    assert fit.K - 1.96 * fit.K_std <= K_TRUE <= fit.K + 1.96 * fit.K_std


@pytest.mark.slow
def test_identify_withholds_k_when_dynamic_and_steady_disagree():
    """The F1TENTH study (c_r = 10 per unit load) with tyres of friction 0.6 driven to 3.4 m/s2, past
    their bend: the final model's K (about 0.0093) and the steady turns' in their linear range (about
    0.0104, 3.5 standard errors apart) disagree; identify concludes no single K, prints both and why, and
    the steady turns' holds the truth."""
    from agrobot.identification.ordinary_driving import identify_driving, summary
    from agrobot.orchestrator.runner import simulate
    from agrobot.orchestrator.study import Study
    from tests.vehicle_logs import ROOT_STUDIES

    study = ROOT_STUDIES / "f1tenth.toml"
    st = Study.load(study).with_values({"study.stop_time": 120.0, "plan.duration": 120.0, "car.C_r": 114.0,
                                        "car.tyre_friction": 0.6, "car.tyre_shape": 1.3})
    rec, _ = simulate(st)
    f = rec.to_frame().iloc[::4].reset_index(drop=True)
    log = pd.DataFrame({"t": f["t"], "delta_cmd": f["plan.steer_angle_cmd"], "v": f["plan.speed_cmd"],
                        "yaw_rate": f["gyro.yaw_rate_measured"]})
    rep = identify_driving(log, "friction 0.6", Study.load(study))
    pair = next(c for c in rep["comparisons"] if c["quantity"] == "understeer gradient K")
    k_ss = rep["steady_state_regression"]["understeer_gradient"]
    assert k_ss["interval"][0] <= K_TRUE <= k_ss["interval"][1]
    K = rep["understeer_gradient"]
    assert not pair["agree"], pair               # planted: the tyres bend within the dynamic fit's span
    assert K.get("withheld") and not K["identifiable"]
    text = summary(rep)
    line = next(x for x in text.splitlines() if x.startswith("understeer gradient K:"))
    assert f"{pair['estimates']['dynamic fit']['value']:.3g}" in line
    assert f"{k_ss['value']:.3g}" in line
    assert any(why in line for why in ("saturation not modelled", "different stretches", "a different model structure"))
    assert "characteristic speed:" not in text and "critical speed:" not in text and math.isfinite(K["value"])


def test_a_linear_limit_not_read_from_the_turns_is_said_by_its_field():
    """Too few windows under 0.05 m/s2 to read the limit from: it is not derived, by its field."""
    w = steady_turns()
    cap = float(np.percentile(np.abs(w["a_y"]), 99))
    assert in_linear_range(w, L, 0.15 * G, cap, fixed_gain=1.0).limit_derived
    assert not in_linear_range(w, L, 0.05, cap, fixed_gain=1.0).limit_derived
