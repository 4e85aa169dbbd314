"""The wheel-angle sensor is zeroed wrongly: straight driving needs a non-zero reading.

In a steady state the bicycle model turns at r = v o / (L + K v^2) for an offset o and at
r = K a_s v / (L + K v^2) for a lateral pull a_s = g sin(phi) cos(heading - fall line) of a side slope
(K the understeer gradient): the same speed dependence, so only the heading tells a slope from
an offset; a log on few headings leaves the two tied (the selection then says so)."""
import math

from ..effect import Effect, Parameter

DEG = math.pi / 180.0
SPEED_KEY = "log_speed_p95"          # the log's 95th percentile of the moving speed [m/s], set by the selection
WHEELBASE_KEY = "study_wheelbase"    # the study's wheelbase [m], set by the selection
YAW_MATERIAL = 0.005                 # a yaw rate [rad/s] worth a model change (unexplained.MATERIAL's yaw)


class SteeringOffset(Effect):
    id = "steering_offset"
    subsystem = "steering angle sensor (wheel angle seen by the tyres)"
    stages = ("yaw",)
    parameters = (Parameter("steer_angle_offset", "rad", 0.02, -0.15, 0.15, "deg", 1 / DEG, (-0.35, 0.35)),)
    starts = ((0.0,),)
    enters = {"yaw.steer_offset": "steer_angle_offset"}
    threshold = ("|offset| >= 0.3 deg, or its kinematic yaw rate v |offset| / L >= 0.29 deg/s at the log's "
                 "95th-percentile speed (a car's small angles)")
    hypothesis = "the wheel-angle sensor is zeroed wrongly: straight driving needs a non-zero reading"
    experiment = ("straight runs on one line in both directions: an offset's yaw rate v o / (L + K v^2) keeps "
                  "its sign, a side slope's (the same form with K g sin(phi) cos(heading - fall line) for o) "
                  "reverses with the heading; speed alone does not tell them apart")

    def baseline(self, study):
        return {"steer_angle_offset": study.parameters("yaw_plant")["steer_angle_offset"]}

    def material(self, fitted, base):
        """A zero a mechanic would reset, or one that turns the vehicle by a material yaw rate
        r = v offset / L where it drives (a car's offset of 0.1 deg: 0.013 rad/s at 20 m/s)."""
        offset = abs(fitted["steer_angle_offset"] - base["steer_angle_offset"])
        yaw = base.get(SPEED_KEY, 0.0) * offset / base[WHEELBASE_KEY] if base.get(WHEELBASE_KEY) else 0.0
        return offset >= 0.3 * DEG or yaw >= YAW_MATERIAL

    def options(self, fitted, base, study):
        return [("yaw_plant", "steer_angle_offset", fitted["steer_angle_offset"])]

    def plausibility(self, values, ctx):
        """An offset over 8 deg is more than a misaligned zero."""
        if abs(values.get("steer_angle_offset", 0.0)) > math.radians(8):
            return [f"a steering offset of {math.degrees(values['steer_angle_offset']):.1f} deg is more than a "
                    f"misaligned zero: the steering channel is another quantity (a handwheel angle, a command in "
                    f"another unit)"]
        return []
