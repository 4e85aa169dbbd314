"""The figures show what is judged: read from the matplotlib Figure objects (lines, limits, texts),
compared with the metrics, the bounds and roots computed here by a second route."""
from __future__ import annotations

import re

import math
from pathlib import Path
from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def figure8_run():
    from agrobot.orchestrator.runner import simulate
    from agrobot.orchestrator.study import load_study

    study = load_study(ROOT / "studies" / "figure8.toml", ["study.stop_time=45"])
    return study, simulate(study)[0].to_frame()


def _constant_lines(ax) -> dict[str, float]:
    """Horizontal lines (axhline) by label -> their y."""
    return {ln.get_label(): float(ln.get_ydata()[0]) for ln in ax.get_lines()
            if len(set(np.atleast_1d(ln.get_ydata()))) == 1 and len(np.atleast_1d(ln.get_xdata())) == 2}


def test_error_figure_draws_the_euclidean_error_the_bounds_judge(figure8_run):
    from agrobot.analysis.figure8 import error_figure, metrics

    study, frame = figure8_run
    fig = error_figure(frame, study)
    ax = fig.axes[0]
    drawn = next(ln for ln in ax.get_lines() if ln.get_label().startswith("Euclidean error"))
    # the error by a second route: the reference's own samples (every 5th row at 20 Hz) interpolated here
    t = frame["t"].to_numpy()
    own = np.isclose(np.round(t / 0.05) * 0.05, t, atol=1e-9)
    x_ref = np.interp(t, t[own], frame["reference.x_ref"].to_numpy()[own])
    y_ref = np.interp(t, t[own], frame["reference.y_ref"].to_numpy()[own])
    err = np.hypot(frame["tractor.x_cg"].to_numpy() - x_ref, frame["tractor.y_cg"].to_numpy() - y_ref)
    np.testing.assert_allclose(drawn.get_ydata(), err, atol=1e-9)
    m = metrics(frame, study)
    judged = t >= m["metrics_from_time_s"]
    curved = frame["reference.segment"].to_numpy() > 0.5
    assert err[judged & ~curved].max() == pytest.approx(m["euclid_max_straight"], rel=1e-9)
    assert err[judged & curved].max() == pytest.approx(m["euclid_max_curved"], rel=1e-9)
    bounds = _constant_lines(ax)
    assert sorted(v for k, v in bounds.items() if "bound" in k) == [0.40, 0.60]
    marked = {ln.get_label(): float(ln.get_ydata()[0]) for ln in ax.get_lines() if ln.get_label().startswith("max on")}
    assert marked[f"max on straights {m['euclid_max_straight']:.3f} m"] == pytest.approx(m["euclid_max_straight"])
    assert ax.get_ylim()[1] > 0.60
    curve_spans = [p for p in ax.patches if p.get_label() == "curve (bound 0.60 m)"]
    assert curve_spans, "curves are shaded"
    plt.close(fig)


def test_trajectory_shows_the_reference_under_the_path_and_zooms_on_the_largest_error(figure8_run):
    from agrobot.analysis.figure8 import metrics, trajectory_figure

    study, frame = figure8_run
    fig = trajectory_figure(frame, study)
    ax, zoom = fig.axes[:2]
    by_label = {ln.get_label(): ln for ln in ax.get_lines()}
    ref, path = by_label["reference"], by_label["actual (CG)"]
    assert ref.get_linewidth() > 3 * path.get_linewidth() and ref.get_zorder() < path.get_zorder()
    segment = next(ln for ln in zoom.get_lines() if ln.get_label().startswith("largest judged error"))
    (x0, x1), (y0, y1) = segment.get_xdata(), segment.get_ydata()
    m = metrics(frame, study)
    assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(max(m["euclid_max_straight"], m["euclid_max_curved"]), rel=1e-6)
    width = zoom.get_xlim()[1] - zoom.get_xlim()[0]
    assert width < 0.1 * (ax.get_xlim()[1] - ax.get_xlim()[0])        # a zoom, not the whole figure
    plt.close(fig)


