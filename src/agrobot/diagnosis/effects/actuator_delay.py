"""The wheels follow the command late: a transport delay in the valve drive or the bus."""
from agrobot.components.models.steering_equivalent import FirstOrderSteering

from ..effect import Effect, Parameter

HUMAN_REACTION = 0.3          # s: no steering actuator is slower; a longer "delay" is a clock


class ActuatorDelay(Effect):
    id = "actuator_delay"
    subsystem = "steering"
    stages = ("steering",)
    parameters = (Parameter("command_delay", "s", 0.1, 0.0, 0.6, "s", 1.0, (0.0, 2.0)),)
    starts = ((0.05,), (0.15,), (0.3,))
    enters = {"steering.delay": "command_delay"}
    threshold = "delay >= 0.05 s"
    hypothesis = "the wheels follow the command late: a transport delay in the valve drive or the bus"
    experiment = ("small fast steering steps (+/-2 deg) at any speed: a delay shifts "
                  "even the smallest moves, a rate limit does not")
    imitated_by = ("clock_offset", "clock_unchecked", "response_leads_input", "stamp_vs_receive", "gap_bridged")

    def baseline(self, study):
        return {"command_delay": FirstOrderSteering.of(study.parameters("steering")).delay}

    def material(self, fitted, base):
        return fitted["command_delay"] - base["command_delay"] >= 0.05

    def options(self, fitted, base, study):
        return [("steering", "command_delay", fitted["command_delay"])]

    def plausibility(self, values, ctx):
        """A delay longer than a human reaction is a clock offset, not an actuator."""
        if values.get("command_delay", 0.0) > HUMAN_REACTION:
            return [f"a steering delay of {values['command_delay']:.2f} s is longer than a human reaction "
                    f"({HUMAN_REACTION:g} s): no steering actuator is that slow; the steering channels are probably "
                    f"stamped on a clock that lags the gyro's (a recording problem)"]
        return []
