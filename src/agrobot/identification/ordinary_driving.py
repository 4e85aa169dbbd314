"""``identify LOG --study S`` on ordinary driving: the steps, the verdicts and the results' JSON.

1. The log's steering input (measured wheel angle delta, else the command delta_cmd), speed v and
   gyro yaw_rate (without a gyro: a dual-antenna heading or the GNSS course differenced on its own
   updates, identification.yaw_measurement) on an even clock, cut into segments of driving; every
   third one held out. Where the turns are too gentle for the tyres to matter (the kinematic
   regime, identification.kinematic) the steering map is fitted instead of steps 3-5.
2. Gyro bias from the samples standing still (|v| < 2 cm/s, at least 2 s), else fitted.
3. Linear single-track model (identification.driving) fitted on the fit segments: cornering
   coefficients, delay, lag, offset, gain (command input), bias.
4. Tyre saturation (simplified Magic Formula, friction mu and shape C, components.models.tyre):
   fitted from the linear fit; found when the linear model's held-out misfit grows with |a_y|:
   the extended model wins on BIC by more than 10 and takes ``min_gain`` off the held-out RMS in
   the top third of |a_y|, with mu off its bounds. Reported beside it: how the linear model fitted
   where |a_y| <= 0.15 g (tyres on any ground are linear there) misses beyond, signed by the turn's
   direction (a saturating tyre turns less than it predicts: negative).
5. Verdicts: a parameter on its bound is "not identifiable from this log" (value and bound given);
   every quantity is given with its 95 % interval; the steady-state regression
   (identification.steady_state) is reported beside the dynamic fit. A measured angle's fit is
   tried again with a scale of the turns free in the linear range (gain_apart: a scale read only
   where the refit converges and predicts the held-out segments better; K is not concluded where
   the log cannot tell the two apart, nor where its roll, bank or a_y column tells the turns lean
   on a bank, whose share of them a scale or K would take up: identification.ground_lean); no
   characteristic or critical speed past BEYOND_TOP x the
   log's top speed;
   a gyro bias fitted without a standstill is not concluded (_without_standstill).
"""
from __future__ import annotations


import math
from dataclasses import dataclass, replace

import numpy as np

from agrobot.components.models.tyre import SHAPE_BOUNDS, linear_share_limit
from agrobot.components.models.yaw_dynamics import GRAVITY, PHYSICAL_MODELS, TractorParameters
from agrobot.measurements import LogError
from agrobot.measurements.audit import minimum
from agrobot.measurements.clocks import content_lag
from agrobot.measurements.steering_scale import MIN_CORRELATION, slope_on_turns
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import StudyError
from agrobot.orchestrator.work_progress import Work

from .comparisons import (course_bias, mark_not_concluded, model_steady_state, pair, pair_line, understeer_pair,
                          withheld_understeer)
from agrobot.estimation import Z95, Parameter

from .delay_bound import DELAY_LIMIT, delay_verdict, traded_verdict
from .driving import (ACKERMANN, SMALL_ANGLE, DrivingLog, FitResult, NotEnoughDriving, Segments, YawModel,
                      cut_segments, even_grid, fit, fit_percent, gauss_newton_gain, steady_state_gain,
                      understeer_gradient)
from .ground_lean import lean_column, lean_of_log, turns_lean
from .kinematic import KINEMATIC_LATERAL, NOT_AT_THESE_SPEEDS, kinematic_report, kinematic_summary, lateral_p95
from . import skid_steer
from .steady_turn import is_steady_turn, steady_turn_parts, steady_turn_summary
from .turning import turning
from .steady_state import in_linear_range, steady_windows
from .vehicle import Vehicle
from .axle_friction import axle_friction_fit, first_to_bend
from .yaw_measurement import YawMeasurement, check_sign, with_yaw_rate

LARGE_ANGLE = 0.172           # rad: tan w exceeds w by 1 % (identification.driving.ACKERMANN tried)
MIN_DRIVING = 20.0            # s of scored driving, fit and held-out together
LINEAR_TYRE = 0.15 * 9.81    # m/s2: tyres on any ground (mu >= 0.5) are linear up to here
MIN_EXCITATION = 0.02         # rad/s: std of the yaw rate the steering asks for (v u / L)
STEERING_SCALE_SUSPECT = 5.0     # the yaw rate's slope on v u / L beyond which the angle's scale is doubted
STEERING_SCALE_LARGEST = 100.0   # ... up to which a steering ratio or a unit (57.3 deg/rad) explains it
INPUT_NOTE = {True: "input: the steering command delta_cmd (no measured wheel angle): gain, delay and lag are the "
                    "whole steering chain", False: "input: the measured wheel angle delta"}
STANDSTILL = 0.02             # m/s
SEGMENT = 4.0                 # s
BURN_IN = 1.0                 # s


def cornering_bounds(vehicle: Vehicle) -> tuple[float, float]:
    """Cornering stiffness per unit axle load [1/rad]: 1-30 covers tractors' soft front tyres (4)
    to stiff road and racing tyres (20-25)."""
    return 1.0, 30.0


# a tyre's cornering stiffness per unit load is B C mu of its Magic Formula: a racing slick's mu 2 at a
# peak slip of 0.05 rad (C about 1.5) gives about 60; a fit beyond means something else (a scale)
CORNERING_LIMIT = (0.5, 60.0)
WIDENED_ON_BOUND = ("c_f", "c_r", "friction")


def free_parameters(vehicle: Vehicle, command_input: bool, fit_bias: bool, saturation: bool,
                    relaxation: float | None = None) -> list[Parameter]:
    """``relaxation``: the study's front relaxation length, fitted within x 1/4 .. 4 of it (None: held)."""
    lo, hi = cornering_bounds(vehicle)
    bias = vehicle.gyro_bias_bound or 3.0 * math.pi / 180
    out = [Parameter("c_f", "1/rad", 5.0, lo, hi, limit=CORNERING_LIMIT, meaning="front cornering stiffness / front axle load"),
           Parameter("c_r", "1/rad", 5.0, lo, hi, limit=CORNERING_LIMIT, meaning="rear cornering stiffness / rear axle load"),
           Parameter("delay", "s", 0.1, 0.0, 0.5, limit=DELAY_LIMIT, meaning="steering delay (input to the wheels)"),
           Parameter("lag", "s", 0.1, 0.0, 0.5, meaning="steering first-order lag"),
           Parameter("steer_offset", "rad", 0.02, -0.1, 0.1, meaning="wheel angle the tyres see at zero input")]
    if command_input:
        out.append(Parameter("steer_gain", "1", 0.2, 0.5, 1.5, meaning="wheel angle per commanded angle"))
    if fit_bias:
        out.append(Parameter("gyro_bias", "rad/s", 0.01, -bias, bias, meaning="gyro bias"))
    if relaxation:
        out.append(Parameter("sigma_f", "m", 0.25 * relaxation, 0.25 * relaxation, 4.0 * relaxation,
                             meaning="front tyre relaxation length"))
    if saturation:
        mu_lo, mu_hi = vehicle.friction_range
        out += [Parameter("friction", "1", 0.3, mu_lo, mu_hi, limit=vehicle.physical_limits()["tyre_friction"],
                          meaning="tyre friction coefficient mu (peak force / load)"),
                Parameter("shape", "1", 0.3, *SHAPE_BOUNDS, meaning="Magic Formula shape factor C")]
    return out


def similar_columns(columns, wanted: str) -> list[str]:
    """Columns whose name, lower-cased without separators, is the wanted one's (YawRate, yaw-rate)."""
    key = wanted.replace("_", "").lower()
    return [c for c in map(str, columns) if c != wanted and c.replace("_", "").replace("-", "").replace(" ", "").lower() == key]


def missing_text(frame, needs: dict[str, str], derived: dict[str, str] | None = None) -> str | None:
    """None when every need is met; else what is missing, why, and the columns the log has (``derived``:
    a column made from others, named with its source)."""
    gaps = []
    for col, why in needs.items():
        options = col.split("|")
        if not any(o in frame for o in options):
            near = [s for o in options for s in similar_columns(frame.columns, o)]
            hint = f" (the log has {', '.join(near)}: rename it to {options[0]} if it is that, in SI units)" if near else ""
            gaps.append(f"no {' or '.join(options)} ({why}){hint}")
    if not gaps:
        return None
    derived = derived or {}
    names = [f"{c} ({derived[c]})" if c in derived else str(c) for c in frame.columns]
    return "; ".join(gaps) + f"; the log has {', '.join(names)}"


def study_plant(study) -> tuple[str, TractorParameters]:
    if study is None:
        return "rlf", TractorParameters()
    resolved = resolve(study)
    names = resolved.find(role="yaw_plant")
    if not names:
        raise StudyError(f"{study.path}: no component with role 'yaw_plant' (the vehicle's mass, inertia, axles)")
    p = resolved.parameters(names[0])
    model = p.get("model", "rlf")
    if model not in PHYSICAL_MODELS:
        raise StudyError(f"{study.path}: components.{names[0]}.parameters.model = {model!r}: identification from "
                         f"driving needs a physical single-track model {PHYSICAL_MODELS}")
    return model, TractorParameters.of(p)


def _delay_start(log: DrivingLog, L: float, max_delay: float = 0.5) -> float:
    """Lag of the peak cross-correlation between the gyro and the kinematic yaw rate v u / L."""
    kin = log.v * log.u / L
    moving = log.v > 0.3
    best, lag_best = -np.inf, 0
    for lag in range(int(max_delay / log.h) + 1):
        a, b = kin[: len(kin) - lag], log.r[lag:]
        m = moving[lag:] & (log.run[lag:] == log.run[: len(kin) - lag])
        if m.sum() < 20:
            continue
        c = np.corrcoef(a[m], b[m])[0, 1]
        if c > best:
            best, lag_best = c, lag
    return lag_best * log.h


def _spread(segs: Segments, max_seconds: float, h: float) -> Segments:
    """At most ``max_seconds`` of segments, evenly spread over the log."""
    per = segs.scored.sum(axis=1) * h
    if per.sum() <= max_seconds:
        return segs
    k = max(1, int(len(per) * max_seconds / per.sum()))
    return segs.take(np.unique(np.linspace(0, len(per) - 1, k).round().astype(int)))


def _fitted_part(segs: Segments, max_seconds: float, h: float) -> tuple[Segments, str | None]:
    """(the segments fitted, what was passed over): the segments not held out, at most ``max_seconds``
    of them evenly spread over the log (_spread: the fits' cost grows with the samples)."""
    pool = segs.take(~segs.held_out)
    fitted = _spread(pool, max_seconds, h)
    if len(fitted.idx) == len(pool.idx):
        return fitted, None
    return fitted, (f"fitted on {fitted.seconds * h:.0f} s of the {pool.seconds * h:.0f} s of segments not held out "
                    f"({len(fitted.idx)} of {len(pool.idx)}, evenly spread over the log; cost bound): passed over "
                    f"{(pool.seconds - fitted.seconds) * h:.0f} s ({len(pool.idx) - len(fitted.idx)} segments); "
                    f"--fit-seconds (now {max_seconds:g}) fits more; held out: "
                    f"{segs.take(segs.held_out).seconds * h:.0f} s")


def _bins(a: np.ndarray, res: np.ndarray, edges, signed: bool = False) -> list[dict]:
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (a >= lo) & (a < hi)
        if m.sum() >= 10:
            out.append({"from": float(lo), "to": float(hi), "samples": int(m.sum()),
                        "rms": float(np.sqrt(np.mean(res[m] ** 2)))}
                       | ({"mean_signed": float(res[m].mean())} if signed else {}))
    return out


