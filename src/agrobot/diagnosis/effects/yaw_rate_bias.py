"""The gyro reads a constant offset: the integrated yaw rate turns away from the GPS track."""
import math

from ..effect import Effect, Parameter


class YawRateBias(Effect):
    id = "yaw_rate_bias"
    subsystem = "gyro"
    stages = ("yaw", "position")
    parameters = (Parameter("yaw_rate_bias", "rad/s", 0.01, -0.2, 0.2, "deg/s", 180.0 / math.pi, (-0.2, 0.2)),)
    starts = ((0.0,),)
    enters = {"gyro.bias": "yaw_rate_bias"}
    threshold = "|bias| >= 0.229 deg/s"
    hypothesis = "the gyro reads a constant offset: the integrated yaw rate turns away from the GPS track"
    experiment = "30 s standing still: a gyro bias reads a yaw rate with the vehicle at rest"
    imitated_by = ("scale_disagreement", "opposite_sign")

    def hypothesis_for(self, stages):
        if "position" in stages:
            return self.hypothesis
        return "the gyro reads a constant offset: it reads a turn when the vehicle drives straight"

    def baseline(self, study):
        return {"yaw_rate_bias": study.parameters("gyro", {"bias": 0.0})["bias"]}

    def material(self, fitted, base):
        return abs(fitted["yaw_rate_bias"] - base["yaw_rate_bias"]) >= 0.004

    def options(self, fitted, base, study):
        return [("gyro", "bias", fitted["yaw_rate_bias"])]

    def plausibility(self, values, ctx):
        """A bias beyond the gyro class's drift is no drift."""
        bound = ctx.vehicle.gyro_bias_bound
        if bound and abs(values.get("yaw_rate_bias", 0.0)) > bound:
            return [f"a gyro bias of {math.degrees(values['yaw_rate_bias']):.2f} deg/s is beyond what a gyro of this "
                    f"class drifts ({math.degrees(bound):g} deg/s): a steering offset or a side slope seen through the "
                    f"yaw rate, or a gyro mounted tilted"]
        return []
