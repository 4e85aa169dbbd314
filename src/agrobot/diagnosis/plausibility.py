"""What a fitted value is judged against: the vehicle it would be a property of, and the rules more
than one effect shares.

Each effect judges its own values (``Effect.plausibility``, diagnosis.effect); the verdict calls the
rule of every judged effect in a loop (diagnosis.verdict). A value that no vehicle of the class has
is not a mounting, an actuator or a tyre but a sign of something else, and the rule says what.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping

from agrobot.components.models.yaw_dynamics import GRAVITY

if TYPE_CHECKING:
    from agrobot.identification.vehicle import Vehicle

CALIBRATION = (0.7, 1.4)      # a scale factor or a gain errs inside this; outside it is a unit or a channel

# a class's outline when the [vehicle] table gives no length and width, in wheelbases: (rear overhang
# behind the rear axle, front overhang ahead of the front axle, width); "vehicle": no class declared
CLASS_OUTLINE = {"tractor": (0.45, 0.6, 1.0), "car": (0.35, 0.3, 0.65), "truck": (0.5, 0.35, 0.6),
                 "scale_car": (0.3, 0.4, 0.9), "robot": (0.3, 0.3, 0.9), None: (0.5, 0.5, 1.0)}

# understeer gradient K [rad/(m/s2)] a class's vehicle has: (lowest, highest); a road vehicle understeers
# (0.5-4 deg/g: 0.001-0.007), a tractor more on soft tyres; a small machine either way, within 10 deg/g
UNDERSTEER = {"tractor": (-0.002, 0.03), "car": (-0.001, 0.012), "truck": (-0.001, 0.015),
              "scale_car": (-0.02, 0.02), "robot": (-0.02, 0.02), None: (-0.02, 0.03)}
KINEMATIC = 0.03              # the kinematic regime: the axles' slip angles at the log's lateral acceleration
                              # (99th percentile) under 3 % of its steering angle: r = v tan(delta) / L; a stiffness
                              # off by 2.5 x then moves the yaw rate by less than 8 %


@dataclass(frozen=True)
class VehicleContext:
    """The vehicle a value is judged against: its ``[vehicle]`` table, the wheelbase and the rear
    axle's distance from the centre of gravity ``l_r`` [m], the log's median moving speed [m/s] and
    the study's antenna (forward, left) from the rear axle [m]."""

    vehicle: Vehicle
    wheelbase: float
    l_r: float
    speed: float
    antenna: tuple[float, float] = (0.0, 0.0)

    def outline(self) -> tuple[tuple[float, float], tuple[float, float], str]:
        """((forward lo, hi), (left lo, hi)) of the vehicle from its rear axle, and how it is known:
        the [vehicle] table's length and width, the length beyond the wheelbase split between the
        overhangs as its class's (CLASS_OUTLINE: behind = (length - L) rear / (rear + front), the body
        then ends length - behind ahead of the rear axle), else its class's default outline."""
        arm, wb = self.vehicle.lever_arm_bounds(), self.wheelbase
        rear, front, width = CLASS_OUTLINE.get(self.vehicle.kind, CLASS_OUTLINE[None])
        if arm and 0.0 < wb < self.vehicle.length:
            behind = (self.vehicle.length - wb) * rear / (rear + front)
            return ((-behind, self.vehicle.length - behind), arm[1],
                    f"its outline ({self.vehicle.length:g} m long, {self.vehicle.width:g} m wide; the "
                    f"{self.vehicle.length - wb:.2g} m beyond its wheelbase split as a {self.vehicle.kind or 'vehicle'}'s "
                    f"overhangs: {behind:.2g} m behind the rear axle, {self.vehicle.length - wb - behind:.2g} m ahead "
                    f"of the front one)")
        if arm:
            return arm[0], arm[1], f"its outline ({self.vehicle.length:g} m long, {self.vehicle.width:g} m wide)"
        return ((-rear * wb, (1 + front) * wb), (-0.5 * width * wb, 0.5 * width * wb),
                f"the default outline of {self.defaults_named()}")

    def defaults_named(self) -> str:
        """The class's default outline in words (for a [vehicle] table without length and width)."""
        rear, front, width = CLASS_OUTLINE.get(self.vehicle.kind, CLASS_OUTLINE[None])
        wb = self.wheelbase
        return (f"a {self.vehicle.kind or 'vehicle of no declared class'} of wheelbase {wb:.3g} m: "
                f"{(1 + rear + front) * wb:.3g} m long ({rear * wb:.2g} m behind the rear axle, {front * wb:.2g} m "
                f"ahead of the front one), {width * wb:.3g} m wide")

    def defaults_note(self) -> str | None:
        """What the verdict assumes of a vehicle whose dimensions the study does not give (None: it gives them)."""
        if self.vehicle.lever_arm_bounds():
            return None
        return (f"the study's [vehicle] table gives no length and width: the class's defaults are used, "
                f"{self.defaults_named()} (set vehicle.length and vehicle.width to judge against the real outline)")