def _quantity(value, std, unit, bounds=None, at_bound=None, **more) -> dict:
    d = {"value": float(value), "std": float(std), "interval": [float(value - Z95 * std), float(value + Z95 * std)],
         "unit": unit}
    if bounds is not None:
        d["bounds"] = [float(bounds[0]), float(bounds[1])]
        # a positive physical quantity whose 95 % interval reaches zero is not pinned down either
        lo, hi = value - Z95 * std, value + Z95 * std
        vague = (bounds[0] > 0 and not lo > 0) or (lo < bounds[0] and hi > bounds[1])
        d["identifiable"] = at_bound is None and math.isfinite(std) and not vague
        if at_bound:
            d["note"] = (f"not identifiable from this log: ended on its {at_bound} bound "
                         f"{bounds[0] if at_bound == 'lower' else bounds[1]:g} {unit}")
        elif not d["identifiable"]:
            d["note"] = (f"not identifiable from this log: its 95 % interval [{lo:.3g}, {hi:.3g}] {unit} "
                         + ("covers its whole range" if lo < bounds[0] and hi > bounds[1] else "reaches zero"))
    d.update(more)
    return d


def identify_driving(frame, where: str, study=None, min_gain: float = 0.05, max_fit_seconds: float = 300.0,
                     progress=None, max_rate: float = 25.0, course_speed: float | None = None,
                     dynamic: bool = False, wheelbase: float | None = None, geometry: str = "auto", input_hold="auto"):
    """The report (a JSON-able dict); raises NotEnoughDriving or a LogError naming what the log lacks.
    Yaw without a gyro: identification.yaw_measurement (``course_speed``, None: the log's own); the kinematic regime, the
    steering map unless ``dynamic``: identification.kinematic; ``wheelbase``: wheelbase_of; ``geometry``: _steering_geometry;
    ``input_hold``: driving.input_hold."""
    say = progress or (lambda text: None)
    vehicle = Vehicle.of(study)
    model_name, p = study_plant(study)
    L, L_from = wheelbase_of(vehicle, p, wheelbase, study)
    p, L_from = plant_on_wheelbase(p, L, L_from)
    frame, measured = with_yaw_rate(frame, where, course_speed)
    input_name = _steering_input(frame, where, vehicle, measured)
    command = input_name == "delta_cmd"
    log = even_grid(frame, input_name, max_rate=max_rate, update_times=measured.update_times, hold=input_hold)
    log.kernel, log.lean = measured.kernel(log.h), lean_of_log(frame, log)
    check_sign(np.where(log.measured, log.r, np.nan), log.v * log.u, where, measured)
    notes = list(log.notes) + [measured.text, f"wheelbase {L:.3g} m: {L_from}", INPUT_NOTE[command]]
    floor = measured.course_speed if measured.kind == "GNSS course" else 0.0
    min_speed, segs, driven = _enough_driving(log, where, L, input_name, notes, floor)
    say(f"{len(segs.idx)} segments, {driven:.0f} s of driving ({segs.held_out.sum()} held out)")
    if is_steady_turn(log, L, segs, MIN_EXCITATION):
        say("a steady turn at a constant input: the steady-state gain only")
        return _steady_turn(log, segs, (L, L_from), where, input_name, driven, min_speed, vehicle, p, measured, notes)
    p95 = lateral_p95(log, min_speed)
    if p95 < KINEMATIC_LATERAL and not dynamic:
        say("kinematic regime: fitting the steering map")
        return _kinematic(log, segs, (L, L_from), where, model_name, input_name, driven, min_speed, vehicle, p,
                          measured, notes, p95)
    fits = _fit_models(log, segs, vehicle, model_name, p, L, command, min_speed, max_fit_seconds, notes, say, geometry)
    say("judging on the held-out segments")
    held = _judge_saturation(log, fits, min_gain)
    saturation = not held.reasons
    linear, nl, test_segs = fits.linear, fits.nl, fits.test_segs
    gain_check, alike, final, params_json, stiff = _with_gain(log, fits, held, saturation, command, min_speed, L)
    top = float(np.percentile(log.v[log.v >= min_speed], 99))
    pred = held.sims[1] if saturation else held.sims[0]
    K, K_sd, understeer, char = _understeer(final, fits.free, L, alike, top, (gain_check or {}).get("span"))
    g, g_sd = _turn_gain(final)
    linear_range = _linear_range(saturation, nl, log, min_speed)
    windows, ss, twin = _steady_check(log, fits.model, final.values, L, min_speed, linear_range["value"], command)
    checks = physical_checks(frame, log, fits.model, final.values, test_segs)
    comparisons = independent_estimates(frame, log, test_segs, held.r_test, pred, understeer, ss, params_json["delay"],
                                        params_json.get("gyro_bias"), linear_range, L, min_speed,
                                        _low_range_understeer(fits, saturation), twin)
    understeer, char = withheld_understeer(understeer, char, comparisons,
                                           lambda k, sd: characteristic_speed(k, sd, L, top_speed=top))
    K, K_sd = understeer["value"], understeer["std"]
    report = {
        "method": "output error, single-track model LPV in speed, segments held out",
        "source": where, "model": model_name, "input": input_name,
        "final_model": "tyre_saturation" if saturation else "linear",
        "steering_geometry": "tan" if fits.model.geometry == ACKERMANN else "w",
        "steering_geometry_choice": fits.model.geometry_choice, "samples_per_second": 1 / log.h, "seconds_driven": driven,
        "segments": {"fit": int(len(fits.fit_segs.idx)), "held_out": int(len(test_segs.idx)), "length_s": SEGMENT,
                     "burn_in_s": BURN_IN, "min_speed": min_speed},
        "vehicle": {**_vehicle_json(vehicle, (L, L_from), p), "axle_loads": list(fits.loads)},
        "understeer_gradient": understeer,
        "characteristic_speed": char,
        **({"steering_gain_check": gain_check} if gain_check else {}),
        "delay": params_json["delay"],
        "held_out_fit": _held_out_fit(log, test_segs, held, pred, study),
        "cornering_stiffness": stiff,
        "parameters": params_json,
        "steady_state_gain": _steady_gain(log, min_speed, (K, K_sd, understeer), L, (g, g_sd), notes),
        "linear_range": linear_range,
        "tyre_saturation": _tyre_json(held, nl, fits.free_nl, saturation),
        "residual_by_lateral_acceleration": _residual_bins(held),
        "steady_state_regression": _steady_json(ss, vehicle, windows, params_json["steer_offset"]),
        "not_identifiable": [f"{k}: {v['note']}" for k, v in params_json.items() if v.get("note")],
        "comparisons": mark_not_concluded(comparisons, understeer, params_json),
        "physical_checks": checks,
        "notes": notes,
        "yaw_measurement": measured.as_dict(),
        "regime": _dynamic_regime(p95),
    }
    report["_plot"] = {"log": log, "model": fits.model, "test": test_segs, "test_pred": pred, "linear": linear.values,
                       "nl": nl.values, "final": final.values, "windows": windows, "K": K, "K_sd": K_sd, "L": L, "g": g}
    return report


def _dynamic_regime(p95: float) -> dict:
    """The report's regime of a log past the kinematic one: 95 % of its lateral accelerations |v r|."""
    return {"kinematic": False, "lateral_acceleration_p95": p95, "threshold": KINEMATIC_LATERAL,
            "says": f"dynamic regime: 95 % of |v r| up to {p95:.2g} m/s2 (kinematic below {KINEMATIC_LATERAL:g})"}


def _vehicle_json(vehicle, wheelbase: tuple, p) -> dict:
    """The report's vehicle: its class, the wheelbase identify stood on and where it came from, the plant's
    mass, yaw inertia and axle distances."""
    L, L_from = wheelbase
    return {"class": vehicle.kind, "wheelbase": L, "wheelbase_from": L_from, "m": p.m, "I": p.I, "l_f": p.l_f, "l_r": p.l_r}


def _kinematic(log, segs, wheelbase, where, model_name, input_name, driven, min_speed, vehicle, p, measured, notes,
               p95) -> dict:
    """The report in the kinematic regime (identification.kinematic): the steering map in place of
    the tyres; the dynamic fit is what ``dynamic=True`` asks for. ``wheelbase``: (L, where from)."""
    L, L_from = wheelbase
    fixed, bias_info = _standstill_bias(log)
    part = kinematic_report(log, segs, L, fixed, p95)
    smap = part["steering_map"]
    params = {k: smap[k] for k in ("gain_left", "gain_right", "steer_offset", "delay", "gyro_bias") if k in smap}
    params["steer_gain"] = smap["gain"]                   # the mean of both sides
    if bias_info:
        params["gyro_bias"] = {**bias_info, "identifiable": True}
    return {"method": "kinematic model r = v tan(delta) / L, segments held out", "source": where, "model": "kinematic",
            "input": input_name, "final_model": "kinematic", "steering_geometry": "tan",
            "steering_geometry_choice": {"value": "tan", "how": "kinematic", "passed_over": "w"}, "samples_per_second": 1 / log.h, "seconds_driven": driven,
            "segments": {"fit": int((~segs.held_out).sum()), "held_out": int(segs.held_out.sum()), "length_s": SEGMENT,
                         "burn_in_s": BURN_IN, "min_speed": min_speed},
            "vehicle": _vehicle_json(vehicle, (L, L_from), p),
            **{k: v for k, v in part.items() if k != "_plot"}, "delay": smap["delay"], "parameters": params,
            "not_identifiable": [f"{k}: {v['note']}" for k, v in params.items() if v.get("note")],
            "linear_range": {"value": float("nan"), "note": part["regime"]["says"]},
            "steady_state_regression": {"note": part["regime"]["says"]}, "comparisons": [], "physical_checks": {},
            "notes": notes, "yaw_measurement": measured.as_dict(), "_plot": part["_plot"]}


def _steady_turn(log, segs, wheelbase, where, input_name, driven, min_speed, vehicle, p, measured, notes) -> dict:
    """The report of a steady turn at a constant input (identification.steady_turn): its
    steady-state gain, the dynamics not identifiable."""
    L, L_from = wheelbase
    _, bias = _standstill_bias(log)
    part = steady_turn_parts(log, L, segs, bias, measured.kind == "gyro")
    nan = float("nan")
    return {"method": "steady-state gain r / (v tan(u) / L) of a steady turn", "source": where, "model": "steady turn",
            "input": input_name, "final_model": "steady_turn", "samples_per_second": 1 / log.h, "seconds_driven": driven,
            "segments": {"fit": int(len(segs.idx)), "held_out": 0, "length_s": SEGMENT, "burn_in_s": BURN_IN,
                         "min_speed": min_speed},
            "vehicle": _vehicle_json(vehicle, (L, L_from), p),
            **{k: v for k, v in part.items() if k != "says"}, "delay": part["parameters"]["delay"],
            "regime": {"kinematic": False, "steady_turn": True, "says": part["says"]},
            "held_out_fit": {"value": nan, "std": nan, "interval": [nan, nan], "unit": "%", "per_segment": [],
                             "linear_model": nan, "saturation_model": nan, "note": part["says"]},
            "not_identifiable": [f"{k}: {v['note']}" for k, v in part["parameters"].items() if v.get("note")],
            "linear_range": {"value": nan, "note": part["says"]}, "steady_state_regression": {"note": part["says"]},
            "comparisons": [], "physical_checks": {}, "notes": notes, "yaw_measurement": measured.as_dict(),
            "_plot": {}}


def wheelbase_of(vehicle: Vehicle, p: TractorParameters, given: float | None, study) -> tuple[float, str]:
    """(L [m], where it comes from): the one given with the recording (--wheelbase; or ``given`` a
    (value, where from) pair: from_log.recorded_wheelbase), else the study's
    [vehicle] wheelbase, else its yaw plant's l_f + l_r (the paper tractor's without a study)."""
    where = getattr(study, "path", None)
    given, told = given if isinstance(given, tuple) else (given, "given with the recording (--wheelbase)")
    if given:
        passed = (f"; the study's {vehicle.wheelbase:.3g} m passed over" if vehicle.wheelbase and
                  abs(vehicle.wheelbase - given) > 1e-9 else "")
        return float(given), f"{told}{passed}"
    if vehicle.wheelbase:
        return float(vehicle.wheelbase), f"the [vehicle] table of {where}"
    if study is not None:
        return p.l_f + p.l_r, f"l_f + l_r of the yaw plant of {where} (--wheelbase gives the vehicle's)"
    return p.l_f + p.l_r, "the paper tractor's l_f + l_r: no study and no --wheelbase given (either gives the vehicle's)"


