"""Large steering moves are slower than the model: less pump flow than assumed."""
import math

from agrobot.components.models.steering_equivalent import FirstOrderSteering

from ..effect import Effect, Parameter

DEG = math.pi / 180.0


class SteeringRateLimit(Effect):
    id = "steering_rate_limit"
    subsystem = "steering"
    stages = ("steering",)
    parameters = (Parameter("steering_rate_limit", "rad/s", 0.3, 0.03, 10.0, "deg/s", 1 / DEG, (0.01, 10.0)),)
    starts = ((0.8,), (0.4,), (0.2,))
    enters = {"steering.rate_limit": "steering_rate_limit"}
    threshold = "rate limit <= 0.8 x the baseline's"
    hypothesis = "large steering moves are slower than the model: less pump flow than assumed"
    experiment = "large fast steering steps (+/-20 deg): a rate limit slows only the large moves"
    imitated_by = ("clock_offset", "clock_unchecked", "response_leads_input", "gap_bridged")

    def baseline(self, study):
        return {"steering_rate_limit": FirstOrderSteering.of(study.parameters("steering")).rate_limit}

    def material(self, fitted, base):
        return fitted["steering_rate_limit"] <= 0.8 * base["steering_rate_limit"]

    def options(self, fitted, base, study):
        return [("steering", "rate_limit", fitted["steering_rate_limit"])]
