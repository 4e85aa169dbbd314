"""Identification (paper section IV): Appendix A against the equations of motion, the physical
RLFR against the paper's identified model, calibrated recovery of a known transfer function,
nonlinearity detection, the whole pipeline on a simulated experiment and on its log, bad logs."""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.components.models.paper_models import G_2ND
from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.identification import frf
from agrobot.identification.experiment import config_of, simulate_experiment
from agrobot.identification.fitting import fit
from agrobot.identification.multisine import MultisineDesign, crest_factor, realisation
from agrobot.identification.physical import MISPRINTS, appendix_as_printed, coefficients, rlfr_physical
from agrobot.orchestrator.study import Study
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
P = TractorParameters()
PAPER_RLFR = ([279, 335, 27860], [1, 11.5, 347, 1311, 23340])
PAPER_G2ND = (list(G_2ND.num), list(G_2ND.den))


@pytest.mark.parametrize("v", [0.7, 2.0, 3.0])
@pytest.mark.parametrize("model", ["rlf", "rlfr"])
def test_appendix_is_right_except_for_the_named_misprints(model, v):
    printed, derived = appendix_as_printed(model, P, v), coefficients(model, P, v)
    assert set(printed) == set(derived)
    for name in printed:
        same = math.isclose(printed[name], derived[name], rel_tol=1e-10)
        assert same != ((model, name) in MISPRINTS), f"{model} {name}: printed {printed[name]}, derived {derived[name]}"


def test_misprint_rlf_a2_is_missing_its_denominator():
    m, I, lr, Cr, sf, v = P.m, P.I, P.l_r, P.C_r, P.sigma_f, 2.0
    assert appendix_as_printed("rlf", P, v)["a2"] / (I * m * v * sf) == pytest.approx(coefficients("rlf", P, v)["a2"])
    assert coefficients("rlf", P, v)["a2"] == pytest.approx((I * m * v**2 + Cr * lr**2 * m * sf + I * Cr * sf) / (I * m * v * sf))


def test_misprint_rlfr_a0_is_missing_the_speed_term():
    m, I, lf, lr, Cf, Cr, sf, sr, v = P.m, P.I, P.l_f, P.l_r, P.C_f, P.C_r, P.sigma_f, P.sigma_r, 2.0
    right = (Cf * Cr * (lf + lr) ** 2 + m * v**2 * (Cr * lr - Cf * lf)) / (I * m * sf * sr)
    assert coefficients("rlfr", P, v)["a0"] == pytest.approx(right, rel=1e-10)
    assert appendix_as_printed("rlfr", P, v)["a0"] == pytest.approx(Cf * Cr * (lf + lr) ** 2 / (I * m * sf * sr))


def test_misprint_rlfr_a1_speed_multiplies_the_whole_numerator():
    m, I, lf, lr, Cf, Cr, sf, sr, v = P.m, P.I, P.l_f, P.l_r, P.C_f, P.C_r, P.sigma_f, P.sigma_r, 2.0
    right = v * (I * (Cf + Cr) + m * (Cf * lf**2 + Cr * lr**2 - Cf * lf * sr + Cr * lr * sf)) / (I * m * sf * sr)
    assert coefficients("rlfr", P, v)["a1"] == pytest.approx(right, rel=1e-10)


def test_table_values_at_2_mps_give_the_papers_identified_rlfr_within_15_percent():
    c = coefficients("rlfr", P, 2.0)
    num, den = PAPER_RLFR
    for i, b in enumerate(num[::-1]):
        assert c[f"b{i}"] == pytest.approx(b, rel=0.15)
    for i, a in enumerate(den[::-1]):
        assert c[f"a{i}"] == pytest.approx(a, rel=0.15)
    # ...and not at 1 m/s: the comparison pins the speed of the paper's experiment
    c1 = coefficients("rlfr", P, 1.0)
    assert abs(c1["b1"] / 335 - 1) > 0.5


