"""The gyro reads s x the yaw rate (a scale-factor error, or a unit off by a factor): the yaw
rate is too high or too low in every turn, and the dead-reckoned heading turns s times too far."""
from ..effect import Effect, Parameter
from ..plausibility import scale_factor


class GyroScale(Effect):
    id = "gyro_scale"
    subsystem = "gyro (scale factor)"
    stages = ("yaw", "position")
    parameters = (Parameter("gyro_scale", "1", 0.1, 0.75, 1.3, "-", 1.0, (0.3, 3.0)),)
    starts = ((1.0,), (0.9,), (1.1,))
    enters = {"gyro.gain": "gyro_scale"}
    threshold = "|s - 1| >= 0.04"
    hypothesis = "the gyro reads a scaled yaw rate: a scale-factor error (or a unit off by a factor)"
    experiment = ("a full circle at constant speed, then the same circle the other way: the integrated gyro "
                  "turns s x 360 deg while the GNSS course turns 360 deg, at any speed")
    imitated_by = ("scale_disagreement", "opposite_sign")

    def baseline(self, study):
        return {"gyro_scale": 1.0}

    def material(self, fitted, base):
        return abs(fitted["gyro_scale"] - 1.0) >= 0.04

    def options(self, fitted, base, study):
        raise KeyError("gyro scale factor (divide the log's yaw_rate by it)")

    def plausibility(self, values, ctx):
        """A scale factor outside 0.7-1.4 is a unit or a channel, no sensor error."""
        return scale_factor("gyro", values.get("gyro_scale"))