def plant_on_wheelbase(p: TractorParameters, L: float, L_from: str) -> tuple[TractorParameters, str]:
    """The yaw plant's axles on the wheelbase used: l_f + l_r scaled to L where they differ by more
    than 1 % (the study's l_f / (l_f + l_r) kept), so that the dynamic fit's K = m (l_r/C_f - l_f/C_r) / L
    and the steady turns' v tan(u) / L stand on one wheelbase; said in the wheelbase's source."""
    plant = p.l_f + p.l_r
    if abs(plant - L) <= 0.01 * L:
        return p, L_from
    k = L / plant
    scaled = replace(p, l_f=p.l_f * k, l_r=p.l_r * k)
    return scaled, (f"{L_from}; the yaw plant's l_f + l_r ({plant:.3g} m) scaled to it: l_f {scaled.l_f:.3g} m, "
                    f"l_r {scaled.l_r:.3g} m")


def _steering_input(frame, where: str, vehicle: Vehicle, measured: YawMeasurement | None = None) -> str:
    """The log's steering input: the measured wheel angle ``delta``, else the command ``delta_cmd``;
    raises when the vehicle has no yaw dynamics to identify or the log lacks a column it needs
    (a torque-commanded steering needs the measured angle)."""
    if vehicle.steering == "none" or vehicle.drive != "ackermann":
        why = vehicle.not_applicable().get("yaw")
        raise NotEnoughDriving(f"{where}: the yaw dynamics are not identified: {why}")
    gap = missing_text(frame, {"yaw_rate": "the gyro's yaw rate is the output fitted; without a gyro, a dual-antenna "
                                           "heading 'heading' [rad] or positions x, y for the GNSS course",
                               "delta|delta_cmd": "a steering angle, measured or commanded, is the input; a skid-"
                                                  "steered vehicle's is a turn rate, odom_yaw_rate or turn_rate_cmd "
                                                  "[rad/s]: --signal 'odom_yaw_rate=/odom.twist.twist.angular.z'",
                               "v": "the speed schedules the model"},
                       None if measured is None or measured.kind == "gyro" else
                       {"yaw_rate": f"derived from the {measured.kind}, not logged"})
    if gap:
        raise LogError(f"{where}: identification from driving not possible: {gap}")
    if vehicle.steering == "torque" and "delta" not in frame:
        raise NotEnoughDriving(f"{where}: the steering is commanded in torque (vehicle.steering = 'torque') and the "
                               f"log has no measured wheel angle delta: delta_cmd is not an angle the wheels follow")
    return "delta" if "delta" in frame else "delta_cmd"


def _enough_driving(log: DrivingLog, where: str, L: float, input_name: str, notes: list[str], floor: float = 0.0):
    """(min_speed, segments, seconds driven): the log cut into segments of driving above
    max(0.2, floor, 0.1 x the 90th percentile of |v|); raises NotEnoughDriving below MIN_DRIVING s (past
    its floor, measurements.audit.minimum; above it a note), without two fit and one held-out
    segment, or when the steering asks for less than MIN_EXCITATION rad/s of yaw rate (std of v u / L)."""
    min_speed = max(0.2, floor, 0.1 * float(np.percentile(np.abs(log.v), 90)))
    segs = cut_segments(log, min_speed, SEGMENT, BURN_IN)
    driven = segs.seconds * log.h
    excitation = float(np.std((log.v * log.u / L)[log.v >= min_speed])) if np.any(log.v >= min_speed) else 0.0
    if driven < MIN_DRIVING:               # the nominal length is guidance down to its floor (measurements.audit)
        try:
            notes.append(minimum(driven, MIN_DRIVING, f"the driving (v >= {min_speed:.2g} m/s, no clock gap, "
                                                      f"stretches of 1 s or more)"))
        except LogError as exc:
            raise NotEnoughDriving(f"{where}: {exc}: record {MIN_DRIVING - driven:.0f} s more of driving with turns") \
                from None
    if segs.held_out.sum() < 1 or (~segs.held_out).sum() < 2:
        raise NotEnoughDriving(f"{where}: {driven:.1f} s of driving (v >= {min_speed:.2g} m/s, no clock gap, stretches of "
                               f"1 s or more) in {len(segs.idx)} segment(s); identification needs at least "
                               f"{MIN_DRIVING:g} s in 3 segments (two to fit, one held out): record "
                               f"{max(MIN_DRIVING - driven, 3 * SEGMENT - driven, 0):.0f} s more of driving with turns")
    _steering_scale_check(log, where, input_name, excitation, log.v >= min_speed, L)   # at any excitation
    if excitation < MIN_EXCITATION and not is_steady_turn(log, L, segs, MIN_EXCITATION):
        raise NotEnoughDriving(f"{where}: the steering hardly moves: it asks for {excitation:.3g} rad/s of yaw rate "
                               f"(std of v {input_name} / L); identification needs {MIN_EXCITATION} rad/s or more: "
                               f"drive turns and slaloms (for example +-{math.degrees(2 * MIN_EXCITATION * L / max(np.median(log.v), 0.5)):.1f} deg "
                               f"of steering at {max(np.median(log.v), 0.5):.2g} m/s)")
    return min_speed, segs, driven


def _steering_scale_check(log: DrivingLog, where: str, input_name: str, excitation: float, moving, L: float) -> None:
    """Raises NotEnoughDriving naming the steering's scale when the measured yaw rate moves
    (std >= MIN_EXCITATION) and its slope on v u / L over the turns (measurements.steering_scale.
    slope_on_turns, the import's rule, over the ``moving`` samples measured; correlation at least
    MIN_CORRELATION) is STEERING_SCALE_SUSPECT to STEERING_SCALE_LARGEST: the angle is not the road
    wheel's (a steering ratio divided into a road-wheel angle, degrees for radians), not a steering
    that hardly moves; beyond that scale the input does not move."""
    seen = moving if log.measured is None else moving & log.measured
    answer = float(np.std(log.r[seen])) if seen.any() else 0.0
    slope = slope_on_turns(log.v, log.u, log.r, seen, L) if answer >= MIN_EXCITATION else None
    if slope is None or slope[1] < MIN_CORRELATION or not STEERING_SCALE_SUSPECT <= slope[0] <= STEERING_SCALE_LARGEST:
        return
    raise NotEnoughDriving(f"{where}: the yaw rate moves {answer:.3g} rad/s (std while driving), "
                           f"{slope[0]:.3g} times what v {input_name} / L asks for "
                           f"({excitation:.3g} rad/s std; the turns' slope, correlation {slope[1]:.2f}): {input_name} is "
                           f"not the road-wheel angle it should be: a "
                           f"steering ratio divided into an angle that is the road wheel's already (a --steering-ratio "
                           f"given is taken as given, the study's only where the turns say the angle is the "
                           f"handwheel's; --steering-ratio 1 keeps the angle as recorded), an angle in other units, or not the steering")


@dataclass
class _Fits:
    """identify_driving's fits on the fit segments: the linear model everywhere and where the tyres
    are linear (|a_y| <= LINEAR_TYRE; the same fit when that part is short), the tyre-saturation
    model; the gyro bias standing still (None: fitted)."""
    model: YawModel
    loads: tuple
    free: list[Parameter]
    free_nl: list[Parameter]
    fit_segs: Segments
    test_segs: Segments
    linear: FitResult
    linear_low: FitResult
    nl: FitResult
    bias_info: dict | None


def _standstill_bias(log: DrivingLog) -> tuple[dict[str, float], dict | None]:
    """(fixed values, the bias's quantity): the gyro bias as the mean reading over the samples
    standing still (|v| < STANDSTILL, at least 2 s; its std error with one independent sample per
    0.5 s), else nothing fixed (the bias is fitted)."""
    if log.update_times is not None:           # a yaw rate from a heading or a course: no gyro, no bias
        return {"gyro_bias": 0.0}, None
    still = np.abs(log.v) < STANDSTILL
    fixed: dict[str, float] = {}
    bias_info = None
    if still.sum() * log.h >= 2.0:
        rs = log.r[still]
        b, b_sd = float(rs.mean()), float(rs.std() / math.sqrt(max(1.0, still.sum() * log.h / 0.5)))
        fixed["gyro_bias"] = b
        bias_info = _quantity(b, b_sd, "rad/s", how=f"mean gyro reading over {still.sum() * log.h:.1f} s standing still")
    return fixed, bias_info


def _fit_models(log: DrivingLog, segs: Segments, vehicle: Vehicle, model_name: str, p: TractorParameters, L: float,
                command: bool, min_speed: float, max_fit_seconds: float, notes: list[str], say,
                geometry: str = "auto") -> _Fits:
    """The linear fit from the study's cornering coefficients per unit load (clipped to the
    vehicle's bounds) and the delay of the peak cross-correlation (_delay_start); the linear fit
    again where |a_y| <= LINEAR_TYRE when both parts are long enough; the tyre-saturation fit from
    the linear one, the friction started near the data's top |a_y| / g, else near its upper bound;
    a friction per axle from that fit where it can win (axle_friction.axle_friction_fit)."""
    fixed, bias_info = _standstill_bias(log)
    relaxation = float(p.sigma_f) if model_name != "bicycle" else None      # fitted: held, it pulls K
    free = free_parameters(vehicle, command, "gyro_bias" not in fixed, saturation=False, relaxation=relaxation)
    Fz = YawModel(model_name, p, log, segs).loads
    lo, hi = cornering_bounds(vehicle)
    start = {"c_f": float(np.clip(p.C_f / Fz[0], lo, hi)), "c_r": float(np.clip(p.C_r / Fz[1], lo, hi)),
             "delay": _delay_start(log, L), "lag": 0.05, "steer_offset": 0.0, "steer_gain": 1.0, "gyro_bias": 0.0,
             "sigma_f": float(p.sigma_f)}
    model = YawModel(model_name, p, log, segs, min_sim_speed=max(min_speed, 0.3))
    fit_segs, bound = _fitted_part(segs, max_fit_seconds, log.h)
    test_segs = segs.take(segs.held_out)
    if bound:
        notes.append(bound)
        say(bound)
    with Work(say, "fitting the vehicle models (linear, linear range, tyre saturation)", 3, "fits") as work:
        say("fitting the linear model")
        linear = _steering_geometry(model, lambda x0: fit(model, free, x0, fixed, fit_segs), start, fit_segs, notes,
                                    geometry)
        work.step()
        a_fit = np.abs(log.a_y[fit_segs.idx])
        low = a_fit <= LINEAR_TYRE
        if (low & fit_segs.scored).sum() * log.h >= 0.5 * MIN_DRIVING and (~low & fit_segs.scored).sum() * log.h >= 5.0:
            say(f"fitting the linear model where |a_y| <= {LINEAR_TYRE:g} m/s2")
            linear_low = fit(model, free, linear.values, fixed, fit_segs, mask=low)
            work.step()
        else:
            linear_low = linear
        say("fitting the tyre-saturation model")
        free_nl = free_parameters(vehicle, command, "gyro_bias" not in fixed, saturation=True, relaxation=relaxation)
        ay_fit = np.abs(log.a_y[fit_segs.idx][fit_segs.scored])
        mu0 = float(np.clip(1.25 * np.percentile(ay_fit, 99) / GRAVITY, *vehicle.friction_range))
        nl = None
        for mu_start in (mu0, 0.9 * vehicle.friction_range[1]):      # near the data's top; else nearly linear
            trial = fit(model, free_nl, {**linear.values, "friction": mu_start, "shape": 1.3}, fixed, fit_segs)
            work.step()
            if nl is None or trial.rss_total < nl.rss_total:
                nl = trial
            if trial.rss_total <= linear.rss_total and not trial.at_bound(free_nl[-2]):
                break
        nl, free_nl = axle_friction_fit(lambda free_a, start_a, n: fit(model, free_a, start_a, fixed, fit_segs, max_nfev=n),
                                        lambda free_a, start_a, added: gauss_newton_gain(model, free_a, start_a, fixed, fit_segs, added),
                                        nl, free_nl, notes)
    linear, free = widened_refit(model, linear, free, fixed, fit_segs, notes, say)
    nl, free_nl = widened_refit(model, nl, free_nl, fixed, fit_segs, notes, say)
    return _Fits(model, Fz, free, free_nl, fit_segs, test_segs, linear, linear_low, nl, bias_info)


