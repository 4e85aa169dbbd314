"""Figure-8 tracking (paper section VI-B): Euclidean error of the CG on straights and curves,
speed and yaw-rate tracking, the paper's figures as PNG.

Imported where used: matplotlib (start-up: pyplot, about 1.1 s here, would be paid by every run of a figure-8
study and by each of its sweep workers, which read this module for their metrics, plots or not).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.components.models.figure8_path import Figure8Path
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .signal_roles import between_samples, component_named, rms, runs, sample_rows, signal
from .mcap_scene import mcap_scene  # noqa: F401 - the run's MCAP scene (orchestrator.mcap_out)

# The paper's reported bounds (abstract and section VI-B): Euclidean error below 40 cm on
# straight and below 60 cm on curved time-based trajectories.
PAPER_BOUNDS = {"euclid_max_straight": 0.40, "euclid_max_curved": 0.60}
# The start from rest is not steady tracking: metrics start this long after the reference has
# reached its speed; the start-up error is reported apart as euclid_max_startup.
STARTUP_SETTLE_S = 5.0


def tracking_error(frame: pd.DataFrame, study: Study, held: bool = False) -> np.ndarray:
    """|CG - reference| at every instant of the plant, the reference taken at the same instant
    (interpolated between its 20 Hz samples: signals.between_samples); ``held``: the reference as
    the table holds it between samples (up to speed x its step behind: the figures of a reference held at 20 Hz)."""
    if held:
        x_ref, y_ref = signal(frame, study, "reference", "x_ref"), signal(frame, study, "reference", "y_ref")
    else:
        x_ref, y_ref = between_samples(frame, study, "reference", ("x_ref", "y_ref"))
    return np.hypot(signal(frame, study, "yaw_plant", "x_cg") - x_ref, signal(frame, study, "yaw_plant", "y_cg") - y_ref)


def settled_index(t: np.ndarray, speed: np.ndarray, fraction: float = 0.999) -> int:
    """First sample STARTUP_SETTLE_S after ``speed`` reaches ``fraction`` of its maximum (a run
    that ends with the speed still rising has not reached it: said so, not a time that moves with
    the run's end)."""
    t_full = t[int(np.argmax(speed >= fraction * speed.max()))]
    start = int(np.searchsorted(t, t_full + STARTUP_SETTLE_S))
    if start >= len(t) - 1 and len(speed) > 1 and speed[-1] > speed[-2]:
        raise ValueError(f"run too short for metrics: the speed still rises at its end (t = {t[-1]:g} s); the "
                         f"metrics start {STARTUP_SETTLE_S:g} s after it has reached its speed: run past the "
                         f"reference's ramp (reference.ramp_time) and {STARTUP_SETTLE_S:g} s more")
    if start >= len(t) - 1:
        raise ValueError(f"run too short for metrics: it must last beyond {t_full + STARTUP_SETTLE_S} s")
    return start


def metrics(frame: pd.DataFrame, study: Study) -> dict[str, float]:
    """Tracking metrics from STARTUP_SETTLE_S after the reference reaches its speed; the start
    from rest is reported apart as ``euclid_max_startup``."""
    err_all = tracking_error(frame, study)
    held = tracking_error(frame, study, held=True)
    start = settled_index(frame["t"].to_numpy(), signal(frame, study, "reference", "speed_ref"))
    frame, err, held = frame.iloc[start:], err_all[start:], held[start:]
    curved = signal(frame, study, "reference", "segment") > 0.5
    speed = signal(frame, study, "drivetrain", "speed")
    v_d = signal(frame, study, "tracker", "speed_desired")
    gamma = signal(frame, study, "yaw_plant", "yaw_rate")
    gamma_d = signal(frame, study, "tracker", "yaw_rate_desired")
    psi = signal(frame, study, "yaw_plant", "heading")
    psi_hat = signal(frame, study, "pose_estimator", "heading")
    dpsi = np.angle(np.exp(1j * (psi_hat - psi)))
    straight = ~curved
    t = frame["t"].to_numpy()
    delta = signal(frame, study, "steering", "steer_angle")        # the wheels' angle (not the sensor's)
    steer_rate = np.diff(delta) / np.diff(t) if len(t) > 1 else np.zeros(0)

    def stat(fn, values):      # NaN when the window holds no sample of that kind
        return float(fn(values)) if len(values) else float("nan")

    return {
        "euclid_mean_straight": stat(np.mean, err[straight]),
        "euclid_max_straight": stat(np.max, err[straight]),
        "euclid_mean_curved": stat(np.mean, err[curved]),
        "euclid_max_curved": stat(np.max, err[curved]),
        "euclid_rms": rms(err),
        "euclid_max_startup": float(err_all[:start].max()) if start else 0.0,
        "euclid_mean_straight_held": stat(np.mean, held[straight]),
        "euclid_max_straight_held": stat(np.max, held[straight]),
        "euclid_mean_curved_held": stat(np.mean, held[curved]),
        "euclid_max_curved_held": stat(np.max, held[curved]),
        "metrics_from_time_s": float(frame["t"].iloc[0]),
        "speed_rms_error": rms(speed - v_d),
        "speed_mean_error": float(np.mean(speed - v_d)),
        "speed_rms_error_vs_path": rms(speed - signal(frame, study, "reference", "speed_ref")),
        "yaw_rate_rms_error": rms(gamma - gamma_d),
        "yaw_rate_mean_error": float(np.mean(gamma - gamma_d)),
        "heading_estimate_rms_error": rms(dpsi),
        "steer_angle_rms": rms(delta),
        "steer_rate_rms": rms(steer_rate),
    }


def _next_time_on(study: Study, label: int, after: float) -> float | None:
    """The first time after ``after`` at which the reference is on a segment ``label``
    (models.figure8_path: 0 straight, 1 curve), from the reference's own parameters and
    s(t) = v (t - t0 - T/2) past its ramp; None when the reference is not a figure-8's."""
    p = resolve(study).parameters(component_named(study, "reference"))
    if not {"speed", "radius", "centre_offset", "ramp_time"} <= set(p):
        return None
    path, v, ramp, t0 = Figure8Path(p["radius"], p["centre_offset"]), p["speed"], p["ramp_time"], study.study.start_time
    s0 = v * max(after - t0 - ramp / 2.0, 0.0)
    for s in s0 + np.arange(0.0, path.lap_length, 0.05):
        if path.pose(s)[4] == label:
            return t0 + ramp / 2.0 + s / v
    return None


def _short_of(values: dict[str, float], study: Study):
    """(figures, the segment, the settling time, the run's end, the time the reference next
    reaches that segment or None) for each segment kind whose figures are nan."""
    settled = values.get("metrics_from_time_s", float("nan"))
    end = study.study.start_time + values.get("sim_time_s", study.study.stop_time - study.study.start_time)
    for kind, label in (("straight", 0), ("curved", 1)):
        names = [f"euclid_{q}_{kind}{held}" for q in ("mean", "max") for held in ("", "_held")]
        missing = [n for n in names if np.isnan(values.get(n, 0.0))]
        if missing:
            t = _next_time_on(study, label, settled) if np.isfinite(settled) else None
            yield missing, "straight" if label == 0 else "curve", settled, end, t


def reasons(values: dict[str, float], study: Study) -> dict[str, str]:
    """Why a figure is nan: no straight (or curve) between the settling and the run's end, with
    the stop time that would reach one (orchestrator.key_figures prints it on the figure's line)."""
    out = {}
    for names, where, settled, end, t in _short_of(values, study):
        need = f": run at least {int(np.ceil(t + 1.0))} s" if t is not None else ""
        out.update(dict.fromkeys(names, f"no {where} after the {settled:.0f} s settling (the run ends at {end:.0f} s){need}"))
    return out


def stop_time_needed(values: dict[str, float], study: Study) -> dict[str, float]:
    """figure -> the stop time (s) that would give it a value, for the figures nan because the run
    ends before the reference reaches a straight or a curve after the settling (a sweep refuses to
    run points that cannot judge their bounds, orchestrator.sweep_judgement.check_length)."""
    return {n: float(np.ceil(t + 1.0)) for names, _, _, _, t in _short_of(values, study) if t is not None
            for n in names}


def unjudged(values: dict[str, float], study: Study) -> dict[str, str]:
    """The bounds a run too short to reach a straight or a curve after the settling cannot judge:
    shown with why, neither passed nor failed (a nan for any other reason still fails)."""
    return reasons(values, study)

# metric -> (SI unit, the paper's statement): a statement "< 0.40" is a bound that the run passes or
# fails (orchestrator.key_figures prints them after a run or a sweep); the units label sweep plots too
METRICS = {"euclid_mean_straight": ("m", None), "euclid_max_straight": ("m", f"< {PAPER_BOUNDS['euclid_max_straight']:.2f}"),
           "euclid_mean_curved": ("m", None), "euclid_max_curved": ("m", f"< {PAPER_BOUNDS['euclid_max_curved']:.2f}"),
           "speed_mean_error": ("m/s", "steady-state error seen"), "speed_rms_error": ("m/s", None),
           "yaw_rate_mean_error": ("rad/s", "no steady-state error"), "yaw_rate_rms_error": ("rad/s", None),
           "heading_estimate_rms_error": ("rad", None), "steer_angle_rms": ("rad", None),
           "steer_rate_rms": ("rad/s", None), "sim_time_s": ("s", None), "wall_time_s": ("s", None)}
BOUNDS_SOURCE = "paper"
METRIC_UNITS = {**{k: unit for k, (unit, _) in METRICS.items()},
                **{f"{k}_held": "m" for k in ("euclid_mean_straight", "euclid_max_straight", "euclid_mean_curved",
                                              "euclid_max_curved")},
                "euclid_rms": "m", "euclid_max_startup": "m", "metrics_from_time_s": "s",
                "speed_rms_error_vs_path": "m/s", "events": "count"}


# A sweep judges each point's steering-rate RMS against the nominal run's (orchestrator.sweep_judgement):
# a loop that hunts tracks within the error bounds while its steering valve works ten times as hard.
# Why 3: the steering rate of a loop that tracks is set by the path's curvature and the speed; over
# studies/robustness.toml's 200 draws the draws that track stay within 0.52-1.90 x the nominal's
# 5.1 deg/s (speed 1.0-2.5 m/s against 2.0, every yaw model and delay), the 24 that hunt (RLFR model
# above 1.7 m/s) steer at 4.43-9.74 x (sweep studies/robustness.toml --engine compiled).
OSCILLATION = ("steer_rate_rms", 3.0)

# What a sweep plots (orchestrator.sweep.sweep_plots), with the bound each is judged by: the bounded
# errors, the tracking of the two inner loops, the steering effort.
SWEEP_METRICS = {"euclid_max_straight": PAPER_BOUNDS["euclid_max_straight"],
                 "euclid_max_curved": PAPER_BOUNDS["euclid_max_curved"],
                 "speed_rms_error": None, "yaw_rate_rms_error": None, "steer_angle_rms": None, "steer_rate_rms": None}


def error_figure(frame: pd.DataFrame, study: Study):
    """The bounded quantity: |CG - reference| (the metrics' error) against time, the paper's bounds
    as lines, curves shaded, the start-up (not judged) hatched, the maxima on straights and curves
    marked; a second panel at the error's own scale when it is under a quarter of the bounds."""
    import matplotlib.pyplot as plt

    t = frame["t"].to_numpy()
    err = tracking_error(frame, study)
    curved = signal(frame, study, "reference", "segment") > 0.5
    start = settled_index(t, signal(frame, study, "reference", "speed_ref"))
    judged = np.arange(len(t)) >= start
    bound_s, bound_c = PAPER_BOUNDS["euclid_max_straight"], PAPER_BOUNDS["euclid_max_curved"]
    peak = float(err[judged].max())
    zoom = peak < 0.25 * min(bound_s, bound_c)
    fig, axes = plt.subplots(2 if zoom else 1, 1, sharex=True, figsize=(8, 6.5 if zoom else 4.5), squeeze=False)
    verdicts = []
    for ax in axes[:, 0]:
        for k, (a, b) in enumerate(runs(curved)):
            ax.axvspan(t[a], t[b - 1], color="C1", alpha=0.15, lw=0, label="curve (bound 0.60 m)" if k == 0 else None)
        ax.axvspan(t[0], t[start], facecolor="none", edgecolor="0.6", hatch="//", lw=0,
                   label=f"start-up, not judged (t < {t[start]:.0f} s)")
        ax.plot(t, err, color="k", lw=0.9, label="Euclidean error |CG - reference|")
        ax.set_ylabel("Euclidean error [m]")
        ax.grid(alpha=0.3)
    main = axes[0, 0]
    main.axhline(bound_s, color="C0", ls="--", lw=1.2, label=f"paper bound on straights {bound_s:.2f} m")
    main.axhline(bound_c, color="C1", ls="--", lw=1.2, label=f"paper bound on curves {bound_c:.2f} m")
    for kind, sel, bound, colour in (("straight", ~curved, bound_s, "C0"), ("curve", curved, bound_c, "C1")):
        idx = np.flatnonzero(sel & judged)
        if not len(idx):
            continue
        i = idx[np.argmax(err[idx])]
        verdicts.append(f"max on {kind}s {err[i]:.3f} m {'<' if err[i] < bound else '>='} {bound:.2f} m")
        for ax in axes[:, 0]:
            ax.plot(t[i], err[i], "o", color=colour, ms=6, mec="k", label=f"max on {kind}s {err[i]:.3f} m"
                    if ax is main else None)
    main.set_ylim(0, 1.4 * max(bound_c, bound_s, float(err.max())))      # headroom for the legend
    main.set_title("Tracking error judged by the paper's bounds: " + "; ".join(verdicts), fontsize=9)
    main.legend(fontsize=7, loc="upper right", ncol=2)
    if zoom:
        axes[1, 0].set_ylim(0, 1.15 * peak)
        axes[1, 0].set_title("zoom: the judged error at its own scale (bounds far above)", fontsize=9)
    axes[-1, 0].set_xlabel("time [s]")
    axes[-1, 0].set_xlim(t[0], t[-1])
    fig.tight_layout()
    return fig


def trajectory_figure(frame: pd.DataFrame, study: Study):
    """The reference (wide grey band, its 20 Hz samples as dots in the zoom) under the CG's path
    (thin red); the right panel zooms on the largest judged error, drawn as a segment."""
    import matplotlib.pyplot as plt

    t = frame["t"].to_numpy()
    x, y = signal(frame, study, "yaw_plant", "x_cg"), signal(frame, study, "yaw_plant", "y_cg")
    x_ref, y_ref = between_samples(frame, study, "reference", ("x_ref", "y_ref"))
    err = np.hypot(x - x_ref, y - y_ref)
    start = settled_index(t, signal(frame, study, "reference", "speed_ref"))
    i = start + int(np.argmax(err[start:]))
    fig, (ax, zoom) = plt.subplots(1, 2, figsize=(11, 4.8), gridspec_kw={"width_ratios": [2, 1]})
    half = max(3.0 * err[i], 0.3)
    for a in (ax, zoom):
        a.plot(x_ref, y_ref, color="0.6", lw=5 if a is ax else 4, alpha=0.6, solid_capstyle="round",
               label="reference", zorder=1)
        a.plot(x, y, color="r", lw=0.8, label="actual (CG)", zorder=2)
        a.set_xlabel("east x [m]"), a.set_ylabel("north y [m]"), a.grid(alpha=0.3)
    near = (np.abs(x_ref - x_ref[i]) < half) & (np.abs(y_ref - y_ref[i]) < half)
    own = sample_rows(frame, study, "reference")
    zoom.plot(x_ref[own & near], y_ref[own & near], ".", color="0.3", ms=3, label="reference samples (20 Hz)")
    zoom.plot([x[i], x_ref[i]], [y[i], y_ref[i]], "b-", lw=1.5, label=f"largest judged error {err[i]:.3f} m")
    zoom.plot(x[i], y[i], "o", color="r", ms=6, label=f"CG at t = {t[i]:.1f} s")
    zoom.plot(x_ref[i], y_ref[i], "x", color="k", ms=8, mew=2, label="reference at the same t")
    xdot, ydot = (v[i] for v in between_samples(frame, study, "reference", ("xdot_ref", "ydot_ref")))
    along = ((x_ref[i] - x[i]) * xdot + (y_ref[i] - y[i]) * ydot) / max(np.hypot(xdot, ydot), 1e-9)
    across = np.sqrt(max(err[i] ** 2 - along ** 2, 0.0))
    zoom.set_xlim(x_ref[i] - half, x_ref[i] + half), zoom.set_ylim(y_ref[i] - half, y_ref[i] + half)
    zoom.set_aspect("equal", adjustable="box")
    zoom.set_title(f"zoom, {2 * half:.1f} m square: the largest judged error\n{along:+.3f} m along the path (+: CG behind), "
                   f"{across:.3f} m across", fontsize=8)
    zoom.legend(fontsize=7, loc="lower left")
    ax.axis("equal")
    ax.indicate_inset([x_ref[i] - half, y_ref[i] - half, 2 * half, 2 * half], inset_ax=zoom, edgecolor="b")
    ax.legend(fontsize=8, loc="upper right")
    fig.suptitle(trajectory_verdict(frame, study), fontsize=10)
    fig.tight_layout()
    return fig


def trajectory_verdict(frame: pd.DataFrame, study: Study) -> str:
    """The trajectory figure's conclusion: the largest errors on straights and curves against the paper's
    bounds (section VI), each said within or beyond."""
    m = metrics(frame, study)
    parts = []
    for key, where in (("euclid_max_straight", "straights"), ("euclid_max_curved", "curves")):
        value, bound = m[key], PAPER_BOUNDS[key]
        if not np.isfinite(value):
            parts.append(f"no {where} judged")
        else:
            parts.append(f"{where} max {value:.2f} m ({'within' if value < bound else 'BEYOND'} the paper's {bound:.2f} m)")
    return "The CG follows the figure-8: " + "; ".join(parts)


def plots(frame: pd.DataFrame, study: Study, out_dir: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = frame["t"].to_numpy()
    sig = lambda typ, port: signal(frame, study, typ, port)  # noqa: E731
    written = []

    def save(fig, name):
        path = out_dir / name
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    save(trajectory_figure(frame, study), "trajectory.png")
    save(error_figure(frame, study), "error.png")

    for port_d, (typ, port), label, title, name in (
            ("speed_desired", ("drivetrain", "speed"), "speed [m/s]", "Longitudinal speed", "speed.png"),
            ("yaw_rate_desired", ("yaw_plant", "yaw_rate"), "yaw rate [rad/s]", "Yaw rate", "yaw_rate.png")):
        fig, ax = plt.subplots(figsize=(7, 3.5))
        if port == "speed":
            ax.plot(t, sig("reference", "speed_ref"), color="0.6", lw=2, alpha=0.6, label="path's speed (reference)")
        ax.plot(t, sig("tracker", port_d), "k--", lw=0.8, label="desired (tracker)")
        ax.plot(t, sig(typ, port), "r", lw=0.8, label="actual")
        ax.set_xlabel("time [s]"), ax.set_ylabel(label), ax.legend(fontsize=8), ax.grid(alpha=0.3)
        ax.set_title(title)
        save(fig, name)
    return written
