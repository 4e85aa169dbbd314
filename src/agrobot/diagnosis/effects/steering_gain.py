"""The wheels turn k x the steering command or the wheel-angle reading: a servo's travel per command,
a steering ratio or a potentiometer calibrated wrong, a command in another scale. Judged for every
steering type (the yaw stage driven by the measured angle, or by the command replayed): the yaw rate
is k times the expected one in every turn at low speed (r = v tan(k delta) / L), unlike a ratio curve
(off only in tight turns) or soft tyres (off only at speed)."""
import math

from ..effect import Effect, Parameter
from ..plausibility import CALIBRATION


class SteeringGain(Effect):
    id = "steering_gain"
    subsystem = "steering map (wheel angle per commanded or measured angle)"
    stages = ("yaw", "steering")     # the turns, and the actuator's rate read through the map
    tested_on = ("steering",)
    order = 0.0                      # the wheels turn k x the reading, then each side its own share (asymmetry)
    parameters = (Parameter("steering_gain", "1", 0.1, 0.7, 1.4, "-", 1.0, (0.01, 3.0)),)
    starts = ((1.0,), (0.85,), (1.15,))
    threshold = "|k - 1| >= 0.05"
    hypothesis = ("the wheels turn k x the commanded (or measured) angle: a servo's travel per command, a steering "
                  "ratio or a potentiometer calibrated wrong, or a command in another scale")
    experiment = ("steady circles at walking speed at three commanded angles each way: the kinematic yaw rate "
                  "v tan(k delta_cmd) / L against the gyro gives the same k at every angle (a ratio curve changes "
                  "with the angle, soft tyres with the speed)")

    def baseline(self, study):
        return {"steering_gain": 1.0}

    def material(self, fitted, base):
        return abs(fitted["steering_gain"] - 1.0) >= 0.05

    def wheel_angle(self, x, v, t):
        """k x: the wheels turn k x the reading or the command."""
        k = v["steering_gain"]
        return None if k == 1.0 else k * x

    def options(self, fitted, base, study):
        raise KeyError("steering map gain (multiply the log's delta_cmd and delta by it)")

    def plausibility(self, values, ctx):
        """A gain outside ``CALIBRATION`` is a unit (180/pi), a steering ratio (1:8 to 1:30) or another quantity,
        whether the log's steering is the command or a measured angle."""
        k = values.get("steering_gain")
        if k is None or CALIBRATION[0] <= k <= CALIBRATION[1]:
            return []
        if abs(k * 180 / math.pi - 1.0) < 0.1 or abs(k * math.pi / 180 - 1.0) < 0.1:
            return [f"a steering gain of {k:.3g} (wheel angle per logged steering) is a unit: the log's steering "
                    f"(command or reading) is in degrees where radians are expected, or the other way round"]
        if 1 / 30 <= k <= 1 / 8:
            return [f"a steering gain of {k:.3g} (wheel angle per logged steering) is a steering ratio "
                    f"(1:{1 / k:.0f}): the log's steering is the handwheel's angle, not the road wheels'"]
        return [f"a steering gain of {k:.3g} (wheel angle per logged steering) is no calibration error: the "
                f"log's steering (command or reading) is another quantity or in another unit"]