def test_the_papers_rlfr_maps_back_near_the_table():
    sols = rlfr_physical(*PAPER_RLFR, v=2.0, m=700.0, l_f=1.0, l_r=0.4)
    best = sols[0]
    assert abs(best["C_r"] - 90000) < 7000                      # Table: 90000 +- 7000
    assert best["sigma_f"] == pytest.approx(0.1942, rel=0.05)
    assert best["sigma_r"] == pytest.approx(1.6657, rel=0.05)
    assert best["C_f"] == pytest.approx(8000, rel=0.10)          # 7270: outside the Table's +-500
    assert best["cost"] < 0.05


def test_multisine_design():
    d = MultisineDesign(20.0, 1000, 0.02, 2.0, math.radians(4), "odd_odd")
    assert list(d.excited[:4]) == [1, 5, 9, 13] and d.excited[-1] == 97
    x = realisation(d, np.random.default_rng(0))
    X = np.abs(np.fft.rfft(x))
    assert np.all(X[np.setdiff1d(np.arange(1, 500), d.excited)] < 1e-9 * X.max())
    assert np.sqrt(np.mean(x**2)) == pytest.approx(math.radians(4))
    assert crest_factor(x) < 3.5
    with pytest.raises(ValueError, match="band"):
        MultisineDesign(20.0, 1000, 0.02, 12.0, 0.1)


def band_limited_experiment(num, den, seed, M=4, P_=4, noise=0.075, delay=0.0):
    """Steady-state periodic data of a known G(s) e^{-s delay}: Y_k = G(j w_k) U_k exactly, plus
    white noise."""
    d = MultisineDesign(20.0, 1000, 0.02, 2.0, math.radians(4), "odd_odd")
    rng = np.random.default_rng(seed)
    us, ys = [], []
    for _ in range(M):
        one = realisation(d, rng)
        s = 2j * np.pi * np.arange(501) * d.f0
        G = np.polyval(num, s) / np.polyval(den, s) * np.exp(-s * delay)
        y_one = np.fft.irfft(G * np.fft.rfft(one), n=1000)
        us.append(np.tile(one, P_).reshape(P_, 1000))
        ys.append(np.tile(y_one, P_).reshape(P_, 1000) + noise * rng.standard_normal((P_, 1000)))
    return frf.analyse(np.array(us), np.array(ys), 20.0, d.excited)


def test_recovery_of_a_known_transfer_function_is_within_three_reported_sigmas():
    num0, den0 = PAPER_G2ND
    z = []
    for seed in range(25):
        r = band_limited_experiment(num0, den0, seed)
        f = fit("second_order", r.freq, r.G, r.var_fit)
        z.append(np.concatenate([(f.num - num0) / f.num_std, (f.den[1:] - den0[1:]) / f.den_std[1:]]))
        assert 0.4 < f.cost / f.cost_expected < 2.0
    z = np.array(z)
    assert np.mean(np.abs(z) <= 3) >= 0.97                      # 3-sigma coverage
    assert 0.7 < z.std() < 1.4                                   # the reported sigmas are calibrated
    assert abs(z.mean()) < 0.5                                   # no bias


def test_a_pure_delay_is_recovered_when_asked_for():
    hits = 0
    for seed in range(10):
        r = band_limited_experiment(*PAPER_G2ND, seed, delay=0.15)
        f = fit("second_order", r.freq, r.G, r.var_fit, delay=True)
        hits += abs(f.delay - 0.15) <= 3 * f.delay_std
        assert f.delay_std < 0.02
    assert hits >= 9
    no_delay = fit("second_order", r.freq, r.G, r.var_fit)
    assert no_delay.cost > 5 * f.cost                      # leaving it out does not fit


def test_frf_variances_match_their_empirical_spread():
    Gs, var = [], []
    for seed in range(60):
        r = band_limited_experiment(*PAPER_G2ND, seed)
        Gs.append(r.G)
        var.append(r.var_noise)
    ratio = np.var(np.array(Gs), axis=0, ddof=1) / np.mean(var, axis=0)
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.1)


def nl_experiment(deadband_v):
    study = Study.load(ROOT / "studies/identification.toml",
                       [f"steering.deadband={deadband_v}", "steering.potentiometer_resolution=0.0",
                        "gyro.noise_std=0.01", "identification.period=20.0", 'identification.rms="1 deg"'])
    exp = simulate_experiment(study, config_of(study), 2.0, (0.05, 2.0), "odd_odd", 2, 3, 1)
    return frf.analyse(exp.u, exp.y, exp.fs, exp.excited)


