"""The wheels turn further one way than the other: a steering linkage, a servo or a potentiometer
whose gain differs left and right. The wheels turn delta (1 + a sign(delta)) for a command or
reading delta: left turns (delta > 0) on a radius L / tan(delta (1 + a)), right ones on
L / tan(delta (1 - a)); a common gain error is the steering_gain effect, an offset shifts both
ways' zero alike (steering_offset), this one scales each side apart."""
import numpy as np

from ..effect import Effect, Parameter


class SteeringAsymmetry(Effect):
    id = "steering_asymmetry"
    subsystem = "steering map (wheel angle per angle, left against right)"
    stages = ("yaw", "steering")     # the turns, and the actuator's rate read through the map
    tested_on = ("steering",)
    order = 1.0                      # after the gain k: k x (1 + a sign x)
    parameters = (Parameter("steering_asymmetry", "1", 0.05, -0.4, 0.4, "-", 1.0, (-0.8, 0.8)),)
    starts = ((0.0,), (0.1,), (-0.1,))
    threshold = "|a| >= 0.04 (the left and the right gain differ by >= 8 %)"
    hypothesis = ("the wheels turn further one way than the other: the steering map's gain differs left "
                  "(x (1 + a)) and right (x (1 - a))")
    experiment = ("steady circles at walking speed at the same command left and right: the radii "
                  "L / tan(delta (1 +- a)) differ by the asymmetry, at every speed")

    def baseline(self, study):
        return {"steering_asymmetry": 0.0}

    def material(self, fitted, base):
        return abs(fitted["steering_asymmetry"]) >= 0.04

    def wheel_angle(self, x, v, t):
        """x (1 + a sign x): left turns (x > 0) 1 + a times, right ones 1 - a times."""
        a = v["steering_asymmetry"]
        return x * (1.0 + a * np.sign(x)) if a else None

    def options(self, fitted, base, study):
        raise KeyError("steering map asymmetry (a lookup of wheel angle against the reading, each side its gain)")

    def plausibility(self, values, ctx):
        """One side turning more than twice the other's angle is no linkage but a wrong channel or sign."""
        a = values.get("steering_asymmetry", 0.0)
        if abs(a) > 1.0 / 3.0:
            return [f"a left/right asymmetry of {a:+.2f} turns one side {(1 + abs(a)) / (1 - abs(a)):.1f} x the "
                    f"other's angle: no linkage or servo errs so far; the steering channel is another quantity "
                    f"on one side (a clipped or re-signed reading)"]
        return []