def widened_refit(model, result: FitResult, free: list[Parameter], fixed: dict, segs: Segments, notes: list[str],
                  say) -> tuple[FitResult, list[Parameter]]:
    """A fit whose WIDENED_ON_BOUND parameters ended on a bound of the class that is not their
    physical limit (Parameter.limit), fitted again with that bound moved to the limit: a value on a
    bound is never concluded. One that runs to the limit too is put back on the class's bound (not
    identifiable, said why) and the others fitted again without it; the wider fit stands when it
    fits the segments as well or better."""
    wide = {p.name: p.widened(result.values[p.name]) for p in free if p.name in WIDENED_ON_BOUND and result.at_bound(p)}
    wide = {k: w for k, w in wide.items() if w is not None}
    runaway = []
    while wide:
        moved = ", ".join(f"{k} {result.values[k]:.3g} to [{w.lower:.3g}, {w.upper:.3g}]" for k, w in wide.items())
        say(f"fitted again with bounds widened to their physical limits: {moved}")
        free_wide = [wide.get(p.name, p) for p in free]
        again = fit(model, free_wide, result.values, fixed, segs)
        ran = [k for k, w in wide.items() if again.at_bound(w)]
        if not ran and again.rss_total <= result.rss_total:
            notes.append(f"ended on the class's bounds, fitted again within their physical limits: {moved} (now "
                         + ", ".join(f"{k} {again.values[k]:.3g}" for k in wide) + ")" + _ran_to(runaway))
            return again, free_wide
        runaway += ran
        wide = {k: w for k, w in wide.items() if k not in ran} if ran else {}
    if runaway and f"ended on the class's bounds{_ran_to(runaway)}" not in notes:
        notes.append(f"ended on the class's bounds{_ran_to(runaway)}")
    return result, free


def _ran_to(names: list[str]) -> str:
    return (f"; {', '.join(names)} ran to {'its' if len(names) == 1 else 'their'} physical limit too when widened: "
            f"kept on the class's bound, not identifiable from this log" if names else "")


def _steering_geometry(model: YawModel, fit_linear, start: dict, segs: Segments, notes: list[str],
                       choice: str = "auto") -> FitResult:
    """The linear fit (``fit_linear(start)``) under the steering geometry ``choice``: "w" (small
    angle), "tan" (driving.ACKERMANN: an Ackermann machine turns on r = v tan w / L when its tyres
    do not slip) or "auto": where the wheel angle reaches LARGE_ANGLE (tan w exceeds w by 1 %)
    both, the one with the smaller residual sum of squares (same parameters) kept on ``model`` and
    said with what it passed over; below it w (the two are alike). The choice also goes on
    ``model.geometry_choice``, {value, how (option|small_angles|compared), reach [rad], threshold,
    rms [rad/s] by geometry, passed_over}: the report's steering_geometry_choice."""
    if choice != "auto":
        model.geometry = ACKERMANN if choice == "tan" else SMALL_ANGLE
        model.geometry_choice = {"value": choice, "how": "option", "passed_over": "w" if choice == "tan" else "tan"}
        notes.append(f"steering geometry: the yaw plant is driven by {choice} (--steering-geometry {choice})")
        return fit_linear(start)
    small = fit_linear(start)
    u = np.abs(model.log.u[segs.idx][segs.scored])
    reach = float(np.percentile(u, 99)) if len(u) else 0.0
    model.geometry_choice = {"value": "w", "how": "small_angles", "reach": reach, "threshold": LARGE_ANGLE,
                             "passed_over": "tan"}
    if reach < LARGE_ANGLE:
        return small
    model.geometry = ACKERMANN
    ackermann = fit_linear(small.values)
    keep = ackermann if ackermann.rss_total < small.rss_total else small
    model.geometry = ACKERMANN if keep is ackermann else SMALL_ANGLE
    rms = {k: math.sqrt(f.rss_total / max(f.n_total, 1)) for k, f in (("tan w", ackermann), ("w", small))}
    chosen, other = ("tan w", "w") if keep is ackermann else ("w", "tan w")
    model.geometry_choice |= {"value": chosen.removesuffix(" w"), "how": "compared", "passed_over": other.removesuffix(" w"),
                              "rms": {"tan": rms["tan w"], "w": rms["w"]}}
    notes.append(f"steering geometry: the wheel angle reaches {reach:.2g} rad (99th percentile), where tan w exceeds w "
                 f"by {100 * (math.tan(reach) / reach - 1):.0f} %: the yaw plant is driven by {chosen} (yaw RMS "
                 f"{rms[chosen]:.3g} rad/s); passed over: {other} (RMS {rms[other]:.3g} rad/s); --steering-geometry "
                 f"w|tan sets it")
    return keep


@dataclass
class _HeldOut:
    """The three fits simulated on the held-out segments (linear, saturation, linear in the linear
    range), their residuals on the scored samples, and the verdict's numbers on tyre saturation."""
    r_test: np.ndarray
    sims: list
    a_test: np.ndarray
    y: np.ndarray
    res_lin: np.ndarray
    res_nl: np.ndarray
    res_low: np.ndarray
    hi_q: float
    growth: float
    gain_top: float
    gain_all: float
    dbic: float
    reasons: list[str]


def _judge_saturation(log: DrivingLog, fits: _Fits, min_gain: float) -> _HeldOut:
    """Tyre saturation is found when dBIC (saturation - linear) < -10, the held-out RMS in the top
    third of |a_y| falls by ``min_gain`` and the friction is off its bounds (``reasons``: what
    failed). Beside it, ``growth``: the linear model's signed misfit at high |a_y| against its
    standard error (n_eff from the fit's autocorrelation)."""
    linear, linear_low, nl, test_segs = fits.linear, fits.linear_low, fits.nl, fits.test_segs
    r_test = log.r[test_segs.idx]
    sims = fits.model.simulate_many([linear.values, nl.values, linear_low.values], test_segs)
    a_test = np.abs(log.a_y[test_segs.idx])[test_segs.scored]
    y = r_test[test_segs.scored]
    res_lin, res_nl = y - sims[0][test_segs.scored], y - sims[1][test_segs.scored]
    hi_q = float(np.percentile(a_test, 100 * 2 / 3)) if len(a_test) else 0.0
    top = a_test >= hi_q
    res_low = y - sims[2][test_segs.scored]
    rms = lambda x: float(np.sqrt(np.mean(x ** 2))) if len(x) else float("nan")  # noqa: E731
    # systematic misfit at high |a_y|: the residual of the linear model fitted where the tyres are
    # linear, signed by the turn's direction (a saturating tyre turns less than the linear one
    # predicts: negative), against its standard error with the autocorrelation's n_eff
    signed = (res_low * np.sign(y))[a_test > max(LINEAR_TYRE, 0.0)] if linear_low is not linear else (res_lin * np.sign(y))[top]
    n_top = max(2.0, len(signed) * linear.n_eff_total / max(linear.n_total, 1))
    growth = float(signed.mean() / (signed.std() / math.sqrt(n_top))) if len(signed) > 2 and signed.std() > 0 else 0.0
    gain_top = 1 - rms(res_nl[top]) / max(rms(res_lin[top]), 1e-12)
    gain_all = 1 - rms(res_nl) / max(rms(res_lin), 1e-12)
    dbic = nl.bic - linear.bic
    mu_param = next(q for q in fits.free_nl if q.name == "friction")
    reasons = []
    if dbic >= -10:
        reasons.append(f"dBIC {dbic:.1f} is not below -10")
    if gain_top < min_gain:
        reasons.append(f"held-out RMS at high |a_y| falls by {100 * gain_top:.1f} % < {100 * min_gain:.0f} %")
    # on its upper bound (the class's highest) the log reaches the curve's bend but not its peak: the
    # saturation stands with the friction "at least" that; on its lower bound it is no estimate
    if nl.at_bound(mu_param) == "lower" or (nl.at_bound(mu_param) and reasons):
        reasons.append(f"the friction ended on its {nl.at_bound(mu_param)} bound: not identifiable from this log")
    return _HeldOut(r_test, sims, a_test, y, res_lin, res_nl, res_low, hi_q, growth, gain_top, gain_all, dbic, reasons)


def _held_out_fit(log: DrivingLog, test_segs: Segments, held: _HeldOut, pred, study) -> dict:
    """The final model's held-out fit, 100 (1 - |y - y_model| / |y - mean y|), overall and per
    segment, with a 95 % interval from a percentile bootstrap over the held-out segments (400
    draws, seeded by the study)."""
    r_test, y, sims = held.r_test, held.y, held.sims
    per_segment = []
    for i in range(len(test_segs.idx)):
        m = test_segs.scored[i]
        if m.sum() >= 10:
            per_segment.append({"t_start": float(log.t[test_segs.idx[i][m][0]]), "seconds": float(m.sum() * log.h),
                                "fit_percent": fit_percent(r_test[i][m], pred[i][m]),
                                "rms": float(np.sqrt(np.mean((r_test[i][m] - pred[i][m]) ** 2)))})
    overall = fit_percent(y, pred[test_segs.scored])
    pieces = [(r_test[i][test_segs.scored[i]], pred[i][test_segs.scored[i]]) for i in range(len(test_segs.idx))
              if test_segs.scored[i].sum() >= 10]
    rng = np.random.default_rng(getattr(getattr(study, "study", None), "seed", 0) or 0)
    picks = [np.bincount(rng.integers(len(pieces), size=len(pieces)), minlength=len(pieces))
             for _ in range(400 if len(pieces) > 1 else 0)]
    boot = list(_bootstrap_fit(pieces, np.array(picks))) if picks else []
    fit_lo, fit_hi = (float(np.percentile(boot, 2.5)), float(np.percentile(boot, 97.5))) if boot else (overall, overall)
    fit_sd = float(np.std(boot)) if boot else 0.0
    return {"value": overall, "std": fit_sd, "interval": [fit_lo, fit_hi],
            "unit": "%", "how": "100 (1 - |y - y_model| / |y - mean y|) on the held-out samples; "
            "interval: 2.5-97.5 % of a bootstrap over the held-out segments", "per_segment": per_segment,
            "linear_model": fit_percent(y, sims[0][test_segs.scored]),
            "saturation_model": fit_percent(y, sims[1][test_segs.scored])}


