"""The speed reads k x the ground speed: a wheel radius off, or the wheels slipping. The dead
reckoning runs k times too far and, near the kinematic yaw rate v delta / L, the yaw model turns
k times too fast (its LPV speed is k times too high)."""
from ..effect import Effect, Parameter
from ..plausibility import scale_factor


class SpeedScale(Effect):
    id = "speed_scale"
    subsystem = "speed sensor (wheel radius or slip)"
    stages = ("yaw", "position", "speed")
    parameters = (Parameter("speed_scale", "1", 0.1, 0.8, 1.25, "-", 1.0, (0.3, 3.0)),)
    starts = ((1.0,), (1.08,), (0.93,))
    enters = {"speed.gain": "speed_scale"}
    threshold = "|k - 1| >= 0.03"
    hypothesis = "the speed reads k x the ground speed: a wheel radius off, or the wheels slipping"
    experiment = ("a straight run of known length (or the GNSS speed over ground beside the wheel speed) at "
                  "constant speed, with and without draught: a radius error stays, slip grows with the pull")
    imitated_by = ("scale_disagreement", "opposite_sign")

    def baseline(self, study):
        return {"speed_scale": 1.0}

    def material(self, fitted, base):
        return abs(fitted["speed_scale"] - 1.0) >= 0.03

    def options(self, fitted, base, study):
        raise KeyError("speed scale factor (divide the log's v by it)")

    def plausibility(self, values, ctx):
        """A scale factor outside 0.7-1.4 is a unit or a channel, no sensor error."""
        return scale_factor("speed", values.get("speed_scale"))
