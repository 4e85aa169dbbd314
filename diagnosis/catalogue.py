"""The catalogue of model extensions a diagnosis tests (issue 6, step 2).

Each effect names the subsystem it lives in, the replay stages whose residuals it changes, its
parameters (SI, with the bounds searched and a typical scale for the optimiser), a materiality
threshold (smaller fitted values are not worth a model change, whatever the statistics say) and
the component option that switches it on in a study (step 3).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from components.models.yaw_dynamics import GRAVITY

DEG = math.pi / 180.0


@dataclass(frozen=True)
class Parameter:
    name: str                 # key of the replay's value mapping
    unit: str                 # SI unit
    scale: float              # typical magnitude (optimiser scaling)
    lower: float
    upper: float
    display_unit: str = ""
    display_factor: float = 1.0


@dataclass(frozen=True)
class Effect:
    id: str
    subsystem: str
    stages: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    starts: tuple[tuple[float, ...], ...]                     # starting values of the parameters
    threshold: str                                            # the materiality rule, in words
    material: Callable[[dict[str, float], dict[str, float]], bool]   # (fitted, baseline) -> bool
    options: Callable[[dict[str, float], dict[str, float]], list[tuple[str, str, float]]]
    # (fitted, baseline) -> [(role, parameter, SI value)] to set in a study
    hypothesis: str


def slope_angle_and_heading(v: dict[str, float]) -> tuple[float, float]:
    """(slope angle, fall-line azimuth) from the lateral-acceleration components g sin(phi) (cos, sin)(psi_d)."""
    mag = math.hypot(v["slope_east"], v["slope_north"])
    return math.asin(min(mag / GRAVITY, 1.0)), math.atan2(v["slope_north"], v["slope_east"])


# the baseline's re-fitted ("uncertain") parameters of each stage
UNCERTAIN = {
    "steering": (Parameter("steering_time_constant", "s", 0.05, 0.005, 1.0),),
    "yaw": (Parameter("cornering_front_scale", "1", 0.2, 0.4, 2.5), Parameter("cornering_rear_scale", "1", 0.2, 0.4, 2.5)),
    "position": (),
}

SIGNALS = {"steering": ("delta", "rad"), "yaw": ("yaw_rate", "rad/s"), "position": ("antenna_position", "m")}

CATALOGUE: tuple[Effect, ...] = (
    Effect("actuator_delay", "steering", ("steering",),
           (Parameter("command_delay", "s", 0.1, 0.0, 0.6, "s", 1.0),), ((0.05,), (0.15,), (0.3,)),
           "delay >= 0.05 s",
           lambda f, b: f["command_delay"] - b["command_delay"] >= 0.05,
           lambda f, b: [("steering", "command_delay", f["command_delay"])],
           "the wheels follow the command late: a transport delay in the valve drive or the bus"),
    Effect("steering_deadband", "steering", ("steering",),
           (Parameter("steering_deadband", "rad", 0.02, 0.0, 0.12, "deg", 1 / DEG),),
           ((0.5 * DEG,), (2.0 * DEG,), (4.0 * DEG,)),
           "dead-band >= the baseline's + 0.4 deg",
           lambda f, b: f["steering_deadband"] - b["steering_deadband"] >= 0.4 * DEG,
           lambda f, b: [("steering", "angle_deadband", max(0.0, f["steering_deadband"] - b["steering_deadband"]))],
           "small steering corrections are not executed: play in the linkage or a valve dead-band"),
    Effect("steering_rate_limit", "steering", ("steering",),
           (Parameter("steering_rate_limit", "rad/s", 0.3, 0.03, 10.0, "deg/s", 1 / DEG),),
           ((0.8,), (0.4,), (0.2,)),
           "rate limit <= 0.8 x the baseline's",
           lambda f, b: f["steering_rate_limit"] <= 0.8 * b["steering_rate_limit"],
           lambda f, b: [("steering", "rate_limit", f["steering_rate_limit"])],
           "large steering moves are slower than the model: less pump flow than assumed"),
    Effect("steering_offset", "steering angle sensor (wheel angle seen by the tyres)", ("yaw",),
           (Parameter("steer_angle_offset", "rad", 0.02, -0.15, 0.15, "deg", 1 / DEG),), ((0.0,),),
           "|offset| >= 0.3 deg",
           lambda f, b: abs(f["steer_angle_offset"] - b["steer_angle_offset"]) >= 0.3 * DEG,
           lambda f, b: [("tractor", "steer_angle_offset", f["steer_angle_offset"])],
           "the wheel-angle sensor is zeroed wrongly: straight driving needs a non-zero reading"),
    Effect("yaw_rate_bias", "gyro", ("yaw", "position"),
           (Parameter("yaw_rate_bias", "rad/s", 0.01, -0.2, 0.2, "rad/s", 1.0),), ((0.0,),),
           "|bias| >= 0.004 rad/s",
           lambda f, b: abs(f["yaw_rate_bias"] - b["yaw_rate_bias"]) >= 0.004,
           lambda f, b: [("gyro", "bias", f["yaw_rate_bias"])],
           "the gyro reads a constant offset: the integrated yaw rate turns away from the GPS track"),
    Effect("gps_latency", "gps", ("position",),
           (Parameter("gps_latency", "s", 0.1, 0.0, 1.0, "s", 1.0),), ((0.05,), (0.25,)),
           "latency >= 0.05 s",
           lambda f, b: f["gps_latency"] - b["gps_latency"] >= 0.05,
           lambda f, b: [("gps", "latency", f["gps_latency"])],
           "the GPS reports where the antenna was a moment ago"),
    Effect("speed_dependent_cornering", "yaw (tyre cornering stiffness)", ("yaw",),
           (Parameter("cornering_speed_slope", "s/m", 0.1, -0.35, 0.8, "1/(m/s)", 1.0),), ((0.0,), (-0.2,), (0.3,)),
           "|k| >= 0.08 per m/s",
           lambda f, b: abs(f["cornering_speed_slope"] - b["cornering_speed_slope"]) >= 0.08,
           lambda f, b: [("tractor", "cornering_speed_slope", f["cornering_speed_slope"]),
                         ("tractor", "cornering_reference_speed", b["cornering_reference_speed"])],
           "the tyres' cornering stiffness changes with speed: one model does not fit every speed"),
    Effect("side_slope", "yaw (terrain: a side slope)", ("yaw",),
           (Parameter("slope_east", "m/s2", 0.5, -3.0, 3.0), Parameter("slope_north", "m/s2", 0.5, -3.0, 3.0)),
           ((0.0, 0.0),),
           "slope >= 1.5 deg",
           lambda f, b: slope_angle_and_heading(f)[0] >= 1.5 * DEG,
           lambda f, b: [("tractor", "slope_angle", slope_angle_and_heading(f)[0]), ("tractor", "slope_downhill_heading", slope_angle_and_heading(f)[1])],
           "the field is tilted: gravity pulls sideways, by an amount that follows the heading"),
    Effect("antenna_lever_arm", "gps (antenna mounting)", ("position",),
           (Parameter("antenna_forward", "m", 0.5, -4.0, 4.0, "m", 1.0),
            Parameter("antenna_left", "m", 0.5, -2.0, 2.0, "m", 1.0)), ((0.0, 0.0),),
           "lever arm >= 0.15 m",
           lambda f, b: math.hypot(f["antenna_forward"] - b["antenna_forward"], f["antenna_left"] - b["antenna_left"]) >= 0.15,
           lambda f, b: [("tractor", "antenna_forward", f["antenna_forward"]), ("tractor", "antenna_left", f["antenna_left"])],
           "the antenna is not where the model puts it: in turns it swings on a different radius"),
)

EFFECT_IDS = tuple(e.id for e in CATALOGUE)