def _bootstrap_fit(pieces: list[tuple[np.ndarray, np.ndarray]], counts: np.ndarray) -> np.ndarray:
    """fit_percent of each bootstrap draw (a row of ``counts``: how often each held-out piece (y,
    y_model) is drawn), from the pieces' sums: with n, S = sum y, Q = sum y^2 and E = sum (y - y_model)^2
    summed over the draw, 100 (1 - sqrt(E) / sqrt(Q - S^2 / n))."""
    sums = np.array([(len(y), y.sum(), y @ y, (y - m) @ (y - m)) for y, m in pieces])
    n, S, Q, E = (counts @ sums).T
    den = np.sqrt(np.maximum(Q - S * S / n, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, 100.0 * (1.0 - np.sqrt(E) / den), np.nan)


def _final_parameters(log: DrivingLog, fits: _Fits, held: _HeldOut, saturation: bool):
    """(the final fit, its parameters, the cornering stiffnesses): a delay ended on its zero bound is
    fitted again with the delay searched below zero (identification.delay_bound), judged there, and
    its held-out prediction put in ``held.sims``; the first fit stays when the delay is not decided
    because the response's own parameters sit on their bounds."""
    first, first_free = (fits.nl, fits.free_nl) if saturation else (fits.linear, fits.free)
    delay = next(p for p in first_free if p.name == "delay")
    wide = delay.widened(first.values["delay"])
    if wide is None:
        return (first, *_parameters(first, first_free, fits))
    # a lag on its zero bound (its physical limit) stays there: a negative delay and a lag trade off
    on_zero = [p for p in first_free if p.name == "lag" and first.at_bound(p) == "lower"]
    before = _parameters(first, first_free, fits)
    fixed = {**_standstill_bias(log)[0], **{p.name: p.lower for p in on_zero}}
    free = [wide if p is delay else p for p in first_free if p not in on_zero]
    final = min((fit(fits.model, free, {**first.values, "delay": d}, fixed, fits.fit_segs)     # from the bound and
                 for d in (first.values["delay"], -0.1)), key=lambda f: f.rss_total)          # from beyond it
    # a relaxation length held on its bound lags (sigma_f / v) or leads the model as much as a delay does
    shaping = [p.name for p in free if p.name in ("c_f", "c_r", "steer_gain", "sigma_f") and final.at_bound(p)]
    verdict = delay_verdict(_parameters(final, free, fits)[0]["delay"], shaping)
    tau, lag = final.values["delay"], final.values.get("lag", 0.0)
    if not shaping and not on_zero and tau < 0 < lag:       # a lead traded against the lag: judged on tau + T
        verdict = traded_verdict(_parameters(final, free, fits)[0]["delay"], before[0]["delay"], lag, tau + lag,
                                 final.interval_of({"delay": 1.0, "lag": 1.0}))
    if shaping or verdict["verdict"] == "below its upper limit" and "net_delay" in verdict:
        return first, {**before[0], "delay": verdict}, before[1]
    params_json, stiff = _parameters(final, free, fits)
    params_json["delay"] = verdict
    for p in on_zero:
        params_json[p.name] = {**before[0][p.name], "note": before[0][p.name]["note"] + "; held there while the delay "
                               "was searched below zero"}
    held.sims[1 if saturation else 0] = fits.model.simulate(final.values, fits.test_segs)
    return final, params_json, stiff


def _parameters(final: FitResult, free: list[Parameter], fits: _Fits) -> tuple[dict, dict]:
    """(parameters, cornering stiffnesses): every fitted parameter of the final model with its 95 %
    interval and bounds, the standing-still gyro bias; each axle's stiffness C = c F_z [N/rad]
    from its coefficient per unit load."""
    params_json = {}
    for q in free:
        params_json[q.name] = _quantity(final.values[q.name], final.std(q.name), q.unit, (q.lower, q.upper),
                                        final.at_bound(q), meaning=q.meaning)
    if fits.bias_info:
        params_json["gyro_bias"] = {**fits.bias_info, "bounds": None, "identifiable": True}
    lag = params_json.get("lag", {})
    if "steer_gain" not in final.names and "lower bound" in lag.get("note", ""):
        lag["note"] += (": the input is a measured wheel angle, with no steering actuator after it to lag (the "
                        "tyres' own lag is sigma_f): 0 s is its physical limit, not told from any lag the fit "
                        "has no use for")
    stiff = {}
    for key, q, load in (("front", "c_f", fits.loads[0]), ("rear", "c_r", fits.loads[1])):
        entry = params_json[q]
        stiff[key] = {**_quantity(entry["value"] * load, entry["std"] * load, "N/rad"),
                      "identifiable": entry["identifiable"], "per_axle_load": entry,
                      **({"note": entry["note"]} if "note" in entry else {})}
    return params_json, stiff


def one_speed(log: DrivingLog, min_speed: float, bias: float = 0.0) -> str | None:
    """Why a fitted steering gain g and an understeer gradient K are not told apart (None: they
    are): the steady yaw rate g v / (L + K v^2) of turns at one speed (the 90th percentile of the
    turning speeds under 1.5 x the 10th, steady_state.regression's rule) fixes only their ratio.
    Turning: where the path curvature clears the log's own turns' share and noise (turning; ``bias``:
    the gyro's)."""
    moving = (log.v >= min_speed) & (np.ones(len(log.v), bool) if log.measured is None else log.measured)
    turns, limit = turning(log.h, log.v, log.r, moving, bias)
    if turns.sum() < 10:
        return None
    lo, hi = np.percentile(log.v[turns], [10, 90])
    if hi >= 1.5 * lo:
        return None
    return (f"one speed ({lo:.2g}-{hi:.2g} m/s, 10th to 90th percentile of the turns, where the path curvature |r / v| "
            f"exceeds a quarter of the log's tight turns', {limit:.2g} 1/m, and its noise): a steering gain (or a scale of the turns) "
            f"and an understeer gradient give the same yaw rate g v / (L + K v^2) there")


def _understeer(final: FitResult, free: list[Parameter], L: float, alike: str | None = None,
                top_speed: float = math.inf, span: list[float] | None = None):
    """(K, its std, K's quantity, the characteristic or critical speed): K = (1/c_f - 1/c_r) / g,
    its std by the delta method on the fit's covariance; v_ch = sqrt(L / |K|). ``alike``: why the
    log cannot tell K from a steering gain (one_speed, gain_apart), then K is not identifiable;
    ``top_speed``: the log's (characteristic_speed); ``span``: K's 95 % interval widened to it
    (gain_apart: the fits with the turns' scale at 1 and free)."""
    K, K_sd = _k_of(final)
    if span:
        K_sd = max(K - span[0], span[1] - K) / Z95
    # K needs one axle's stiffness off its bound (K = 1/(g c_f) as c_r grows without bound); its
    # interval then says how well the log pins it
    k_ident = any(final.at_bound(q) is None for q in free if q.name in ("c_f", "c_r"))
    understeer = _quantity(K, K_sd, "rad/(m/s2)", identifiable=bool(k_ident and math.isfinite(K_sd) and not alike),
                           deg_per_g=math.degrees(K) * GRAVITY, **({"note": f"not identifiable from this log: {alike}"}
                                                                    if alike else {}))
    char = characteristic_speed(K, K_sd, L, understeer["identifiable"], alike, top_speed)
    if understeer["identifiable"] and not char["identifiable"] and K < 0 and char["value"] < top_speed:
        understeer.update(identifiable=False, note=f"not concluded: its critical speed is {char['note']}")
    return K, K_sd, understeer, char


SENSED_GAIN = (0.8, 1.25)      # yaw per kinematic v tan(w) / L: a wheelbase, speed, gyro or angle scale 10-20 % off
# K's std with the turn scale k free over its std at k = 1 is 1 / sqrt(1 - rho^2), rho = corr(k, K):
# at 2, k carries three quarters of what the log says of K and K is not told from it
APART = 2.0
# a tyre's rolling radius moves 1-2 % with its pressure, load and wear (the speed's scale) and a
# declared wheelbase is measured to a centimetre or two on 1-3 m: a turn scale within 2 % is theirs
SCALE_TOLERANCE = 0.02
# at v_ch = 2 v_top the log's top speed sees K v^2 / L = 1/4, a yaw gain 20 % below the neutral
# steer's; beyond, the log sees less than a fifth of the effect whose midpoint v_ch would name
BEYOND_TOP = 2.0


# said beside a scale kept from a log that does not tell the ground's lean (ground_lean)
UNSEEN_LEAN = ("; a bank under the turns would read alike and this log does not tell the ground's lean (a roll, bank "
               "or a_y column lets identify check it)")


class YawScaled:
    """The yaw model with a turn gain k on its yaw rate, its gyro bias b not scaled: r = k (r_model -
    b) + b (``yaw_gain`` among the values). From turns, a wheelbase L / k, a speed or gyro scale k,
    or a wheel-angle sensor's gain (at small angles) are one quantity."""

    def __init__(self, model: YawModel):
        self.model = model

    def __getattr__(self, name):
        return getattr(self.model, name)

    def simulate(self, values: dict, segs: Segments | None = None) -> np.ndarray:
        return self.simulate_many([values], segs)[0]

    def simulate_many(self, sets: list[dict], segs: Segments | None = None, lateral: bool = False):
        out = self.model.simulate_many(sets, segs, lateral=lateral)
        yaw = out[0] if lateral else out
        scaled = [v.get("yaw_gain", 1.0) * (y - v.get("gyro_bias", 0.0)) + v.get("gyro_bias", 0.0)
                  for v, y in zip(sets, yaw)]
        return (scaled, out[1]) if lateral else scaled


TURN_GAIN = Parameter("yaw_gain", "1", 0.05, *SENSED_GAIN, meaning="yaw rate per kinematic v tan(w) / L: a scale of "
                      "the turns (the declared wheelbase's, the speed's, the gyro's, or the wheel angle sensor's)")
TYRE_SHAPE = ("friction", "shape", "friction_ratio")


def _turn_scale_fits(fits: _Fits, final: FitResult, cap: float | None) -> tuple[FitResult, FitResult, np.ndarray | None]:
    """(the final model at k = 1, the same with k free (YawScaled), the |a_y| mask): both on the fit
    segments where |a_y| <= ``cap`` (the linear range, where a misfit of the tyres' bend cannot pass
    for a scale; None: everywhere, and the k = 1 fit is ``final``), the saturation's friction and
    shape held as the final fit has them."""
    a_y = np.abs(fits.model.log.a_y[fits.fit_segs.idx])
    mask = None if cap is None or a_y[fits.fit_segs.scored].max() <= cap else a_y <= cap
    free = [q for q in final.free if q.name not in TYRE_SHAPE]
    fixed = {k: v for k, v in final.values.items() if k not in [q.name for q in free]}
    base = final if mask is None else fit(fits.model, free, final.values, fixed, fits.fit_segs, mask=mask)
    scaled = fit(YawScaled(fits.model), [*free, TURN_GAIN], {**base.values, "yaw_gain": 1.0}, fixed, fits.fit_segs,
                 mask=mask)
    return base, scaled, mask


def held_out_gain(fits: _Fits, base: FitResult, scaled: FitResult, cap: float | None) -> tuple[float, float, int]:
    """(mean, standard error, segments) of the held-out segments' mean square yaw misfit at k = 1
    less that with k free, each segment (|a_y| <= ``cap``, at least 10 samples) one independent
    draw: a scale of the turns the log supports predicts them better by more than Z95 standard errors."""
    segs, log = fits.test_segs, fits.model.log
    y = log.r[segs.idx]
    at_one, free = fits.model.simulate(base.values, segs), YawScaled(fits.model).simulate(scaled.values, segs)
    m = segs.scored & (np.abs(log.a_y[segs.idx]) <= (math.inf if cap is None else cap))
    d = np.array([np.mean((y[i] - at_one[i])[m[i]] ** 2) - np.mean((y[i] - free[i])[m[i]] ** 2)
                  for i in range(len(segs.idx)) if m[i].sum() >= 10])
    if len(d) < 3:
        return math.nan, math.nan, len(d)
    return float(d.mean()), float(d.std(ddof=1) / math.sqrt(len(d))), len(d)


def scale_on_bound(fit: FitResult) -> str | None:
    """Why the turn scale k of a fit with k free (``yaw_gain``) is not concluded, or None: it ends on
    a bound of SENSED_GAIN or its 95 % interval reaches or crosses one. Those bounds are its limit as
    a scale (a sensor's gain, the declared wheelbase or speed off by up to 20 %; past them the
    declaration itself is wrong), so there is no wider physical bound to search: the log cannot
    decide whether k lies inside them, nor what K is, which moves with it."""
    g, sd, q = fit.values["yaw_gain"], fit.std("yaw_gain"), TURN_GAIN
    lo, hi = g - Z95 * sd, g + Z95 * sd
    side = fit.at_bound(q) or ("lower" if not lo > q.lower else "upper" if not hi < q.upper else None)
    if side is None and math.isfinite(sd):
        return None
    side = side or ("lower" if g - q.lower < q.upper - g else "upper")
    bound = q.lower if side == "lower" else q.upper
    interval = f" [{lo:.3g}, {hi:.3g}]" if math.isfinite(sd) else ""
    return (f"k {g:.3g}{interval} at its bound {bound:g}; cannot decide: a scale of the turns is searched in "
            f"[{q.lower:g}, {q.upper:g}] (a sensor's gain, the declared wheelbase or speed off by up to 20 %), its limit "
            f"as a scale; past it the declared wheelbase, speed or wheel angle is wrong, not off by a scale: check them")


def gain_apart(fits: _Fits, final: FitResult, cap: float | None = None) -> tuple[dict, str | None, FitResult | None]:
    """A measured wheel angle is fitted at k = 1; a scale error of the turns (the angle sensor's, the
    declared wheelbase's, the speed's) then reads as understeer, since the steady yaw rate
    k v / (L + K v^2) differs from a neutral vehicle's as much at low speeds. The final model fitted
    again with k free in SENSED_GAIN where |a_y| <= ``cap`` (_turn_scale_fits): (the check's JSON,
    why K is not told from k or None, the fit with k free when it is the one to keep or None).
    k = 1 is kept when the refit does not converge, when k does not predict the held-out segments
    better (held_out_gain: no evidence of a scale; a misfit of the model fits the fit segments
    alone), or when K at k = 1 lies inside K's 95 % interval with k free. Else, where k or its 95 %
    interval reaches a bound (scale_on_bound: neither k nor K concluded), both stiffnesses end on
    theirs or K's std with k free exceeds APART x its std at k = 1, K is not told from k; else a scale clearly beyond SCALE_TOLERANCE keeps the free fit, a smaller one
    k = 1 with K's interval spanning both fits' (``span``)."""
    base, free_fit, mask = _turn_scale_fits(fits, final, cap)
    gain = TURN_GAIN
    (k1, sd1), (k2, sd2) = _k_of(base), _k_of(free_fit)
    g, g_sd = free_fit.values["yaw_gain"], free_fit.std("yaw_gain")
    gained, gained_se, n_held = held_out_gain(fits, base, free_fit, cap)
    lo, hi = k2 - Z95 * sd2, k2 + Z95 * sd2
    k2_seen = any(free_fit.at_bound(q) is None for q in free_fit.free if q.name in ("c_f", "c_r"))
    bound = scale_on_bound(free_fit)
    wide = not (k2_seen and math.isfinite(sd2)) or sd2 > APART * sd1 or bound is not None
    scaled = abs(g - 1) - Z95 * g_sd > SCALE_TOLERANCE       # beyond what a declared wheelbase or speed is sure of
    inside = lo <= k1 <= hi
    alone = not gained > Z95 * gained_se                     # nan (too few held-out segments): no evidence either
    how_wide = (f"K's std x {sd2 / sd1:.2g} with k free" if k2_seen and math.isfinite(sd2) else
                "with k free both stiffnesses end on their bounds")
    span = [min(lo, k1 - Z95 * sd1), max(hi, k1 + Z95 * sd1)]
    where = "" if mask is None else f" where |a_y| <= {cap:.3g} m/s2 (the linear range)"
    unseen = UNSEEN_LEAN if fits.model.log.lean is None else ""
    verdict = ("k = 1 kept: the refit with k free did not converge: no evidence of a scale"
               if not free_fit.converged else
               "k = 1 kept: K at k = 1 lies inside the interval of K with k free" if inside else
               f"k = 1 kept: the fit with k free predicts the held-out segments no better (mean square "
               f"misfit {gained:+.2g} +- {gained_se:.2g} (rad/s)^2 less over {n_held} segments): no evidence of a "
               f"scale, what k takes up on the fit segments does not carry over" if alone else
               f"k not concluded: {bound}" if bound else
               f"K not told apart from k ({how_wide})" if wide else
               f"a scale of the turns of {100 * (g - 1):+.1f} %: the fit with k free kept{unseen}" if scaled else
               f"k = 1 kept, a scale of {100 * (g - 1):+.1f} % not clearly beyond the {100 * SCALE_TOLERANCE:g} % a "
               f"declared wheelbase and speed are sure of: K's interval spans both fits, [{span[0]:.3g}, {span[1]:.3g}]")
    no_scale = not free_fit.converged or alone or inside
    out = {"yaw_gain": _quantity(g, g_sd, "1", (gain.lower, gain.upper), free_fit.at_bound(gain), meaning=gain.meaning,
                                 **({"identifiable": False, "note": f"not concluded: {bound}"} if bound else {})),
           "understeer_gradient_gain_free": _quantity(k2, sd2, "rad/(m/s2)"),
           "understeer_gradient_gain_one": _quantity(k1, sd1, "rad/(m/s2)"), "verdict": verdict,
           "held_out_gain": {"mean": gained, "std_error": gained_se, "segments": n_held, "unit": "(rad/s)^2"},
           "kept": bool(not no_scale and not wide and scaled), "converged": free_fit.converged,
           "turn_scale": 1.0 if no_scale or not (wide or scaled) else None if wide else g,
           "how": f"the final model again with a turn gain k free in [{gain.lower:g}, {gain.upper:g}]{where}"}
    if no_scale or (not wide and not scaled):
        return out | ({} if no_scale else {"span": span}), None, None
    if not wide:
        return out, None, free_fit if mask is None else _scaled_everywhere(fits, final, free_fit)
    if bound:
        return out, (f"the turn scale is not concluded ({bound}), nor K, which moves with it: K {k2:.3g} [{lo:.3g}, "
                     f"{hi:.3g}] rad/(m/s2) with k free, {k1:.3g} [{k1 - Z95 * sd1:.3g}, {k1 + Z95 * sd1:.3g}] at "
                     f"k = 1"), None
    return out, (f"a scale of the turns and the understeer gradient are not told apart at these speeds: with a turn "
                 f"gain free it goes to {g:.3g} and K to {k2:.3g} [{lo:.3g}, {hi:.3g}] rad/(m/s2), against K {k1:.3g} "
                 f"[{k1 - Z95 * sd1:.3g}, {k1 + Z95 * sd1:.3g}] with the turns taken at their declared scale; the "
                 f"log's turns fix the two together ({how_wide}), so a scale of the wheelbase, "
                 f"the speed or the angle sensor reads as understeer"), None


def _scaled_everywhere(fits: _Fits, final: FitResult, scaled: FitResult) -> FitResult:
    """The final model with the turn scale found in the linear range, fitted on every fit segment
    from there (its saturation free again)."""
    fixed = {k: v for k, v in final.values.items() if k not in final.names}
    return fit(YawScaled(fits.model), [*final.free, TURN_GAIN], {**final.values, **scaled.values}, fixed, fits.fit_segs)


def _stiffnesses_on_bounds(final: FitResult) -> str | None:
    """Why K is not identifiable from the final fit alone (both stiffnesses on their bounds) or None."""
    on = [q for q in final.free if q.name in ("c_f", "c_r") and final.at_bound(q)]
    return "both cornering stiffnesses end on their bounds" if len(on) == 2 else None


def _misfit_on_bound(final: FitResult) -> str | None:
    """Why the final model misses the turns' zero (a steering offset or a gyro bias beyond its range,
    on its bound) or None: a turn scale would take that misfit up, not measure a scale."""
    on = [q.name for q in final.free if q.name in ("steer_offset", "gyro_bias") and final.at_bound(q)]
    return f"{', '.join(on)} on its bound: the model misses the log by more than a scale" if on else None


def _with_gain(log: DrivingLog, fits: _Fits, held: _HeldOut, saturation: bool, command: bool, min_speed: float,
               L: float):
    """(the gain check or None, why K is not identifiable or None, final fit, parameters, stiffnesses)
    from _final_parameters: at one speed (one_speed) a gain or a scale of the turns and K are not
    told apart and nothing is refitted; a measured angle goes through gain_apart otherwise (unless
    both stiffnesses are on their bounds, K already not identifiable), in the linear range where
    saturation is found, and a scale it finds replaces the final fit (``fits.model`` becomes
    YawScaled; its held-out prediction in ``held.sims``; the delay's verdict kept). A bias fitted
    beside an offset: _without_standstill."""
    final, params, stiff = _final_parameters(log, fits, held, saturation)
    leaning = turns_lean(log.lean, log.v, log.r, log.h, (log.v >= min_speed) & log.measured)
    alike = "; and ".join(x for x in (one_speed(log, min_speed, final.values.get("gyro_bias", 0.0)), leaning) if x)
    check, alike, free_fit = None, alike or None, None
    skip = alike or _stiffnesses_on_bounds(final) or _misfit_on_bound(final)
    if not command and skip:
        check = {"verdict": f"not fitted: K is not identifiable from this log already, or not through a scale ({skip})",
                 "kept": False,
                 "turn_scale": None}
    elif not command:
        cap = _linear_range(True, fits.nl, log, min_speed)["value"] if saturation else None
        check, alike, free_fit = gain_apart(fits, final, cap)
    if free_fit is not None:
        fits.model = YawScaled(fits.model)
        new_params, stiff = _parameters(free_fit, list(free_fit.free), fits)
        if "verdict" in params["delay"]:                # decided below zero: that verdict stands
            new_params["delay"] = params["delay"]
        held.sims[1 if saturation else 0] = fits.model.simulate(free_fit.values, fits.test_segs)
        final, params = free_fit, new_params
    _without_standstill(params, final, log, L, min_speed)
    return check, alike, final, params, stiff


def _turn_gain(final: FitResult) -> tuple[float, float]:
    """(g, std) of the final fit's steering gain (a command) or turn scale (a measured angle), else (1, 0)."""
    name = next((k for k in ("steer_gain", "yaw_gain") if k in final.names), None)
    return (final.values[name], final.std(name)) if name else (1.0, 0.0)


def characteristic_speed(K: float, K_sd: float, L: float, identifiable: bool = True, alike: str | None = None,
                         top_speed: float = math.inf) -> dict:
    """The characteristic (K > 0) or critical (K < 0) speed sqrt(L / |K|) with its std (delta
    method), identifiable where K is (``alike``: why K is not) and no further than BEYOND_TOP x the
    log's ``top_speed`` (beyond: not identifiable at these speeds)."""
    if K > 0:
        vch = math.sqrt(L / K)
        char = {"kind": "characteristic speed (understeer): the yaw-rate gain peaks there", "value": vch,
                "std": 0.5 * vch * K_sd / K, "unit": "m/s"}
    elif K < 0:
        vch = math.sqrt(-L / K)
        char = {"kind": "critical speed (oversteer): unstable above it", "value": vch, "std": 0.5 * vch * K_sd / -K,
                "unit": "m/s"}
    else:
        char = {"kind": "neutral steer", "value": math.inf, "std": math.inf, "unit": "m/s"}
    char["interval"] = [char["value"] - Z95 * char["std"], char["value"] + Z95 * char["std"]]
    char["identifiable"] = identifiable          # v_ch is K's: identifiable where K is
    if not identifiable:
        char["note"] = "not identifiable from this log: it is set by K, which is not" + (f" ({alike})" if alike else "")
    elif K < 0 and char["value"] < top_speed:       # driven stably above it: the sign is a misfit's, not the car's
        char["identifiable"] = False
        char["note"] = (f"impossible, not a verdict: sqrt(L / |K|) = {char['value']:.3g} m/s lies below the speeds the "
                        f"vehicle was driven at (top {top_speed:.3g} m/s, 99th percentile) without losing it: the "
                        f"model misses the log (a steering angle's scale, a clock, a bias), the car is not oversteering")
    elif char["value"] > BEYOND_TOP * top_speed:     # an extrapolation of the gain curve far past the log
        char["identifiable"] = False
        char["note"] = (f"{NOT_AT_THESE_SPEEDS}: sqrt(L / |K|) = {char['value']:.3g} m/s lies beyond {BEYOND_TOP:g} x the "
                        f"log's top speed {top_speed:.3g} m/s (99th percentile), where K v^2 / L is "
                        f"{100 * abs(K) * top_speed ** 2 / L:.1f} % of the yaw gain")
    return char


def _steady_check(log: DrivingLog, model: YawModel, values: dict, L: float, min_speed: float, cap: float,
                  command: bool):
    """(the steady windows, their regression in the linear range up to ``cap``, the same regression
    on the model's own yaw rate: comparisons.model_steady_state): the independent check on K (a
    negative delay is left to the fit); the input enters as the model's does, tan u under its
    Ackermann geometry (L r = v tan u - K v^2 r is the no-slip turn at any angle). A command's gain
    is fitted beside K; a measured angle's held at 1, as the dynamic fit takes it (a scale of the
    turns is the turn-scale check's, gain_apart, and the model's own regression carries it)."""
    delay = max(values["delay"], 0.0)
    u = model.turning(log.u)       # as the model turns
    windows = steady_windows(log.t, u, log.v, log.r, log.run, min_speed, delay=delay)
    ss = in_linear_range(windows, L, LINEAR_TYRE, cap, fixed_gain=None if command else 1.0)
    return windows, ss, model_steady_state(model, values, log, min_speed, delay, windows, ss, u)


def _without_standstill(params: dict, final: FitResult, log: DrivingLog, L: float, min_speed: float) -> None:
    """A gyro bias fitted (no standstill to measure it) beside a steering offset: both notes say so
    and that neither is concluded. Both shift the yaw rate, an offset delta_0 by v delta_0 / L, a
    bias by b at every speed: only the speed's spread tells them apart, their fitted correlation says
    how little, and their intervals hold only for an exact model (a gain, a lag or an asymmetry it
    misses moves both beyond them)."""
    if "gyro_bias" not in final.names or "steer_offset" not in final.names:
        return
    i, j = final.names.index("gyro_bias"), final.names.index("steer_offset")
    c = final.cov
    rho = float(c[i, j] / math.sqrt(c[i, i] * c[j, j])) if c[i, i] > 0 and c[j, j] > 0 else math.nan
    v = float(np.median(log.v[log.v >= min_speed]))
    why = (f"fitted without a standstill (no 2 s with |v| < {STANDSTILL:g} m/s in the log: the recording's standing "
           f"still trimmed, or never recorded): the gyro bias and the steering offset both shift the yaw rate (an offset "
           f"of 1 deg reads as {math.radians(1) * v / L:.3g} rad/s of bias at the median speed {v:.2g} m/s), told apart "
           f"only by the speed's spread (correlation {rho:+.2f}); their intervals hold only for an exact model, any "
           f"misfit moves both beyond them: not concluded; keep a standstill of 2 s or more in the log (--time-range "
           f"around it) to measure the bias")
    for name, text in (("gyro_bias", why), ("steer_offset", "fitted without a standstill, traded against the gyro "
                                                          "bias: not concluded (see gyro_bias)")):
        q = params[name]
        params[name] = {**q, "concluded": False, "no_standstill": True,
                        "note": f"{q['note']}; {text}" if q.get("note") else text}


def _steady_json(ss, vehicle: Vehicle, windows: dict, dynamic_offset: dict | None = None) -> dict:
    """The steady-state regression's JSON, with why its gain is held (a measured angle) and its
    offset flagged ``implausible`` beyond the class's steering offset (vehicle.CLASSES), its cause
    from the dynamic fit's offset (``dynamic_offset``): on the same side beyond the class's range too
    (or on its bound there), an offset of the steering itself, a fault to check; else the regression's
    straight-line model missing the turns. ``ss`` None: why there is none."""
    if ss is None:
        return {"windows": int(len(windows["u"])), "note": "not possible: fewer than 7 steady windows inside the "
                "linear range, no steady turning, or (a command input) one speed, where the steering gain and K "
                "are not told apart"}
    d = ss.as_dict()
    if ss.fixed_gain is not None:
        d["gain_held"] = "a measured angle taken at its declared scale, as the dynamic fit takes it (steering_gain_check)"
    bound, off = vehicle.steer_offset_bound, d["steer_offset"]["value"]
    if abs(off) <= bound:
        return d
    dyn = (dynamic_offset or {}).get("value", 0.0)
    both = dyn * off > 0 and abs(dyn) > bound
    cause = (f"the dynamic fit's offset {dyn:.3g} rad is beyond it on the same side"
             f"{' (on its bound)' if 'bound' in (dynamic_offset or {}).get('note', '') else ''}: the steering is off "
             f"by more than a healthy {vehicle.kind or 'vehicle'}'s, a fault to check (the angle sensor's zero, the "
             f"steering linkage)" if both else
             f"the dynamic fit's offset {dyn:.3g} rad is not: the regression's offset takes up what its straight-line "
             f"model misses")
    d["steer_offset"]["implausible"] = (f"|{math.degrees(off):.3g}| deg beyond the {math.degrees(bound):.3g} deg a "
                                        f"{vehicle.kind or 'vehicle'}'s angle sensor can be off; {cause}; not concluded")
    return d


def _low_range_understeer(fits: _Fits, saturation: bool) -> tuple[float, float] | None:
    """(K, std) of the linear model fitted where |a_y| <= LINEAR_TYRE (None: no such separate fit,
    or the tyre-saturation model is the final one, already linear there)."""
    low = fits.linear_low
    if low is fits.linear or saturation:
        return None
    return _k_of(low)


def _k_of(fit: FitResult) -> tuple[float, float]:
    """(K, its std) of a fit's c_f, c_r: K = (1/c_f - 1/c_r) / g, the std by the delta method on the
    fit's covariance."""
    cf, cr = fit.values["c_f"], fit.values["c_r"]
    return understeer_gradient(cf, cr), fit.interval_of({"c_f": -1 / (GRAVITY * cf ** 2), "c_r": 1 / (GRAVITY * cr ** 2)})


def _steady_gain(log: DrivingLog, min_speed: float, k: tuple, L: float, gain: tuple, notes: list[str]) -> dict:
    """The steady-state yaw-rate gain's JSON: _gain_rows at K = k[0] (std k[1]), none (said in
    ``notes``) when no single K is concluded (k[2], the understeer quantity, ``withheld`` or not
    ``identifiable``)."""
    d = {"unit": "(rad/s) per rad of input", "formula": "g v / (L + K v^2)"}
    if k[2].get("withheld") or not k[2].get("identifiable", True):
        why = ("left out: no single K is concluded (" + ("the dynamic fit's and the steady turns' disagree" if
               k[2].get("withheld") else "see the understeer gradient") + "), so no gain curve is drawn from one")
        notes.append(f"steady-state yaw-rate gain rows and figure {why}")
        return d | {"rows": [], "note": why}
    return d | {"rows": _gain_rows(log, min_speed, k[0], k[1], L, *gain)}


def _gain_rows(log: DrivingLog, min_speed: float, K: float, K_sd: float, L: float, g: float, g_sd: float) -> list[dict]:
    """The steady-state yaw-rate gain G = g v / (L + K v^2) at 12 speeds up to the 99th percentile
    of the driving's, with its 95 % interval (delta method on K and g)."""
    speeds = np.linspace(max(min_speed, 0.1), float(np.percentile(log.v[log.v >= min_speed], 99)), 12)
    gain_rows = []
    for s in speeds:
        G = float(steady_state_gain(s, K, L, g))
        dG_dK = -g * s ** 3 / (L + K * s * s) ** 2
        sd = math.sqrt((dG_dK * K_sd) ** 2 + (G / g * g_sd) ** 2)
        gain_rows.append({"speed": float(s), "gain": G, "interval": [G - Z95 * sd, G + Z95 * sd]})
    return gain_rows


def _linear_range(saturation: bool, nl: FitResult, log: DrivingLog, min_speed: float) -> dict:
    """How far in |a_y| the linear model holds: with saturation, where the Magic Formula's force of
    the axle that bends first (axle_friction.first_to_bend) falls 5 % below the linear tyre's, mu g x
    share(C) (std by the delta method on the fit's covariance of mu_f, rho and C); without, the 99th
    percentile of the driving's |a_y|."""
    if saturation:
        shape = nl.values["shape"]
        mu, d_mu, axle = first_to_bend(nl.values["friction"], nl.values.get("friction_ratio", 1.0))
        share = linear_share_limit(shape)
        lin_range = mu * GRAVITY * share
        eps = 1e-4
        d_share = (linear_share_limit(min(shape + eps, SHAPE_BOUNDS[1])) - linear_share_limit(shape - eps)) / (2 * eps)
        lr_sd = GRAVITY * nl.interval_of({**{k: share * g for k, g in d_mu.items()}, "shape": mu * d_share})
        per_axle = "friction_ratio" in nl.names          # one friction on both axles: no axle to name
        whose, mu_said = (f"of the {axle} axle (the first to bend) ", f"mu {mu:.3g}, ") if per_axle else ("", "")
        return {**_quantity(lin_range, lr_sd, "m/s2"),
                "how": f"where the Magic Formula's force {whose}falls 5 % below the linear tyre's: |a_y| = mu g "
                       f"x {share:.3f} ({mu_said}shape {shape:.2f})", "saturation": True}
    top_a = float(np.percentile(np.abs(log.a_y[log.v >= min_speed]), 99))
    return {"value": top_a, "std": 0.0, "interval": [top_a, top_a], "unit": "m/s2", "at_least": True,
            "how": "no saturation found: the linear model holds over the whole log, whose largest |a_y| (99th "
                   "percentile) this is: the tyres' bend is not reached", "saturation": False}


def _tyre_json(held: _HeldOut, nl: FitResult, free_nl: list[Parameter], saturation: bool) -> dict:
    """The tyre-saturation verdict: found or why not, dBIC, held-out gains, the misfit's growth at
    high |a_y|, the fitted friction and shape with their intervals."""
    params = {q.name: _quantity(nl.values[q.name], nl.std(q.name), q.unit, (q.lower, q.upper), nl.at_bound(q),
                                meaning=q.meaning) for q in free_nl if q.name in TYRE_SHAPE}
    mu, friction = params["friction"], next(q for q in free_nl if q.name == "friction")
    if saturation and nl.at_bound(friction) == "upper":
        mu |= {"at_least": True, "note": f"at least {mu['bounds'][1]:g}: on the class's upper bound, the log's "
               f"turns reach the tyres' bend but not their peak force"}
    elif saturation and nl.at_bound(next(q for q in free_nl if q.name == "shape")):
        mu |= {"identifiable": False, "note": f"{mu['value']:.3g} not concluded: the shape C (how sharply the tyres "
               f"bend) sits on its bound, and the peak force trades against it"}
    return {"model": "simplified Magic Formula F = mu F_z sin(C atan(B alpha)), B = C_alpha / (C mu F_z)",
            "found": saturation, "why_not": held.reasons, "delta_bic": held.dbic,
            "held_out_gain": held.gain_all, "held_out_gain_high_lateral": held.gain_top,
            "misfit_at_high_lateral_t": held.growth, "high_lateral_from": held.hi_q, "parameters": params}


def _residual_bins(held: _HeldOut) -> dict:
    """The held-out residual's RMS by |a_y| bin: the linear model, the linear model fitted in the
    linear range (signed by the turn's direction, with its mean), the saturation model."""
    edges = [0, 0.5, 1, 2, 3, 4, 6, 8, 10, 15, 30]
    return {"linear": _bins(held.a_test, held.res_lin, edges),
            "linear_fitted_in_linear_range": _bins(held.a_test, held.res_low * np.sign(held.y), edges, signed=True),
            "saturation": _bins(held.a_test, held.res_nl, edges)}


def held_out_misfit(report: dict, unseen) -> dict | None:
    """The identified final model's gyro misfit on its held-out segments where ``unseen(t)`` (a
    boolean array of the sample times) holds: samples neither this fit nor another fit that held them
    out has seen, so that another model of the same vehicle (the diagnosis's) can be scored on the
    same stretches. Returns {"windows": [(t0, t1)], "seconds", "rms" [rad/s]}, or None without such
    samples."""
    plot = report.get("_plot")
    if not plot:
        return None
    log, segs = plot["log"], plot["test"]
    pred = plot["test_pred"]               # the final model on the held-out segments, as judged above
    t = log.t[segs.idx]
    keep = segs.scored & np.asarray(unseen(t), bool)
    if keep.sum() < 10:
        return None
    windows = [(float(t[i][keep[i]].min()), float(t[i][keep[i]].max())) for i in range(len(segs.idx)) if keep[i].any()]
    res = (log.r[segs.idx] - pred)[keep]
    return {"windows": windows, "seconds": float(keep.sum() * log.h), "rms": float(np.sqrt(np.mean(res ** 2)))}


PHYSICAL_COLUMNS = {"beta": ("side-slip angle at the centre of gravity", "rad"),
                    "vy": ("lateral velocity at the centre of gravity", "m/s"),
                    "a_y": ("lateral acceleration", "m/s2")}


def physical_checks(frame, log, model, values: dict, segs) -> dict:
    """The final model's side-slip beta = atan(v_y / v), lateral velocity v_y and lateral
    acceleration a_y = dv_y/dt + v r (its states, never fitted to them) against the log's ``beta``
    [rad], ``vy`` [m/s] and ``a_y`` [m/s2] on the held-out segments: fit [%] and RMS. The log's a_y
    is a specific force (identification.ground_lean): the ground's lean read from a bank or roll
    column is subtracted from the model's (one read from a_y itself would compare a_y with itself)."""
    have = [c for c in PHYSICAL_COLUMNS if c in frame and np.isfinite(frame[c].to_numpy(float)).sum() > 10]
    if not have or not len(segs.idx):
        return {}
    yaw, vy = model.simulate_many([values], segs, lateral=True)
    yaw, vy = yaw[0] - values.get("gyro_bias", 0.0), vy[0]
    v = log.v[segs.idx]
    lean = log.lean[segs.idx] if log.lean is not None and lean_column(frame) else 0.0
    pred = {"beta": np.arctan2(vy, np.maximum(v, 1e-3)), "vy": vy,
            "a_y": np.gradient(vy, log.h, axis=1) + v * yaw - lean}
    t = frame["t"].to_numpy(float)
    out = {}
    for c in have:
        col = frame[c].to_numpy(float)
        ok = np.isfinite(col)
        meas = np.interp(log.t[segs.idx], t[ok], col[ok])
        m, p_ = meas[segs.scored], pred[c][segs.scored]
        out[c] = {"what": PHYSICAL_COLUMNS[c][0], "unit": PHYSICAL_COLUMNS[c][1], "fit_percent": fit_percent(m, p_),
                  "rms": float(np.sqrt(np.mean((m - p_) ** 2))), "measured_std": float(np.std(m)),
                  "how": "the final model's state on the held-out segments, driven by the input alone; never fitted to it"}
    return out


def independent_estimates(frame, log, test_segs, r_test, pred, understeer, ss, delay_q, bias_q, linear_range,
                          L: float, min_speed: float, low=None, twin=None) -> list[dict]:
    """The pairs of identification.comparisons this log allows: K (dynamic fit / steady states in
    their linear range, understeer_pair; ``low``: the dynamic fit's K where |a_y| <= LINEAR_TYRE; ``twin``:
    the regression on the model's own yaw rate, comparisons.model_steady_state),
    the delay (fit / cross-correlation of the gyro against the fitted model on the held-out
    segments: a timing the model misses shows as a lag), the gyro bias (fit / GNSS course)."""
    out = []
    if ss:
        moving = np.abs(log.a_y[log.v >= min_speed])
        out.append(understeer_pair(understeer, ss, linear_range, float(np.percentile(moving, 99)) if len(moving) else 0.0,
                                   low, twin))
    pieces = [(r_test[i][test_segs.scored[i]], pred[i][test_segs.scored[i]]) for i in range(len(test_segs.idx))
              if test_segs.scored[i].sum() >= 10]
    if pieces and math.isfinite(delay_q["value"]):
        meas = np.concatenate([a for a, _ in pieces])
        model = np.concatenate([b for _, b in pieces])
        grid = np.arange(len(meas)) * log.h
        extra, rho = content_lag(grid, model, grid, meas, step=log.h, search=1.0)
        if math.isfinite(extra):
            out.append(pair("command-to-yaw delay", "s", ("dynamic fit", delay_q["value"], delay_q["std"]),
                            ("cross-correlation of the gyro with the fitted model", delay_q["value"] - extra, 0.5 * log.h),
                            (f"the gyro lags the fitted model by {-extra:.3g} s on the held-out segments: a timing the "
                             f"model does not hold (a clock offset between channel groups, or a delay varying over the log)"
                             if extra < 0 else
                             f"the gyro leads the fitted model by {extra:.3g} s on the held-out segments: the response "
                             f"leads its input, which no vehicle does: the steering channels are stamped late against "
                             f"the gyro (a clock offset)")))
    if bias_q and {"x", "y", "t", "yaw_rate"} <= set(frame.columns):
        f = frame[["t", "x", "y", "yaw_rate", "v"]].dropna() if "v" in frame else None
        if f is not None and len(f) > 100:
            cb = course_bias(*(f[c].to_numpy(float) for c in ("t", "x", "y", "yaw_rate", "v")), min_speed=min_speed)
            if cb is not None:
                out.append(pair("gyro bias", "rad/s", ("dynamic fit", bias_q["value"], bias_q["std"]),
                                ("GNSS course", cb[0], cb[1]),
                                "the yaw fit's bias is not the gyro's: it holds a steering offset or a side slope seen "
                                "through the yaw rate (or the positions are not of a rigid point)"))
    return out


def _steady_lines(ss: dict, q) -> list[str]:
    """The steady-state regression on the measured turns, as fitted (its K before the structural
    correction the comparison line carries), its gain fitted or held, its offset flagged when
    outside the class's range."""
    if "understeer_gradient" not in ss:
        return []
    g, off = ss["steer_gain"], ss["steer_offset"]
    gain = f"gain {g['value']:.3g} (held at 1: {ss['gain_held']})" if ss.get("gain_held") else f"gain {g['value']:.3g}"
    flag = f" OUTSIDE the class's range: {off['implausible']}" if off.get("implausible") else ""
    return [f"steady-state regression on the measured turns, before its structural correction ({ss['windows']} "
            f"windows, |a_y| <= {ss['max_lateral_acceleration']:.3g}): K {q(ss['understeer_gradient'])}, {gain}, offset "
            f"{off['value']:.3g} rad ({math.degrees(off['value']):.2g} deg){flag}; linear range {ss['linear_limit']}"
            + (f"; {ss['windows_passed_over']} windows beyond it passed over" if ss["windows_passed_over"] else "")]


def summary(report: dict) -> str:
    """What an engineer reads first."""
    def q(d, f="{:.4g}"):
        if not all(x is not None and math.isfinite(x) for x in d["interval"]):
            return f.format(d["value"]) + " " + d.get("unit", "") + " (on its bound)"
        return f.format(d["value"]) + " [" + ", ".join(f.format(x) for x in d["interval"]) + "] " + d.get("unit", "")

    def told(d, f="{:.4g}"):          # a value not concluded is given as fitted, as the comparisons give it
        return q(d, f) if d.get("identifiable", True) and d.get("concluded", True) else f"not concluded (fitted {q(d, f)})"

    lines = [f"identification from driving ({report['source']}): {report['model']} model, input {report['input']}, "
             f"{report['seconds_driven']:.0f} s of driving, {report['segments']['held_out']} segment(s) held out"]
    lines += [f"  {n}" for n in report["notes"]]
    if report.get("final_model") == "kinematic":
        return "\n".join(lines + kinematic_summary(report))
    if report.get("final_model") == "steady_turn":
        return "\n".join(lines + steady_turn_summary(report))
    if report.get("final_model") == "skid_steer":
        return "\n".join(lines + skid_steer.summary_lines(report))
    K = report["understeer_gradient"]
    if K["identifiable"]:
        ch = report["characteristic_speed"]
        lines += [f"understeer gradient K: {q(K)} ({K['deg_per_g']:.3g} deg/g)" + (f", {K['from']}" if "from" in K else ""),
                  f"{ch['kind'].split(' (')[0]}: {ch['value']:.3g} m/s" if ch["identifiable"] else
                  f"characteristic or critical speed: {ch['note']}"]
    else:       # neither K nor the speed it sets is printed as a result
        lines.append(f"understeer gradient K: {K.get('note', 'not identifiable from this log')} (fitted "
                     f"{K['deg_per_g']:.3g} deg/g; no characteristic or critical speed)")
    if "steering_gain_check" in report:
        gc = report["steering_gain_check"]
        k = gc.get("turn_scale")
        fitted = (f" ({gc['how']}: k {q(gc['yaw_gain'], '{:.3g}')}, K {q(gc['understeer_gradient_gain_free'])})"
                  if "yaw_gain" in gc else "")
        lines.append(f"turn scale k (yaw rate per v tan(w) / L): {'not concluded' if k is None else f'{k:.3g}'}: "
                     f"{gc['verdict']}{fitted}")
    lines.append(f"delay: {told(report['delay'])}" + (f"; {report['delay']['note']}" if "note" in report["delay"] else ""))
    for side, s in report["cornering_stiffness"].items():
        lines.append(f"cornering stiffness {side}: {q(s, '{:.4g}')}" + (f"; {s['note']}" if "note" in s else ""))
    hf = report["held_out_fit"]
    lines.append(f"held-out fit: {q(hf, '{:.1f}')} (linear {hf['linear_model']:.1f} %, with tyre saturation "
                 f"{hf['saturation_model']:.1f} %) over {len(hf['per_segment'])} segment(s)")
    t = report["tyre_saturation"]
    if t["found"]:
        mu, c = t["parameters"]["friction"], t["parameters"]["shape"]
        mu_withheld = mu.get("at_least") or not mu.get("identifiable", True)
        lines.append(f"tyre saturation found: friction {mu['note'] if mu_withheld else q(mu, '{:.3g}')}, shape {q(c, '{:.3g}')}; dBIC {t['delta_bic']:.0f}, "
                     f"held-out RMS -{100 * t['held_out_gain_high_lateral']:.0f} % where |a_y| > "
                     f"{t['high_lateral_from']:.2g} m/s2")
    else:
        lines.append("tyre saturation not found: " + "; ".join(t["why_not"]))
    lr = report["linear_range"]
    lines.append(f"linear model holds for |a_y| at least up to {lr['value']:.3g} m/s2 ({lr['how']})" if lr.get("at_least")
                 else f"linear model holds for |a_y| up to {q(lr, '{:.3g}')}")
    lines += _steady_lines(report["steady_state_regression"], q)
    for c, chk in report.get("physical_checks", {}).items():
        lines.append(f"physical check {c} ({chk['what']}): held-out fit {chk['fit_percent']:.1f} %, RMS {chk['rms']:.3g} "
                     f"{chk['unit']} (measured std {chk['measured_std']:.3g})")
    lines += [pair_line(c) for c in report.get("comparisons", [])]
    for p_name, pj in report["parameters"].items():
        lines.append(f"  {p_name}: {told(pj)}" + (f"  ({pj['note']})" if pj.get("note") else ""))
    lines += [f"extended_study.toml leaves out {x}" for x in report.get("extended_study_left_out", [])]
    return "\n".join(lines)