def reference_point(values: Mapping[str, float], ctx: VehicleContext) -> list[str]:
    """The point the positions are put at (the antenna's place, or the study's antenna plus a reference
    point's offset) must lie inside the outline; outside it, the clock
    offset that moves the track as far is |forward - l_r| / speed."""
    ant = ctx.antenna if "position_forward" in values and "antenna_forward" not in values else (0.0, 0.0)
    fwd = values.get("antenna_forward", 0.0) + values.get("position_forward", 0.0) + ant[0]
    left = values.get("antenna_left", 0.0) + values.get("position_left", 0.0) + ant[1]
    (f_lo, f_hi), (l_lo, l_hi), how = ctx.outline()
    if f_lo <= fwd <= f_hi and l_lo <= left <= l_hi:
        return []
    speed = ctx.speed
    lag = abs(fwd - ctx.l_r) / speed if speed > 0 else math.nan
    return [f"the point it puts the positions at, {fwd:.2f} m ahead of the rear axle and {left:.2f} m left, "
            f"lies outside {how}: no antenna is mounted there; at the log's median speed "
            f"{speed:.2g} m/s a clock offset of about {lag:.2g} s between the positions and the gyro "
            f"moves the track as far, or the positions are an estimate of another frame"]


def scale_factor(what: str, s: float | None) -> list[str]:
    """A sensor's scale factor outside ``CALIBRATION`` is no sensor error but a unit or a channel."""
    lo, hi = CALIBRATION
    if s is None or lo <= s <= hi:
        return []
    return [f"a {what} scale factor of {s:.3g} is no sensor error: a unit or a channel is wrong"]


def slope(phi: float, vehicle: Vehicle) -> list[str]:
    """A side slope steeper than the class's ground (Vehicle.slope_bound; 20 deg for no class) is no
    slope but a lateral pull the model lacks."""
    bound = vehicle.slope_bound or math.radians(20.0)
    if abs(phi) <= bound:
        return []
    return [f"a side slope of {math.degrees(phi):.1f} deg is steeper than the ground a "
            f"{vehicle.kind or 'vehicle'} drives ({math.degrees(bound):.0f} deg): the yaw rate is pulled one way by "
            f"something else (a steering offset or a left/right asymmetry of the steering map, a gyro bias)"]


def study_understeer(p, front_scale: float = 1.0, rear_scale: float = 1.0) -> float:
    """The understeer gradient K = m/L (l_r / (s_f C_f) - l_f / (s_r C_r)) [rad/(m/s2)] of yaw-plant
    parameters ``p`` with its cornering stiffnesses scaled by s_f, s_r."""
    return p.m / (p.l_f + p.l_r) * (p.l_r / (front_scale * p.C_f) - p.l_f / (rear_scale * p.C_r))


def slip_share(p, lateral_p99: float, steering_p99: float) -> float:
    """The largest axle slip angle the study's tyres take at the log's lateral acceleration,
    alpha_f = m a_y l_r / (L C_f), alpha_r = m a_y l_f / (L C_r), over the log's steering angle (99th
    percentiles): how far the tyres move the yaw rate off r = v tan(delta) / L."""
    L = p.l_f + p.l_r
    alpha = p.m * lateral_p99 / L * max(p.l_r / p.C_f, p.l_f / p.C_r)
    return alpha / steering_p99 if steering_p99 > 0 else math.inf


def kinematic(share: float | None) -> str | None:
    """What a log in the kinematic regime (slip_share below KINEMATIC) cannot tell (None: the tyres'
    slip shows in it)."""
    if share is None or share >= KINEMATIC:
        return None
    return (f"the kinematic regime: at the log's lateral acceleration the study's tyres slip {100 * share:.2g} % of "
            f"its steering angle (99th percentiles), and the model is r = v tan(delta) / L; an understeer gradient, "
            f"a critical or a characteristic speed and the cornering stiffnesses are not identifiable at these "
            f"speeds (held at the study's)")


