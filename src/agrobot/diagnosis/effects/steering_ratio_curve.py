"""The steering ratio varies with the angle (a variable-ratio rack, Ackermann geometry read at
one wheel, a nonlinear linkage): the wheels turn delta (1 + c delta^2) for a reading of delta,
right in small turns and off in tight ones."""
from ..effect import Effect, Parameter

DELTA_KEY = "log_delta_p99"      # the log's 99th percentile of |delta| [rad], set by the selection


class SteeringRatioCurve(Effect):
    id = "steering_ratio_curve"
    subsystem = "steering geometry (ratio varying with the angle)"
    stages = ("yaw", "steering")     # the turns, and the actuator's rate read through the map
    tested_on = ("steering",)
    parameters = (Parameter("steering_ratio_curvature", "1/rad2", 0.3, -1.5, 3.0, "1/rad2", 1.0, (-3.0, 8.0)),)
    starts = ((0.0,), (0.8,), (-0.5,))
    threshold = "the ratio changes by >= 4 % at the log's 99th percentile of |delta|"
    hypothesis = "the steering ratio varies with the angle: the wheels turn more (or less) than the reading in tight turns"
    experiment = ("steady circles at walking speed at several wheel angles up to full lock: the kinematic "
                  "yaw rate v tan(delta) / L against the gyro gives the ratio at each angle")
    imitated_by = ("scale_disagreement", "opposite_sign")

    def baseline(self, study):
        return {"steering_ratio_curvature": 0.0}

    def material(self, fitted, base):
        d = base.get(DELTA_KEY, 0.0)
        return abs(fitted["steering_ratio_curvature"]) * d * d >= 0.04

    def options(self, fitted, base, study):
        raise KeyError("steering ratio curve (a lookup of wheel angle against the reading)")
