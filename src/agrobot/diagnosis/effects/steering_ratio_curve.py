"""The steering ratio varies with the angle (a variable-ratio rack, Ackermann geometry read at
one wheel, a nonlinear linkage): the wheels turn delta (1 + c delta^2) for a reading of delta,
right in small turns and off in tight ones.

The curvature c is relative to the baseline's steering geometry: the turned angle then drives the
yaw model as the baseline's does (delta, or tan(delta) under steering_geometry "tan",
components.tractor_yaw_plant.steer_input), so an Ackermann machine replayed under "tan" has c = 0
and the cubic term of tan itself (c = 1/3 against "w") is not read as a ratio curve."""
import copy
from dataclasses import replace

from ..effect import Effect, Parameter

DELTA_KEY = "log_delta_p99"      # the log's 99th percentile of |delta| [rad], set by the selection
REFERENCE_ANGLE = 0.3            # |delta| [rad] at which the ranges below hold (a tractor's or a robot's tight turn)


class SteeringRatioCurve(Effect):
    id = "steering_ratio_curve"
    subsystem = "steering geometry (ratio varying with the angle)"
    stages = ("yaw", "steering")     # the turns, and the actuator's rate read through the map
    tested_on = ("steering",)
    order = 3.0                      # last: the wheels turn g (1 + c g^2) for the angle g the rest gives
    parameters = (Parameter("steering_ratio_curvature", "1/rad2", 0.3, -1.5, 3.0, "1/rad2", 1.0, (-3.0, 8.0)),)
    starts = ((0.0,), (0.8,), (-0.5,))
    threshold = "the ratio changes by >= 4 % at the log's 99th percentile of |delta|"
    hypothesis = "the steering ratio varies with the angle: the wheels turn more (or less) than the reading in tight turns"
    experiment = ("steady circles at walking speed at several wheel angles up to full lock: the kinematic "
                  "yaw rate v tan(delta) / L against the gyro gives the ratio at each angle (against the "
                  "baseline's steering geometry)")
    imitated_by = ("scale_disagreement", "opposite_sign")

    def baseline(self, study):
        return {"steering_ratio_curvature": 0.0}

    def material(self, fitted, base):
        d = base.get(DELTA_KEY, 0.0)
        return abs(fitted["steering_ratio_curvature"]) * d * d >= 0.04

    def for_log(self, log):
        """On a log steered less than REFERENCE_ANGLE (a car: 1 deg), the ranges scaled by
        (REFERENCE_ANGLE / |delta|_99)^2: the same changes of the ratio, c delta^2, at its angles."""
        d = log.get(DELTA_KEY, 0.0)
        if not 0.0 < d < REFERENCE_ANGLE:
            return self
        k = (REFERENCE_ANGLE / d) ** 2
        scaled = copy.copy(self)
        scaled.parameters = tuple(replace(p, scale=p.scale * k, lower=p.lower * k, upper=p.upper * k,
                                          limit=(p.limit[0] * k, p.limit[1] * k)) for p in self.parameters)
        scaled.starts = tuple(tuple(x * k for x in start) for start in self.starts)
        return scaled

    def wheel_angle(self, x, v, t):
        """x (1 + c x^2)."""
        c = v["steering_ratio_curvature"]
        return x * (1.0 + c * x * x) if c else None

    def options(self, fitted, base, study):
        raise KeyError("steering ratio curve (a lookup of wheel angle against the reading)")