def understeer(K, vehicle: Vehicle, share: float | None, turns: dict | None = None) -> str | None:
    """Why an understeer gradient K [rad/(m/s2)] is not concluded (None: it is one this class has):
    a log in the kinematic regime (``share``: slip_share) cannot tell it; ``K`` given as identify's
    quantity (a dict) that is not identifiable, or whose 95 % interval covers the class's whole
    range (UNDERSTEER), is not pinned; outside the class's range the log's steady linear turns
    (``turns``: study_fit.log_vehicle, with the study's wheelbase) tell a steering map's gain from
    the tyres, and without them nothing is decided."""
    if kinematic(share):
        return "not identifiable at these speeds: " + kinematic(share)
    lo, hi = UNDERSTEER.get(vehicle.kind, UNDERSTEER[None])
    kind, deg = vehicle.kind or "vehicle", lambda k: math.degrees(k) * GRAVITY      # noqa: E731
    if isinstance(K, Mapping):
        if K.get("withheld"):       # identify's dynamic and steady-state K disagree: its note has both and why
            return K["note"]
        if not K.get("identifiable", True):
            return "not identifiable from this log: " + K.get("note", "").removeprefix("not identifiable from this log: ")
        a, b = K["interval"]
        if a <= lo and b >= hi:
            return (f"not identifiable from this log: its 95 % interval [{deg(a):.3g}, {deg(b):.3g}] deg/g covers "
                    f"the whole range of a {kind} ({deg(lo):.2g} to {deg(hi):.2g} deg/g)")
        K = K["value"]
    if lo <= K <= hi:
        return None
    text = f"an understeer gradient of {deg(K):.3g} deg/g is not of a {kind} ({deg(lo):.2g} to {deg(hi):.2g} deg/g)"
    if turns is None:
        return text + ": a steering map off in gain or asymmetric, or tyres past their linear range, read so"
    if not turns.get("wheelbase") or not turns.get("study_wheelbase"):
        return text + ": cannot decide whether a steering map's gain or the tyres: " + turns.get(
            "why", "the log has no steady turns to read a wheelbase from")
    ratio = turns["wheelbase"] / turns["study_wheelbase"]
    said = (f"the log's steady turns under {turns['linear_lateral']:g} m/s2 give a wheelbase of "
            f"{turns['wheelbase']:.3g} m against the study's {turns['study_wheelbase']:.3g} m ({100 * (ratio - 1):+.0f} %)")
    if abs(math.log(ratio)) > math.log(1.1):
        return f"{text}: a steering map's gain reads as tyres: {said}, the wheels turning {1 / ratio:.2g} x the input"
    return (f"{text}: cannot decide: {said}, so the steering map's gain is not the cause; the fit spans lateral "
            f"accelerations up to {turns['lateral_acceleration_p99']:.2g} m/s2 (99th percentile), where tyres past "
            f"their linear range read as understeer")


def steering_gain_check(effects: list[dict], turns: dict | None) -> tuple[str, bool] | None:
    """(a bullet, whether they agree) comparing a fitted steering_gain k with the gain the log's
    steady linear turns show, L_study / L_turns (``turns``: study_fit.log_vehicle); within 10 % they
    agree. None: no steering_gain judged or no such turns."""
    e = next((e for e in effects if e["id"] == "steering_gain"), None)
    if e is None or not turns or not turns.get("wheelbase") or not turns.get("study_wheelbase"):
        return None
    k, steady = e["parameters"]["steering_gain"], turns["study_wheelbase"] / turns["wheelbase"]
    agree = abs(math.log(k / steady)) <= math.log(1.1)
    text = (f"the steering gain {k:.3g} against the log's steady turns under {turns['linear_lateral']:g} m/s2, which "
            f"turn as a gain of {steady:.3g} would (wheelbase {turns['wheelbase']:.3g} m against the study's "
            f"{turns['study_wheelbase']:.3g} m): ")
    return text + ("they agree" if agree else "they disagree: the fitted gain also takes up what the model lacks in "
                   "harder turns (tyres, understeer); the steady linear turns' is the steering map's"), agree


DECLARED = math.log(1.1)      # the log's turns and the study's wheelbase more than 10 % apart: said with the evidence


