"""A 'measured' field log from a truth model that is not the project's code path.

Written from the paper's equations of motion (section III, RLF: relaxation length at the front
axle) in scalar form, integrated with Heun's method at 200 Hz (the project's plant uses exact ZOH
steps with matrix exponentials), with its own steering loop (first order, rate limit, a 15 ms
spool lag the baseline does not model), its own parameters drawn around the paper's values, and
its own sensors sampled at 20 Hz. Any combination of catalogue effects can be injected, and
faults the diagnosis catalogue does not list (UNLISTED); the diagnosis under test is not told which. Tests and benchmarks both use it (harness.hidden_effects runs the diagnosis
on its logs).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from agrobot.components.test_drive_plan import driving_plan
from harness import steering_maps

DEG = math.pi / 180
G = 9.81
TABLE = dict(m=700.0, I=280.0, l_f=1.0, l_r=0.4, C_f=8000.0, C_r=90000.0, sigma_f=0.1942)
STEERING_TIME_CONSTANT = 0.0667     # the paper tractor's closed-loop steering (components.models.steering_equivalent)
STEERING_RATE = 60 * DEG
STEERING_DEADBAND = 0.5 / 150       # valve dead-band / kp of the paper tractor

# the magnitude of a gyro bias the truth draws [rad/s]: a tractor's guidance gyro (industrial MEMS, no
# offset learnt at standstill) 0.6-1.7 deg/s, the order of a consumer or industrial MEMS part's
# zero-rate offset (BMI055: 1 deg/s typical, 3 maximal; BMI160: 3 and 10); a car's CAN yaw rate comes
# from its stability control's automotive sensor, temperature-compensated and its offset learnt at
# each standstill: 0.3-0.9 deg/s, inside the car class's 1 deg/s (identification.vehicle.CLASSES)
TRACTOR_GYRO_BIAS = (0.01, 0.03)
CAR_GYRO_BIAS = (0.3 * DEG, 0.9 * DEG)

# other vehicles the truth can be (``vehicle``): their own parameters, steering, sensors and driving;
# "car" is a mid-size passenger car (studies/passenger_car.toml is its baseline) driven at 10, 20
# and 30 m/s with road-wheel angles a twentieth of the tractor's (the same lateral accelerations,
# roughly), an electric power steering and a CAN steering-angle sensor of 0.01 deg at the road wheel
VEHICLES = {
    "tractor": dict(table=TABLE, tau=STEERING_TIME_CONSTANT, rate=STEERING_RATE, deadband=STEERING_DEADBAND,
                    speeds=(1.0, 2.0, 3.0), steer_scale=1.0, resolution=0.1 * DEG, gyro_noise=0.005, v_ref=2.0),
    "car": dict(table=dict(m=1500.0, I=2500.0, l_f=1.2, l_r=1.5, C_f=80000.0, C_r=100000.0, sigma_f=0.5),
                tau=0.05, rate=40 * DEG, deadband=0.02 * DEG, speeds=(10.0, 20.0, 30.0), steer_scale=0.05,
                resolution=0.01 * DEG, gyro_noise=0.002, v_ref=20.0, gyro_bias=CAR_GYRO_BIAS),
    # the same car driven hard: road-wheel angles four times the car's at 15-35 m/s (|a_y| to 8-10 m/s2,
    # beyond the tyres' linear range), as a track day or a vehicle-dynamics test records it
    "car_hard": dict(table=dict(m=1500.0, I=2500.0, l_f=1.2, l_r=1.5, C_f=80000.0, C_r=100000.0, sigma_f=0.5),
                     tau=0.05, rate=40 * DEG, deadband=0.02 * DEG, speeds=(15.0, 25.0, 35.0), steer_scale=0.3,
                     resolution=0.01 * DEG, gyro_noise=0.002, v_ref=20.0, gyro_bias=CAR_GYRO_BIAS),
    # a small Ackermann field robot (a converted mower: 120 kg, wheelbase l_f + l_r = 1.27 m, outline
    # 1.9 m x 1.1 m) with a fast servo steering, driven at 0.5-0.85 m/s by default: lateral
    # accelerations below 1 m/s2, the kinematic regime r = v tan(delta) / L (make_log's ``speeds``
    # drives it faster); harness.vehicle_classes.study is its baseline study
    "small_ackermann": dict(table=dict(m=120.0, I=30.0, l_f=0.6, l_r=0.67, C_f=3000.0, C_r=3000.0, sigma_f=0.02),
                            tau=0.035, rate=1.5, deadband=0.002, speeds=(0.5, 0.65, 0.85), steer_scale=1.0,
                            resolution=0.1 * DEG, gyro_noise=0.005, v_ref=0.65, min_speed=0.3,
                            length=1.9, width=1.1),
}
SMALL_ACKERMANN = VEHICLES["small_ackermann"]
SMALL_WHEELBASE = SMALL_ACKERMANN["table"]["l_f"] + SMALL_ACKERMANN["table"]["l_r"]     # 1.27 m

EFFECTS = ("actuator_delay", "steering_deadband", "steering_rate_limit", "steering_offset", "yaw_rate_bias",
           "gps_latency", "speed_dependent_cornering", "side_slope", "antenna_lever_arm")


# faults outside the diagnosis catalogue: the diagnosis must call them "unexplained"
UNLISTED = ("steering_sensor_gain", "gyro_scale_factor", "wheel_slip", "tyre_saturation")

# effects real vehicles show, added after the catalogue above (drawn from a stream of their own so the
# draws of the others stay): a localisation output at another point of the vehicle on a lagging clock,
# and a steering ratio that varies with the angle (the wheels turn delta (1 + c delta^2) for a reading
# delta: harness.steering_maps with curvature c)
LATER = ("position_reference", "steering_ratio_curve", "steering_clock")

# healthy truths: ways a tractor with no fault differs from the baseline (the diagnosis must say "none")
HEALTHY = ("servo", "servo_guard", "rear_relaxation", "relaxation", "noisy_sensors", "quiet_sensors",
           "one_speed", "field_driving", "servo+rear_relaxation+noisy_sensors")


def draw_healthy(variant: str, rng: np.random.Generator) -> dict:
    """The truth settings of a healthy variant (several joined by '+'):

    - servo: the paper's servo steering instead of a first-order loop: a PI (150 V/rad, 20 V/(rad s)
      x 0.8-1.2) at 1 kHz on a 1-deg potentiometer, a 0.3-0.7 V valve dead-band around neutral, a
      20-40 ms spool lag, 60 deg/s x 0.9-1.1 at full opening; the log's wheel angle is the
      potentiometer's reading (it hunts between two levels); servo_guard: the same with the PI
      ignoring errors within half a potentiometer step (as the shipped figure-8's controller);
    - rear_relaxation: a rear relaxation length of 0.3-1.0 m (with the Table's stiffnesses a longer
      one leaves the yaw mode at 11-13 rad/s almost undamped, and at 1.6 m, the paper's, unstable:
      not a healthy tractor);
      relaxation: the front one x 0.5-2;
    - noisy_sensors / quiet_sensors: gyro, speed, GPS and wheel-angle noise x 2-3 / x 0.3-0.6;
    - one_speed: the whole log at one speed (1.5-2.5 m/s);
    - field_driving: long straights with small corrections and a headland turn every 30-60 s
      (little of the multisine excitation)."""
    out: dict = {}
    u = rng.uniform
    for part in effect_list(variant):
        if part in ("servo", "servo_guard"):
            out.update(steering="servo", guard=part == "servo_guard", kp=150.0 * u(0.8, 1.2), ki=20.0 * u(0.8, 1.2),
                       valve_deadband=u(0.3, 0.7), spool=u(0.02, 0.04), servo_rate=STEERING_RATE * u(0.9, 1.1),
                       resolution=1.0 * DEG)
        elif part == "rear_relaxation":
            out["sigma_r"] = u(0.3, 1.0)
        elif part == "relaxation":
            out["sigma_f_factor"] = float(np.exp(u(math.log(0.5), math.log(2.0))))
        elif part in ("noisy_sensors", "quiet_sensors"):
            lo, hi = (2.0, 3.0) if part == "noisy_sensors" else (0.3, 0.6)
            out["noise"] = float(u(lo, hi))
        elif part == "one_speed":
            out["speeds"] = (float(np.round(u(1.5, 2.5), 1)),)
        elif part == "field_driving":
            out["plan"] = "field"
        else:
            raise ValueError(f"unknown healthy variant {part!r}; known: {HEALTHY}")
    return out


def draw_unlisted(effect: str, rng: np.random.Generator) -> dict[str, float]:
    """Magnitudes of the unlisted faults:

    - steering_sensor_gain: the wheel-angle sensor reads g > 1 x the angle; the steering loop closes
      on the reading, so the wheels turn 1/g as far as the log says (g < 1 would also make the
      logged steering slower than its rate limit: a catalogued steering_rate_limit, rightly found);
    - gyro_scale_factor: the gyro reads s x the yaw rate;
    - wheel_slip: the logged speed (wheel speed) is (1 + slip) x the ground speed;
    - tyre_saturation: the tyre forces saturate, F = C alpha / (1 + |alpha| / alpha_s).
    """
    sign = 1.0 if rng.random() < 0.5 else -1.0
    u = rng.uniform
    return {"steering_sensor_gain": {"sensor_gain": 1.0 + u(0.12, 0.2)},
            "gyro_scale_factor": {"gyro_scale": 1.0 + sign * u(0.08, 0.15)},
            "wheel_slip": {"slip": u(0.06, 0.12)},
            "tyre_saturation": {"alpha_s": u(2.0, 4.0) * DEG}}[effect]


def draw_later(effect: str, rng: np.random.Generator, l_r: float) -> dict[str, float]:
    """Magnitudes of the LATER effects: a point 0.8-1.6 m ahead of the centre of gravity (given, as
    the antenna, from the rear axle: l_r + that) and up to 0.3 m aside, stamped 0.15-0.35 s late;
    a ratio curvature c of 1.5-3 1/rad2 (8-17 % more wheel angle at 0.25 rad); the steering
    channels (delta_cmd, delta) stamped 0.3-0.9 s late against the others."""
    sign = 1.0 if rng.random() < 0.5 else -1.0
    u = rng.uniform
    return {"position_reference": {"forward": l_r + u(0.8, 1.6), "left": sign * u(0.0, 0.3), "latency": u(0.15, 0.35)},
            "steering_ratio_curve": {"ratio_curvature": u(1.5, 3.0)},
            "steering_clock": {"steering_clock": u(0.3, 0.9)}}[effect]


def draw_effect(effect: str | None, rng: np.random.Generator) -> dict[str, float]:
    """A magnitude a real tractor shows."""
    sign = 1.0 if rng.random() < 0.5 else -1.0
    u = rng.uniform
    return {
        None: {},
        "actuator_delay": {"delay": u(0.10, 0.25)},
        "steering_deadband": {"deadband": u(1.0, 3.0) * DEG},
        "steering_rate_limit": {"rate": u(10.0, 25.0) * DEG},
        "steering_offset": {"offset": sign * u(1.0, 3.0) * DEG},
        "yaw_rate_bias": {"bias": sign * u(*TRACTOR_GYRO_BIAS)},
        "gps_latency": {"latency": u(0.10, 0.30)},
        "speed_dependent_cornering": {"k": sign * u(0.15, 0.30)},
        "side_slope": {"slope": u(3.0, 6.0) * DEG, "downhill": u(-math.pi, math.pi)},
        "antenna_lever_arm": {"forward": u(0.4, 1.0), "left": sign * u(0.1, 0.4)},
    }[effect]


def effect_list(effect: str | tuple | list | None) -> list[str]:
    """None, one effect id, a '+'-joined string or a sequence of ids -> the list of ids."""
    if effect is None or effect == "none":
        return []
    if isinstance(effect, str):
        return [e for e in effect.split("+") if e]
    return list(effect)


def field_plan(rng: np.random.Generator, duration: float, rate: float = 20.0, speed: float = 2.0):
    """Field work: straights held by small corrections (steps of 0.5-2 deg every 2-6 s), a headland
    turn (a 20-30 deg U-turn of 12 s, slowing to 60 % of the working speed) every 30-60 s."""
    n = int(round(duration * rate))
    t = np.arange(n) / rate
    cmd = np.zeros(n)
    turns = []
    k, side = 0, rng.choice([-1.0, 1.0])
    while k < n:
        straight = int(rng.uniform(30.0, 60.0) * rate)
        j = k
        while j < min(n, k + straight):
            m = min(n, k + straight, j + int(rng.uniform(2.0, 6.0) * rate))
            cmd[j:m] = rng.uniform(-2.0, 2.0) * DEG * rng.choice([0.25, 1.0])
            j = m
        a = min(n, k + straight)
        b = min(n, a + int(12 * rate))
        peak = side * rng.uniform(20.0, 30.0) * DEG
        cmd[a:b] = np.interp(t[a:b] - a / rate, [0, 2, 10, 12], [0, peak, peak, 0])
        turns.append((a / rate, 12.0))
        side, k = -side, b

    def speed_of(time: float) -> float:
        ramp = min(time / 3.0, 1.0)
        slow = 0.0
        for start, length in turns:
            if start - 3.0 <= time <= start + length + 3.0:
                s = min((time - start + 3.0) / 3.0, 1.0, (start + length + 3.0 - time) / 3.0)
                slow = max(slow, 0.5 * (1 - math.cos(math.pi * max(s, 0.0))))
        return speed * (0.5 * (1 - math.cos(math.pi * ramp))) * (1.0 - 0.4 * slow)

    return t, cmd, speed_of


class Servo:
    """The paper's steering servo (section II) in scalar form, stepped at 1 kHz: a PI on the
    potentiometer's reading -> valve voltage (+-6 V about neutral, dead-band) -> spool lag ->
    wheel rate proportional to the opening -> +-45 deg stop."""

    def __init__(self, v: dict, deadband: float, rate_limit: float, sensor_gain: float, h: float = 0.001):
        self.kp, self.ki, self.db, self.spool_tau = v["kp"], v["ki"], v["valve_deadband"], v["spool"]
        self.full_rate, self.q, self.h = v["servo_rate"], v["resolution"], h
        self.angle_deadband = deadband + (0.5 * self.q if v.get("guard") else 0.0)
        self.rate_limit, self.sensor_gain = rate_limit, sensor_gain
        self.delta = self.opening = self.integral = 0.0
        self.alpha = 1.0 - math.exp(-h / self.spool_tau)

    def advance(self, cmd: float, duration: float) -> float:
        for _ in range(int(round(duration / self.h))):
            reading = self.q * round(self.sensor_gain * self.delta / self.q)
            err = cmd - reading
            d = self.angle_deadband
            err = err - d if err > d else (err + d if err < -d else 0.0)
            raw = self.kp * err + self.integral
            volts = max(-6.0, min(6.0, raw))
            if volts == raw or (raw > 6.0) != (err > 0):
                self.integral = max(-2.0, min(2.0, self.integral + self.ki * self.h * err))
            excess = abs(volts) - self.db
            target = math.copysign(min(excess / (6.0 - self.db), 1.0), volts) if excess > 0 else 0.0
            self.opening += self.alpha * (target - self.opening)
            move = self.full_rate * self.h * self.opening
            move = max(-self.rate_limit * self.h, min(self.rate_limit * self.h, move))
            self.delta = max(-45 * DEG, min(45 * DEG, self.delta + move))
        return self.delta


def make_log(seed: int, effect: str | tuple | list | None = None, duration: float = 240.0,
             scale: dict[str, float] | None = None, speeds: tuple[float, ...] | None = None,
             healthy: str | None = None, vehicle: str = "tractor",
             values: dict[str, float] | None = None, lateral: bool = False,
             rate: float = 20.0) -> tuple[pd.DataFrame, dict]:
    """The log and the truth; ``effect`` is None, one id, or several ('a+b' or a sequence) from
    EFFECTS and UNLISTED; ``scale`` multiplies entries of TABLE (m, I, l_f, l_r, C_f, C_r,
    sigma_f) to stress the diagnosis with a truth further from the baseline; ``healthy``: one or
    several of HEALTHY ('a+b'), ways the truth differs from the baseline without a fault
    (draw_healthy; drawn from a stream of their own, so the rest of the log's draws stay);
    ``vehicle``: a key of VEHICLES (steering effects' angles scale with its steering);
    ``values``: magnitudes that replace the drawn ones (``forward``, ``latency``, ``k``, ...; and
    ``reading_noise``, the wheel-angle sensor's white noise [rad], 0.05 deg);
    ``lateral``: add the measured lateral velocity at the centre of gravity ``vy`` [m/s] and the
    side-slip ``beta`` = atan(vy / v) [rad] (an optical or GNSS/INS sensor; noise 0.005 m/s);
    ``rate``: the command's and the sensors' rate [Hz], a divisor of the 200 Hz integration."""
    if vehicle not in VEHICLES:
        raise ValueError(f"unknown vehicle {vehicle!r}; known: {sorted(VEHICLES)}")
    veh = VEHICLES[vehicle]
    rng = np.random.default_rng(seed)
    ids = effect_list(effect)
    unknown = [i for i in ids if i not in EFFECTS and i not in UNLISTED and i not in LATER]
    if unknown:
        raise ValueError(f"unknown truth effects {unknown}; known: {EFFECTS + UNLISTED + LATER}")
    e, hv, p, tau = _drawn_truth(seed, rng, ids, veh, scale, healthy, values)
    if hv.get("plan") == "field":
        t_log, cmd, speed_of = field_plan(rng, duration, rate)
    else:
        t_log, cmd, speed_of = driving_plan(rng, duration, rate, speeds_cycle=hv.get("speeds", speeds or veh["speeds"]))
    cmd = cmd * veh["steer_scale"]
    rec, times, sub = _driven(rng, e, hv, p, veh, tau, len(t_log), cmd, speed_of, rate)
    frame = _measured(rng, e, hv, p, veh, rec, times, sub, t_log, cmd, speed_of, lateral)
    truth = {"effect": "+".join(ids) or "none", "effects": ids, **e, "tau": tau, "C_f": p["C_f"], "C_r": p["C_r"],
             "sigma_f": p["sigma_f"],
             "vehicle": vehicle, "v_ref": veh["v_ref"],
             "healthy": healthy or "", **{f"healthy_{k}": v for k, v in hv.items()}}
    return frame, truth


def _drawn_truth(seed, rng, ids, veh, scale, healthy, values) -> tuple[dict, dict, dict, float]:
    """(the effects' magnitudes, the healthy differences, the vehicle's parameters, the steering's time
    constant), drawn in this order: the catalogue's effects from ``rng``, unlisted, healthy and later
    ones from streams of their own (so adding one leaves the others' draws), then the parameters'
    spread from ``rng``."""
    e: dict[str, float] = {}
    for i in [i for i in ids if i in EFFECTS] or [None]:
        e.update(draw_effect(i, rng))
    side = np.random.default_rng([seed, 1])           # unlisted faults: the catalogue draws stay as they were
    for i in ids:
        if i in UNLISTED:
            e.update(draw_unlisted(i, side))
    for key in ("offset", "deadband"):
        if key in e:
            e[key] *= veh["steer_scale"]
    if "bias" in e and "gyro_bias" in veh:      # the tractor's draw mapped onto the vehicle's gyro's range
        (lo, hi), (t_lo, t_hi) = veh["gyro_bias"], TRACTOR_GYRO_BIAS
        e["bias"] = math.copysign(lo + (abs(e["bias"]) - t_lo) / (t_hi - t_lo) * (hi - lo), e["bias"])
    hv = draw_healthy(healthy, np.random.default_rng([seed, 2])) if healthy else {}
    p = dict(veh["table"])
    later = np.random.default_rng([seed, 3])
    for i in ids:
        if i in LATER:
            e.update(draw_later(i, later, p["l_r"] * (scale or {}).get("l_r", 1.0)))
    e.update(values or {})
    for key, factor in (scale or {}).items():
        p[key] *= factor
    for k, lo, hi in (("C_f", 0.85, 1.15), ("C_r", 0.85, 1.15), ("sigma_f", 0.9, 1.1)):
        p[k] *= rng.uniform(lo, hi)
    p["sigma_f"] *= hv.get("sigma_f_factor", 1.0)
    return e, hv, p, veh["tau"] * rng.uniform(0.8, 1.2)


def _driven(rng, e, hv, p, veh, tau, n, cmd, speed_of, log_rate=20.0) -> tuple[np.ndarray, np.ndarray, int]:
    """(the states at 200 Hz, their times, the substeps per sample at ``log_rate``): the steering loop, the
    relaxed-tyre yaw dynamics with the truth's faults and the pose, by Heun's method from a drawn
    heading. State: delta, spool, v_y, r, alpha_f, psi, x, y, alpha_r."""
    rate = e.get("rate", veh["rate"])
    dead = veh["deadband"] + e.get("deadband", 0.0)
    delay, offset, curve = e.get("delay", 0.0), e.get("offset", 0.0), e.get("ratio_curvature", 0.0)
    k_corner, v_ref = e.get("k", 0.0), veh["v_ref"]
    slope, downhill = e.get("slope", 0.0), e.get("downhill", 0.0)
    sigma_r, tau_spool = hv.get("sigma_r", 0.0), 0.015
    m, I, lf, lr, sf = p["m"], p["I"], p["l_f"], p["l_r"], p["sigma_f"]
    g_slope = G * math.sin(slope)
    sensor_gain = e.get("sensor_gain", 1.0)
    alpha_s = e.get("alpha_s", math.inf)
    servo = Servo(hv, e.get("deadband", 0.0), rate, sensor_gain) if hv.get("steering") == "servo" else None
    servo_rate = [0.0]                          # the servo's mean wheel rate over the current step

    def deriv(time, s):
        delta, spool, vy, r, af, psi, x, y, ar_state = s
        if servo is None:
            k = int(math.floor((time - delay) * log_rate + 1e-9))
            c = cmd[min(max(k, 0), len(cmd) - 1)]
            reading = steering_maps.reading(delta, curvature=curve) if curve else delta
            err = c - sensor_gain * reading         # the loop closes on the sensor's reading
            err = err - dead if err > dead else (err + dead if err < -dead else 0.0)
            want = max(-rate, min(rate, err / tau))
            d_delta, d_spool = spool, (want - spool) / tau_spool
        else:
            d_delta, d_spool = servo_rate[0], 0.0
        v = speed_of(time)
        scale = max(0.2, 1.0 + k_corner * (v - v_ref) * (2.0 / v_ref))      # relative: k per m/s at 2 m/s
        cf, cr = p["C_f"] * scale, p["C_r"] * scale
        vv = max(v, veh.get("min_speed", 0.8))    # the slip equations divide by v; below it scaled (v / vv)
        ar = ar_state if sigma_r > 0 else (vy - lr * r) / vv
        a_lat = g_slope * math.sin(downhill - psi)
        sat_f, sat_r = 1.0 + abs(af) / alpha_s, 1.0 + abs(ar) / alpha_s
        dvy = -vv * r + (-cf * af / sat_f - cr * ar / sat_r) / m + a_lat
        dr = (-lf * cf * af / sat_f + lr * cr * ar / sat_r) / I
        daf = (vy + lf * r - vv * (delta + offset + af)) / sf
        dar = (vy - lr * r - vv * ar_state) / sigma_r if sigma_r > 0 else 0.0
        c_, s_ = math.cos(psi), math.sin(psi)
        return (d_delta, d_spool, dvy * (v / vv), dr * (v / vv), daf * (v / vv), r,
                v * c_ - vy * s_, v * s_ + vy * c_, dar * (v / vv))

    sub = int(round(200.0 / log_rate))        # 200 Hz internal steps per logged sample
    h = (1.0 / log_rate) / sub
    state = (0.0,) * 5 + (rng.uniform(-math.pi, math.pi), 0.0, 0.0, 0.0)
    rec = np.empty((n * sub, 9))
    times = np.arange(n * sub) * h
    for i in range(n * sub):
        rec[i] = state
        t0 = times[i]
        if servo is not None:                 # the servo runs at 1 kHz; the wheel angle enters linearly over the step
            k = int(math.floor((t0 - delay) * log_rate + 1e-9))
            before = servo.delta
            servo_rate[0] = (servo.advance(cmd[min(max(k, 0), len(cmd) - 1)], h) - before) / h
        k1 = deriv(t0, state)
        s1 = tuple(a + h * b for a, b in zip(state, k1))
        k2 = deriv(t0 + h, s1)
        state = tuple(a + 0.5 * h * (b + c) for a, b, c in zip(state, k1, k2))
    return rec, times, sub


def _measured(rng, e, hv, p, veh, rec, times, sub, t_log, cmd, speed_of, lateral) -> pd.DataFrame:
    """The log the machine would record (20 Hz unless told): the antenna's position (lever arm, latency), the
    wheel-angle sensor (gain, ratio curve, resolution), the speed (slip) and the gyro (scale, bias),
    each with its noise; channels stamped late where the truth says so."""
    n, lr = len(t_log), p["l_r"]
    curve, sensor_gain = e.get("ratio_curvature", 0.0), e.get("sensor_gain", 1.0)
    delta, r, psi, x, y = rec[:, 0], rec[:, 3], rec[:, 5], rec[:, 6], rec[:, 7]
    fwd, left = e.get("forward", 0.0), e.get("left", 0.0)
    c, s = np.cos(psi), np.sin(psi)
    ax = x - lr * c + fwd * c - left * s
    ay = y - lr * s + fwd * s + left * c
    idx = np.arange(n) * sub
    lat = e.get("latency", 0.0)
    gx, gy = np.interp(t_log - lat, times, ax), np.interp(t_log - lat, times, ay)
    noise = rng.standard_normal((6, n)) * hv.get("noise", 1.0)
    q = hv.get("resolution", veh["resolution"])
    frame = pd.DataFrame({
        "t": t_log,
        "delta_cmd": cmd,
        "delta": q * np.round((sensor_gain * steering_maps.reading(delta[idx], curvature=curve)
                               + e.get("reading_noise", 0.05 * DEG) * noise[0]) / q),
        "v": (1.0 + e.get("slip", 0.0)) * np.array([speed_of(tt) for tt in t_log]) + 0.02 * noise[1],
        "yaw_rate": e.get("gyro_scale", 1.0) * r[idx] + e.get("bias", 0.0) + veh["gyro_noise"] * noise[2],
        "x": gx + 0.02 * noise[3],
        "y": gy + 0.02 * noise[4],
    })
    late = e.get("steering_clock", 0.0)
    if late:                                  # the steering channels stamped late: delta_log(t) = delta(t - late)
        for col in ("delta_cmd", "delta"):
            frame[col] = np.interp(t_log - late, t_log, frame[col].to_numpy(float))
    if lateral:
        vy_log = rec[idx, 2] + 0.005 * rng.standard_normal(n)
        frame["vy"] = vy_log
        frame["beta"] = np.arctan2(vy_log, np.maximum(frame["v"].to_numpy(float), 0.1))
    return frame