def _fake_analyses():
    """Two speeds, an RLF fit with a fast pole at -1.44e7 rad/s and a right-half-plane zero at
    +161 rad/s (as the shipped identification finds at 1 m/s), FRF lines to 2 Hz."""
    freq = np.linspace(0.02, 2.0, 40)
    s = 2j * np.pi * freq
    num, den = np.array([-1.8, 290.0]), np.polymul([1.0, 11.6, 249.0], [1.0, 1.44e7])
    G = np.polyval(num, s) / np.polyval(den, s) * 1.44e7

    def fit(n, d):
        return SimpleNamespace(poles=np.roots(d), zeros=np.roots(n),
                               response=lambda f: np.polyval(n, 2j * np.pi * f) / np.polyval(d, 2j * np.pi * f)
                               * (d[-1] / n[-1]) * 1.2)
    detection = {"kind": np.array(["excited", "odd", "even"] * 10), "freq": np.linspace(0.02, 8, 30),
                 "level": np.full(30, 1e-4), "noise": np.full(30, 1e-5)}
    frf = SimpleNamespace(freq=freq, G=G, var_noise=np.full(40, 3e-3), var_nl=np.where(freq > 1, 1e-3, 0.0),
                          detection=detection)
    fits = {"second_order": fit(np.array([290.0]), np.array([1.0, 11.6, 249.0])), "rlf": fit(num, den)}
    return {1.0: {"frf": frf, "fits": fits}, 2.0: {"frf": frf, "fits": {k: fit(np.array([290.0]), np.array([1.0, 11.6, 249.0]))
                                                                    for k in fits}}}


def _captured(monkeypatch) -> list:
    from matplotlib.figure import Figure

    figures = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: figures.append(self))
    return figures


def test_poles_zeros_at_physical_scale_list_the_off_scale_roots(tmp_path, monkeypatch):
    from agrobot.identification.plots import write_plots

    figures = _captured(monkeypatch)
    write_plots(_fake_analyses(), 1.0, tmp_path)
    frf_fig, _, pz_fig = figures
    fast = np.roots(np.polymul([1.0, 11.6, 249.0], [1.0, 1.44e7])).real.min()       # -1.44e7
    rlf = next(ax for ax in pz_fig.axes if ax.get_title().startswith("rlf"))
    lo, hi = rlf.get_xlim()
    assert -40.0 < lo < -10.0 and 10.0 < hi < 40.0       # the slow poles' scale (|p| = 15.8 rad/s), not 1e7
    text = "\n".join(t.get_text() for t in rlf.texts)
    assert f"pole {fast:+.3g} rad/s at 1 m/s" in text and "zero +161 rad/s at 1 m/s (RHP)" in text
    # the magnitude axis spans the measured FRF (2.6..5 dB here), not a fixed 60 dB
    mag = frf_fig.axes[0]
    db = 20 * np.log10(np.abs(_fake_analyses()[1.0]["frf"].G))
    bottom, top = mag.get_ylim()
    assert bottom < db.min() and top > db.max() and top - bottom < 3 * max(db.max() - db.min(), 6.0)


def test_identify_message_names_off_scale_roots_and_right_half_plane_zeros():
    from agrobot.identification.plots import root_notes

    den = np.polymul([1.0, 11.6, 249.0], [1.0, 1.44e7])
    report = {"speeds": {"1": {"models": {"rlf": {"poles": [[p.real, p.imag] for p in np.roots(den)],
                                                  "zeros": [[290.0 / 1.8, 0.0]]}},
                               "frf": {"freq_hz": [0.02, 1.0, 2.0]}}}}
    lines = root_notes(report)
    text = "\n".join(lines)
    assert "off the scale" in text and "rlf: pole -1.44e+07 rad/s at 1 m/s" in text
    assert "right-half-plane zeros" in text and "rlf: zero +161 rad/s at 1 m/s (RHP)" in text


def test_in_field_frame_undoes_the_mission_frame():
    from agrobot.analysis.field_tracks import _in_field_frame
    from agrobot.components.field_route import to_mission

    rng = np.random.default_rng(3)
    xy = rng.uniform(-100, 100, (50, 2))
    origin, rotation = np.array([12.0, -40.0]), 0.7
    plan = SimpleNamespace(path=SimpleNamespace(start_pose=lambda: (origin[0], origin[1], rotation)))
    m = to_mission(xy, origin, rotation)
    back = _in_field_frame(pd.DataFrame({"x": m[:, 0], "y": m[:, 1], "ix": m[:, 0], "iy": m[:, 1]}), plan)
    np.testing.assert_allclose(back[["x", "y"]].to_numpy(), xy, atol=1e-9)