def wheelbase_off(turns: dict | None, mismatch: float = math.log(1.3)) -> str | None:
    """What the log's steady linear turns say of a study whose wheelbase they miss by more than 10 %
    but not by the ``mismatch`` (log ratio) at which the study is named as another vehicle
    (``turns``: study_fit.log_vehicle with the study's wheelbase; None: within 10 %, or no turns)."""
    if not turns or not turns.get("wheelbase") or not turns.get("study_wheelbase"):
        return None
    ratio = turns["wheelbase"] / turns["study_wheelbase"]
    if abs(math.log(ratio)) <= DECLARED or abs(math.log(ratio)) > mismatch:
        return None
    return (f"the log's steady turns under {turns.get('linear_lateral', 2.0):g} m/s2 ({turns.get('samples', 0)} samples) "
            f"give a wheelbase of {turns['wheelbase']:.3g} m against the study's {turns['study_wheelbase']:.3g} m "
            f"({100 * (ratio - 1):+.0f} %, more than 10 %): the study's wheelbase, or its steering map's gain (the "
            f"wheels turning {1 / ratio:.2g} x the input), is off; the verdict's values are of the study's vehicle")


RESCALE_YAW = ("gyro_scale", "steering_gain", "speed_scale")     # effects that rescale the yaw rate as a
                                                                  # wheelbase does: r = v tan(delta) / L
MAP_GAIN = RESCALE_YAW[1]          # the one of them a steering map's gain error is


def steering_map_reading(vehicle, turns: dict) -> bool:
    """Whether a study the log's turns miss by more than 30 % may still be the vehicle with its
    steering map's gain off: the study, given by the user, declares the vehicle (its [vehicle] table:
    the user's word on the wheelbase; ``turns["declared"]``, else the vehicle's own flag) and the gain that would turn the study's wheelbase into the log's, k = L_study /
    L_log (r = v k delta / L_study = v delta / L_log), lies inside a calibration error's range
    (CALIBRATION). Then a fitted steering gain (MAP_GAIN) may be the verdict, the wrong study its
    other reading; a gyro or speed scale that large is no sensor error. A log beyond the study's
    limits (``turns["beyond_limits"]``, cannot_do) is read so only where a reading high is not ruled
    out (UNDECIDED): no map gain turns the wheels past a lock or a rate."""
    beyond = turns.get("beyond_limits")
    if beyond and not beyond.startswith(UNDECIDED):     # the log does what no map gain gives the study's vehicle
        return False
    if beyond and not turns.get("mismatch"):            # a reading k x high not ruled out by the log's turns
        return True
    if not turns.get("wheelbase"):
        return False
    k = turns["study_wheelbase"] / turns["wheelbase"]
    declared = turns.get("declared", getattr(vehicle, "declared", False))      # no --study: the default's is not
    return bool(declared) and CALIBRATION[0] < k < CALIBRATION[1]


def wrong_study(turns: dict | None) -> str | None:
    """The verdict on a study that is not the log's vehicle (``turns``: study_fit.log_vehicle; None:
    it may be): its ``beyond_limits`` statement (cannot_do: the log does what the study's vehicle
    cannot), after the wheelbase's when both hold (wrong_wheelbase: then the verdict)."""
    wheel = wrong_wheelbase(turns)
    beyond = (turns or {}).get("beyond_limits")
    return f"{wheel}; also {beyond.removeprefix(UNDECIDED)}" if wheel and beyond else wheel or beyond


def wrong_wheelbase(turns: dict | None) -> str | None:
    """The verdict on a study whose wheelbase the log's steady linear turns miss by more than 30 %
    (``turns``: study_fit.log_vehicle with its ``mismatch`` and ``suggestion``; None: within 30 %):
    the study is wrong, with the evidence (the log's wheelbase, its 95 % interval, the study's) and
    what to run instead; an effect that rescales the yaw rate (RESCALE_YAW) would only absorb it."""
    if not turns or not turns.get("mismatch") or not turns.get("wheelbase") or not turns.get("study_wheelbase"):
        return None
    L, Ls = turns["wheelbase"], turns["study_wheelbase"]
    lo, hi = turns.get("wheelbase_interval") or (math.nan, math.nan)
    return (f"the study is wrong for this log: its steady turns under {turns.get('linear_lateral', 2.0):g} m/s2 "
            f"({turns.get('samples', 0)} samples) give a wheelbase of {L:.3g} m (95 % interval [{lo:.3g}, {hi:.3g}] m) "
            f"against the study's {Ls:.3g} m ({100 * (Ls / L - 1):+.0f} %, more than the 30 % a study of this vehicle "
            f"can be off): the study is another vehicle, or its steering map turns the wheels {Ls / L:.2g} x the angle "
            f"the log says; {', '.join(RESCALE_YAW)}, which rescale the yaw rate as a wheelbase does, are not "
            f"concluded on it; instead: {turns.get('suggestion') or 'write a study with the log wheelbase'}, "
            f"and diagnose again")


