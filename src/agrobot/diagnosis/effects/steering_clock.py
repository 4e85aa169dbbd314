"""The steering channels are stamped on a clock offset from the gyro's: the yaw rate answers a
wheel angle (or command) the log shows tau seconds later (tau > 0: the response leads its input,
which no vehicle does) or earlier than the vehicle's own delay.

Reading: the yaw model is driven by delta(t + tau). A recording effect, tried before the vehicle
effects it can imitate (a steering delay, a rate limit)."""
import numpy as np

from ..effect import Effect, Parameter


class SteeringClock(Effect):
    id = "steering_clock"
    subsystem = "recording (the steering channels' clock against the gyro's)"
    stages = ("yaw",)
    parameters = (Parameter("steering_clock", "s", 0.1, -0.3, 1.0, "s", 1.0, (-0.6, 3.0)),)
    starts = ((0.05,), (0.4,), (-0.1,))
    threshold = "the steering channels stamped >= 0.05 s late (the yaw rate leads them), or >= 0.25 s early"
    hypothesis = ("the steering channels are stamped on a clock offset from the gyro's: the yaw rate answers a "
                  "wheel angle the log shows later")
    experiment = ("a sharp steering step standing still then driving off, or the recorder's receive stamps beside "
                  "the senders' stamps: a clock offset shifts every channel of the group by the same time")
    recording = True
    order = 2.0                      # the channels as logged, gain and asymmetry applied, shifted; the ratio curve after
    pointwise = False                # the steering stage's command and angle share the clock: its input only
    imitates = ("actuator_delay", "steering_rate_limit")

    def baseline(self, study):
        return {"steering_clock": 0.0}

    def material(self, fitted, base):
        tau = fitted["steering_clock"]
        return tau >= 0.05 or tau <= -0.25

    def wheel_angle(self, x, v, t):
        """x(t + tau): the yaw rate answers the angle the log shows tau later."""
        tau = v["steering_clock"]
        return np.interp(t + tau, t, x) if tau else None

    def options(self, fitted, base, study):
        raise KeyError("steering channels' clock (shift delta and delta_cmd by it before simulating)")