def test_sweep_figure_draws_the_chosen_metrics_with_their_bounds(tmp_path, monkeypatch):
    from agrobot.orchestrator.study import Study
    from agrobot.orchestrator.sweep import sweep_plots

    figures = _captured(monkeypatch)
    study = Study.load(ROOT / "studies" / "speed_sweep.toml")
    table = pd.DataFrame({"point": ["p0", "p1"], "seed": [1, 1], "reference.speed": [1.0, 2.0],
                          "status": ["completed"] * 2, "euclid_max_straight": [0.3, 0.2], "euclid_max_curved": [0.3, 0.2],
                          "steer_rate_rms": [0.1, 0.2], "wall_time_s": [2.0, 3.0], "events": [0, 0],
                          "metrics_from_time_s": [13.0, 13.0]})
    sweep_plots(study, table, tmp_path)
    panels = {ax.get_title(): ax for ax in figures[0].axes if ax.get_title()}
    assert set(panels) == {"euclid_max_straight", "euclid_max_curved", "steer_rate_rms"}
    assert _constant_lines(panels["euclid_max_straight"])["bound 0.4 m"] == 0.40
    assert _constant_lines(panels["euclid_max_curved"])["bound 0.6 m"] == 0.60


def test_diagnosis_figures_agree_with_the_verdict_and_the_report_uses_one_unit_system(tmp_path, monkeypatch):
    """A healthy log (verdict none) whose steering residual is above 1.5 x its floor: the figure draws
    the healthy level that explains it, and the final model's bar stays under the misfit level."""
    from agrobot.diagnosis.pipeline import diagnose
    from agrobot.diagnosis.report import floors_figure
    from harness.truth_tractor import make_log

    frame, _ = make_log(101, None)
    frame.to_csv(tmp_path / "log.csv", index=False)
    res = diagnose(tmp_path / "log.csv", tmp_path / "out", plots=False, identify=False)
    assert res["verdict"] == "none"
    kept = []
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig))
    floors_figure(res, tmp_path / "floors.png")
    ax = kept[0].axes[0]
    stages = [s for s, st in res["stages"].items() if st.get("judged", True)]
    level = {c.get_label().split()[0]: [float(seg[0, 1]) for seg in c.get_segments()] for c in ax.collections}
    final = next(c for c in ax.containers if c.get_label() == "final model")
    steering = stages.index("steering")
    st = res["stages"]["steering"]
    assert final.patches[steering].get_height() > 1.5          # above 1.5 x its floor, yet not a misfit ...
    assert level["healthy"][steering] == pytest.approx(st["healthy_level"] / st["floor"])
    assert level["healthy"][steering] > final.patches[steering].get_height()     # ... the healthy level explains it
    for j, s in enumerate(stages):
        st = res["stages"][s]
        assert level["healthy"][j] == pytest.approx(st["healthy_level"] / st["floor"])
        # the misfit level by the rule in words: 1.5 x floor and a material excess over healthy
        assert level["misfit"][j] == pytest.approx(max(1.5, math.hypot(st["healthy_level"], st["materiality"]) / st["floor"]))
        assert final.patches[j].get_height() < level["misfit"][j]
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert all("no misfit" in label for label in labels)
    # the title says the verdict with the highest stage of diagnosis.json against its floor
    ratio = {s: res["stages"][s]["rms_test"] / res["stages"][s]["floor"] for s in stages}
    top = max(ratio, key=ratio.get)
    assert ax.get_title().startswith(f"Diagnosis: no fault; the study explains the log to its noise floor (highest: "
                                     f"{top} {ratio[top]:.2f} x its floor, no misfit)")
    # report.md: every residual in deg, deg/s, m or m/s; radians only in the note on study-file values
    from agrobot.diagnosis.report import markdown

    text = markdown(res, [])
    body = "\n".join(line for line in text.splitlines() if not line.startswith("Baseline model:"))
    assert not re.search(r"\brad\b", body), [line for line in body.splitlines() if re.search(r"\brad\b", line)]
    assert "| steering | deg |" in text and "| yaw | deg/s |" in text and "**yaw** [deg/s]" in text