def understeer_estimates(estimates: Mapping[str, Mapping], vehicle: Vehicle, turns: dict | None = None) -> str | None:
    """Each estimate of an understeer gradient (``estimates``: {who: {value [rad/(m/s2)], ...}}, as
    estimation.compare gives them) that is not of the vehicle's class (understeer), with why; None:
    every one is of the class. Printed beside the value wherever it is printed."""
    said = [f"{who}: {why}" for who, e in estimates.items()
            if isinstance(e.get("value"), (int, float)) and math.isfinite(e["value"])
            and (why := understeer(e["value"], vehicle, None, turns))]
    return "; ".join(said) or None


LIMIT_MARGIN = 1.25    # a log's figure is beyond a study's limit only past 1.25 x it (a radius below 1 / 1.25 x):
                       # a study's lock, actuator or drivetrain is its design, a real one a little off it; a
                       # wheel-angle sensor reading up to 20 % high stays inside it
RATE_MARGIN = 2.0      # the actuator's full rate is a soft design figure (a pump's flow with engine speed, a
                       # servo's with its supply): generated healthy tractors on the paper's servo reach 1.27 x
                       # the study's, a small robot on its own study 1.33 x; only past 2 x is it not this vehicle's
UNDECIDED = "cannot decide: "      # cannot_do's opening when a sensor reading high is not ruled out
NOISE_SIGMAS = 4       # and past 4 sigmas of the wheel angle's reading noise (a rate: over its window)


def _finite_or_zero(x: float | None) -> float:
    """x when it is a finite number, else 0 (a reading noise not measured adds no margin)."""
    return float(x) if x is not None and math.isfinite(x) else 0.0


def _limit_rows(log: Mapping, study) -> list[tuple[str, float, float, bool, str]]:
    """(what, log figure, study limit, beyond, said) for each limit the study declares and the log
    reads (``log``: vehicle_limits.log_extremes; ``study``: vehicle_limits.StudyLimits)."""
    deg, noise, rows = math.degrees, NOISE_SIGMAS * _finite_or_zero(log.get("angle_noise")), []
    if log.get("min_radius") and study.min_radius:
        rows.append(("turn radius", log["min_radius"], study.min_radius, log["min_radius"] * LIMIT_MARGIN < study.min_radius,
                     f"a steady turn of {log['min_radius']:.2g} m radius (v / |yaw_rate| at t {log['radius_at']:.0f} s, "
                     f"its noise allowed for) against the tightest the study's vehicle makes, L / tan(delta_max) = "
                     f"{study.wheelbase:.3g} m / tan({deg(study.lock):.0f} deg) = {study.min_radius:.2g} m"))
    if log.get("steering_rate") and study.rate:
        rows.append(("steering rate", log["steering_rate"], study.rate,
                     log["steering_rate"] > RATE_MARGIN * study.rate + math.sqrt(2) * noise / log["rate_window"],
                     f"the wheels turning at {deg(log['steering_rate']):.0f} deg/s (delta over {log['rate_window']:.2g} s) "
                     f"against the study's steering actuator at full rate, {deg(study.rate):.0f} deg/s"))
    if log.get("wheel_angle_third_largest") and study.lock:
        angle = log["wheel_angle_third_largest"]
        rows.append(("wheel angle", angle, study.lock, angle > LIMIT_MARGIN * study.lock + noise,
                     f"a wheel angle of {deg(angle):.0f} deg (the 3rd largest) against the study's lock, "
                     f"{deg(study.lock):.0f} deg"))
    if log.get("speed") and study.top_speed:
        rows.append(("speed", log["speed"], study.top_speed, log["speed"] > LIMIT_MARGIN * study.top_speed,
                     f"a speed of {log['speed']:.3g} m/s (99.5th percentile) against the study's top speed, "
                     f"{study.top_speed:.3g} m/s"))
    if log.get("lateral_acceleration_p995") and study.friction:
        grip = study.friction * GRAVITY
        rows.append(("lateral acceleration", log["lateral_acceleration_p995"], grip,
                     log["lateral_acceleration_p995"] > LIMIT_MARGIN * grip,
                     f"a lateral acceleration of {log['lateral_acceleration_p995']:.3g} m/s2 (99.5th percentile) against "
                     f"the {grip:.3g} m/s2 its tyres hold (friction {study.friction:.2g})"))
    return rows


