"""The wheel-angle sensor is zeroed wrongly: straight driving needs a non-zero reading."""
import math

from ..effect import Effect, Parameter

DEG = math.pi / 180.0


class SteeringOffset(Effect):
    id = "steering_offset"
    subsystem = "steering angle sensor (wheel angle seen by the tyres)"
    stages = ("yaw",)
    parameters = (Parameter("steer_angle_offset", "rad", 0.02, -0.15, 0.15, "deg", 1 / DEG, (-0.35, 0.35)),)
    starts = ((0.0,),)
    threshold = "|offset| >= 0.3 deg"
    hypothesis = "the wheel-angle sensor is zeroed wrongly: straight driving needs a non-zero reading"
    experiment = ("straight runs at 1 and 3 m/s in both directions: an offset's "
                  "yaw rate grows with speed and keeps its sign")

    def baseline(self, study):
        return {"steer_angle_offset": study.parameters("yaw_plant")["steer_angle_offset"]}

    def material(self, fitted, base):
        return abs(fitted["steer_angle_offset"] - base["steer_angle_offset"]) >= 0.3 * DEG

    def options(self, fitted, base, study):
        return [("yaw_plant", "steer_angle_offset", fitted["steer_angle_offset"])]

    def plausibility(self, values, ctx):
        """An offset over 8 deg is more than a misaligned zero."""
        if abs(values.get("steer_angle_offset", 0.0)) > math.radians(8):
            return [f"a steering offset of {math.degrees(values['steer_angle_offset']):.1f} deg is more than a "
                    f"misaligned zero: the steering channel is another quantity (a handwheel angle, a command in "
                    f"another unit)"]
        return []