def _verdict(effects: list[tuple[str, dict, float]], unexplained: dict | None = None, status="conclusive") -> dict:
    """A diagnosis result of the JSON's shape: four judged stages (floor 1 in SI), the final model at 1.05 x floor,
    the baseline at 3 x; ``effects``: (id, parameters_display, held-out gain) found, best first."""
    stages = {s: {"stage": s, "floor": f, "healthy_level": 1.1 * f, "misfit_level": 1.5 * f, "misfit": False,
                  "rms_test": 1.05 * f, "rms_baseline_test": 3 * f,
                  "rms_without": {eid: (2 + k) * f for k, (eid, _, _) in enumerate(effects)}}
              for s, f in (("steering", 0.002), ("yaw", 0.005), ("position", 0.02), ("speed", 0.03))}
    found = [{"id": eid, "parameters_display": shown, "held_out_gain": gain} for eid, shown, gain in effects]
    if unexplained:
        stages[unexplained["stage"]].update(misfit=True, rms_test=unexplained["ratio_to_floor"] * stages[unexplained["stage"]]["floor"])
        found.append({"id": "unexplained", **unexplained, "by_stage": {unexplained["stage"]: {"extension": {
            "rms_after": 1.2 * stages[unexplained["stage"]]["floor"]}}}})
    verdict = effects[0][0] if effects else "unexplained" if unexplained else "none"
    return {"verdict": verdict, "verdict_status": status, "stages": stages, "effects": found}


def _drawn_floors(result, tmp_path, monkeypatch):
    from agrobot.diagnosis.report import floors_figure

    kept = []
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig))
    floors_figure(result, tmp_path / "noise_floors.png")
    return kept[0].axes[0]


@pytest.mark.parametrize("case", ["one effect", "two effects, inconclusive", "unexplained", "none"])
def test_the_verdict_figure_says_the_verdict_with_its_numbers_labels_units_and_reads_in_grey(case, tmp_path, monkeypatch):
    from tests.figure_checks import apart_in_greyscale, has_unit

    result = {"one effect": lambda: _verdict([("actuator_delay", {"command_delay [s]": 0.2134}, 0.6412)]),
              "two effects, inconclusive": lambda: _verdict(
                  [("steering_offset", {"steer_angle_offset [deg]": -1.234}, 0.3), ("yaw_rate_bias", {
                      "yaw_rate_bias [deg/s]": 0.0567, "scale [-]": 1.02}, 0.1)], status="inconclusive"),
              "unexplained": lambda: _verdict([], {"stage": "yaw", "ratio_to_floor": 2.37, "held_out_gain": 0.41}),
              "none": lambda: _verdict([])}[case]()
    ax = _drawn_floors(result, tmp_path, monkeypatch)
    title = ax.get_title().split("\n")[0]
    expected = {"one effect": "Diagnosis: actuator delay, command_delay 0.213 s (held-out gain 64 %)",
                "two effects, inconclusive": "Diagnosis: steering offset, steer_angle_offset -1.23 deg (held-out gain 30 %)"
                                             ": inconclusive; also yaw rate bias",
                "unexplained": "Diagnosis: unexplained misfit, the yaw stage at 2.4 x its noise floor "
                               "(a data-driven extension takes 41 % off held out)",
                "none": "Diagnosis: no fault; the study explains the log to its noise floor (highest: steering 1.05 x "
                        "its floor, no misfit)"}[case]
    assert title == expected
    assert has_unit(ax.get_ylabel())
    ticks = [t.get_text() for t in ax.get_xticklabels()]        # each stage's floor in the report's units
    assert "floor 0.11 deg" in ticks[0] and "floor 0.29 deg/s" in ticks[1] and "floor 0.02 m" in ticks[2]
    assert apart_in_greyscale(ax) == []


def test_the_greyscale_check_finds_what_only_hue_tells_apart():
    """The check itself can fail: two solid lines of equal luminance (red 0.30, green 0.29), two unhatched bars
    alike in grey, and the former five-colour coverage map whose grey, green and orange merge."""
    from matplotlib.colors import ListedColormap

    from tests.figure_checks import apart_in_greyscale

    fig, (a, b, c) = plt.subplots(1, 3)
    a.plot([0, 1], [0, 1], color="#ff0000", label="red")
    a.plot([0, 1], [1, 0], color="#00807f", label="teal")
    a.plot([0, 1], [1, 1], color="#ff0000", ls="--", label="dashed red")
    b.bar([0], [1], color="tab:red", label="baseline")
    b.bar([1], [1], color="tab:blue", label="other")
    b.bar([2], [1], color="white", hatch="//", label="hatched")
    a.legend(), b.legend()
    c.pcolormesh(np.arange(5.0).reshape(1, 5), cmap=ListedColormap(["#bdbdbd", "#d7301f", "#a6d96a", "#fdae61", "#7b3294"]))
    assert [x.split(" (")[0] for x in apart_in_greyscale(a)] == ["red / teal"]
    assert [x.split(" (")[0] for x in apart_in_greyscale(b)] == ["baseline / other"]
    assert apart_in_greyscale(c) and "colour map" in apart_in_greyscale(c)[0]
    plt.close(fig)
