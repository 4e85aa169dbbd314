"""Small steering corrections are not executed: play in the linkage or a valve dead-band."""
import math

from agrobot.components.models.steering_equivalent import FirstOrderSteering

from ..effect import Effect, Parameter

DEG = math.pi / 180.0


class SteeringDeadband(Effect):
    id = "steering_deadband"
    subsystem = "steering"
    stages = ("steering",)
    parameters = (Parameter("steering_deadband", "rad", 0.02, 0.0, 0.12, "deg", 1 / DEG, (0.0, 0.3)),)
    starts = ((0.5 * DEG,), (2.0 * DEG,), (4.0 * DEG,))
    enters = {"steering.deadband": "steering_deadband"}
    threshold = "dead-band >= the baseline's + 0.4 deg"
    hypothesis = "small steering corrections are not executed: play in the linkage or a valve dead-band"
    experiment = "slow ramps and small steps around straight ahead: a dead-band swallows only the smallest commands"

    def baseline(self, study):
        return {"steering_deadband": FirstOrderSteering.of(study.parameters("steering")).deadband}

    def material(self, fitted, base):
        return fitted["steering_deadband"] - base["steering_deadband"] >= 0.4 * DEG

    def options(self, fitted, base, study):
        return [("steering", "angle_deadband", max(0.0, fitted["steering_deadband"] - base["steering_deadband"]))]