def test_a_steering_dead_band_shows_at_the_odd_non_excited_lines_only():
    with_db, without = nl_experiment(3.0), nl_experiment(0.0)
    assert frf.nonlinearity_ratio(with_db, "odd") > 4.0          # clearly above the noise floor
    assert frf.nonlinearity_ratio(without, "odd") < 1.5          # at the noise level
    assert frf.nonlinearity_ratio(with_db, "even") < 1.5         # a symmetric dead-band: odd only
    assert frf.nonlinearity_ratio(without, "even") < 1.5


@pytest.fixture(scope="module")
def study_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("ident")
    proc = subprocess.run([sys.executable, "-m", "agrobot", "identify", str(ROOT / "studies/identification.toml"),
                           "--out", str(out)], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout, json.loads((out / "identification.json").read_text())


def test_study_identification_reproduces_section_iv(study_run):
    out, stdout, rep = study_run
    for name in ("frf.png", "nonlinear_distortion.png", "poles_zeros.png", "experiment_log.csv"):
        assert (out / name).stat().st_size > 1000
    models = rep["models"]
    assert set(models) == {"second_order", "bicycle", "rlf", "rlfr"}
    for name, m in models.items():
        assert m["stable"], name
        assert 0.5 < m["cost"] / m["cost_expected"] < 2.0, name
        assert len(m["num"]) == len(m["num_std"]) and m["den"][0] == 1.0
        for band in ("0-2Hz", "0-8Hz"):
            assert 0.05 < m["validation_rmse"][band] < 0.1, (name, band)   # paper: 0.079-0.086
    # a 2nd-order fit to the RLF plant at 2 m/s is close to the paper's G_2nd
    g = models["second_order"]
    assert g["num"][0] == pytest.approx(291, rel=0.15)
    for ours, paper in zip(g["den"], PAPER_G2ND[1]):
        assert ours == pytest.approx(paper, rel=0.15)
    assert set(rep["speeds"]) == {"2", "1"}
    assert rep["models"]["rlfr"]["physical"]["solutions"]
    assert "paper: num [291]" in stdout and "0.0787" in stdout


def test_the_same_command_on_the_experiments_log_gives_the_same_fits(study_run, tmp_path):
    out, _, rep = study_run
    proc = cli("identify", str(out / "experiment_log.csv"), "--out", str(tmp_path), "--no-plots")
    assert proc.returncode == 0, proc.stderr
    log_rep = json.loads((tmp_path / "identification.json").read_text())
    for name in ("second_order", "rlf"):
        np.testing.assert_allclose(log_rep["models"][name]["num"], rep["models"][name]["num"], rtol=1e-6)
        np.testing.assert_allclose(log_rep["models"][name]["den"], rep["models"][name]["den"], rtol=1e-6)
    notes = " ".join(log_rep["notes"])
    assert "1000 samples = 50 s" in notes and "4 realisation(s)" in notes and "2.000 m/s" in notes
    assert "(odd-odd)" in notes


@pytest.mark.parametrize("edit, words", [
    (lambda f: f.drop(columns=["yaw_rate"]), ["identification not possible", "no yaw_rate"]),
    (lambda f: f.assign(t=f["t"].where(f.index != 100, 0.0)), ["not increasing at row"]),
    (lambda f: f.assign(delta=f["delta"].where(f.index != 50, np.nan)), ["'delta'", "NaN"]),
    (lambda f: f.iloc[:2000], ["too few periods"]),
    (lambda f: f.assign(delta=np.degrees(f["delta"])), ["looks like degrees"]),
])
def test_bad_logs_get_clear_errors(study_run, tmp_path, edit, words):
    out, _, _ = study_run
    frame = edit(pd.read_csv(out / "experiment_log.csv"))
    bad = tmp_path / "bad.csv"
    frame.to_csv(bad, index=False)
    proc = cli("identify", str(bad), "--out", str(tmp_path / "o"))
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert str(bad) in proc.stderr
    for w in words:
        assert w in proc.stderr