ON_DELTA = ("steering rate", "wheel angle")     # the limits the log reads on its wheel-angle channel


def beyond_limits(log: Mapping, study, turns_ratio: float | None = None) -> dict:
    """{beyond, compared, undecided}: what the log does beyond the study's vehicle's limits, past
    LIMIT_MARGIN and its reading noise (the tightest steady turn against L / tan(delta_max), the
    wheels' rate against the actuator's full rate, the wheel angle against the lock, the speed
    against the top speed, the lateral acceleration against the tyres' friction times g); what was
    compared; and, when only the wheel-angle channel's figures are beyond, why a wheel-angle sensor
    reading high is not ruled out (sensor_reading; ``turns_ratio``: the log's turns' wheelbase
    over the study's)."""
    rows = _limit_rows(log, study)
    unit = {"turn radius": ("m", 1.0), "steering rate": ("deg/s", 180 / math.pi), "wheel angle": ("deg", 180 / math.pi),
            "speed": ("m/s", 1.0), "lateral acceleration": ("m/s2", 1.0)}
    said = ", ".join(f"{what} {a * unit[what][1]:.3g} {unit[what][0]} (study's limit {b * unit[what][1]:.3g})"
                     for what, a, b, _, _ in rows)
    compared = (f"the log against the study's vehicle's limits (beyond only past {LIMIT_MARGIN:g} x them, "
                f"{RATE_MARGIN:g} x the actuator's rate, and the log's reading noise): {said or 'none the study declares and the log reads'}")
    over = [(what, a / b) for what, a, b, beyond, _ in rows if beyond]
    faster = [text for what, a, b, beyond, text in rows if what == "steering rate" and not beyond and a > LIMIT_MARGIN * b]
    undecided = sensor_reading(max(k for _, k in over), turns_ratio) if over and all(
        what in ON_DELTA for what, _ in over) else None
    noted = (f"{faster[0]} (more than {LIMIT_MARGIN:g} x, under {RATE_MARGIN:g} x): a faster actuator than the "
             f"study declares, a wheel-angle sensor reading high, or another vehicle's; not judged a wrong study "
             f"below {RATE_MARGIN:g} x") if faster else None
    return {"beyond": [text for *_, beyond, text in rows if beyond], "compared": compared, "undecided": undecided,
            "noted": noted}


def sensor_reading(k: float, turns_ratio: float | None) -> str | None:
    """Why a wheel-angle sensor (or a steering map) reading ``k`` x high (the log's rate or angle over
    the study's limit) may be what the log shows instead (None: ruled out): the log's turns, which
    such a reading lengthens as much (L_turns = g L, g >= k), not shorter than k / 1.1 x the study's
    wheelbase; without turns, a gain inside a calibration error's range (CALIBRATION)."""
    if turns_ratio is None and k >= CALIBRATION[1] or turns_ratio is not None and turns_ratio * math.exp(DECLARED) < k:
        return None
    turns = ("the log has no steady turns to tell" if turns_ratio is None else
             f"the log's turns give {turns_ratio:.2g} x the study's wheelbase, as such a reading would")
    return f"a wheel-angle sensor or steering map reading {k:.2g} x high shows the same: {turns}"


def cannot_do(beyond: list[str], suggestion: str, declared: bool, undecided: str | None = None) -> str:
    """The statement on a study whose vehicle cannot do what the log shows (``beyond``, ``undecided``:
    beyond_limits'; ``suggestion``: study_fit.suggestion's; ``declared``: the user gave the study);
    "cannot decide" first when a sensor's reading is not ruled out."""
    whose = ("the study is another vehicle, or the limits it declares are not this vehicle's" if declared
             else "the study is not this vehicle's")
    text = (f"the study's vehicle cannot do what the log shows: {'; '.join(beyond)} (more than {LIMIT_MARGIN:g} x): "
            f"{whose}; its effects are judged against a vehicle the log is not; instead: {suggestion}, and "
            f"diagnose again (--study)")
    return f"{UNDECIDED}{text}; or {undecided}" if undecided else text
