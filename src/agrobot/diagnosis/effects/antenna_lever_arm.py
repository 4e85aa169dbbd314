"""The position's reference point (a GNSS antenna, or a localisation filter's frame) is not where the model
puts it: in turns it swings on a different radius."""
import math

from ..effect import Effect, Parameter
from ..plausibility import reference_point


class AntennaLeverArm(Effect):
    id = "antenna_lever_arm"
    subsystem = "gps (antenna mounting)"
    stages = ("position",)
    parameters = (Parameter("antenna_forward", "m", 0.5, -4.0, 4.0, "m", 1.0, (-8.0, 8.0)),
                  Parameter("antenna_left", "m", 0.5, -2.0, 2.0, "m", 1.0, (-4.0, 4.0)))
    starts = ((0.0, 0.0),)
    enters = {"position.forward": "antenna_forward", "position.left": "antenna_left"}
    threshold = "lever arm >= 0.15 m"
    hypothesis = ("the position's reference point (a GNSS antenna, or the frame a localisation filter reports) is "
                  "not where the model puts it: in turns it swings on a different radius")
    experiment = ("tight turns both ways at low speed: a lever arm swings the antenna "
                  "on a different radius, independent of speed")
    imitated_by = ("clock_offset", "clock_unchecked",)

    def baseline(self, study):
        p = study.parameters("yaw_plant")
        return {"antenna_forward": p["antenna_forward"], "antenna_left": p["antenna_left"]}

    def material(self, fitted, base):
        return math.hypot(fitted["antenna_forward"] - base["antenna_forward"],
                          fitted["antenna_left"] - base["antenna_left"]) >= 0.15

    def options(self, fitted, base, study):
        return [("yaw_plant", "antenna_forward", fitted["antenna_forward"]),
                ("yaw_plant", "antenna_left", fitted["antenna_left"])]

    def plausibility(self, values, ctx):
        """The antenna lies inside the vehicle's outline."""
        return reference_point(values, ctx)
