"""The positions are not an antenna's fixes on the log's clock: they are of another point of the
vehicle (a localisation output: the filter's body frame, the centre of gravity, the rear axle)
and stamped on a clock that lags (or leads) the gyro's.

Reading: p(t) = R(t - tau) + Rot(psi(t - tau)) (f, l), with R the rear axle, (f, l) the point
from the antenna the study places, tau the clock lag. Alone, (f, l) is an antenna lever arm and
tau a latency; this effect is the recording's explanation, tried before them, and found only
when both parts are material (diagnosis.selection tries recording effects first).
"""
import math

from ..effect import Effect, Parameter
from ..plausibility import reference_point

STAMPING_DELAY = 2.0          # s: a stamping delay is shorter; a longer offset is another clock


class PositionReference(Effect):
    id = "position_reference"
    subsystem = "recording (position reference point and clock)"
    stages = ("position",)
    parameters = (Parameter("position_forward", "m", 0.5, -4.0, 4.0, "m", 1.0, (-8.0, 8.0)),
                  Parameter("position_left", "m", 0.5, -2.0, 2.0, "m", 1.0, (-4.0, 4.0)),
                  Parameter("position_clock", "s", 0.1, -1.0, 1.0, "s", 1.0, (-3.0, 3.0)))
    starts = ((0.0, 0.0, 0.1), (0.5, 0.0, 0.3), (0.0, 0.0, -0.2))
    enters = {"position.forward": "position_forward", "position.left": "position_left",
              "position.lag": "position_clock"}
    threshold = "the point >= 0.15 m from the study's antenna and the clock off by >= 0.05 s"
    hypothesis = ("the positions are of another point of the vehicle (a localisation output) and stamped on a "
                  "clock offset from the gyro's")
    experiment = ("straight runs at two speeds and tight turns both ways: a clock offset puts the fix behind by "
                  "speed x lag along the track, a reference point swings on its own radius in turns at any speed")
    recording = True
    imitates = ("antenna_lever_arm", "gps_latency")
    imitated_by = ("clock_offset", "clock_unchecked", "response_leads_input", "stamp_vs_receive")

    def baseline(self, study):
        return {"position_forward": 0.0, "position_left": 0.0, "position_clock": 0.0}

    def material(self, fitted, base):
        return (math.hypot(fitted["position_forward"], fitted["position_left"]) >= 0.15
                and abs(fitted["position_clock"]) >= 0.05)

    def options(self, fitted, base, study):
        p = study.parameters("yaw_plant")
        out = [("yaw_plant", "antenna_forward", p["antenna_forward"] + fitted["position_forward"]),
               ("yaw_plant", "antenna_left", p["antenna_left"] + fitted["position_left"])]
        if fitted["position_clock"] >= 0:
            step = study.step("gps") if study.has("gps") else 0.0
            lag = round(fitted["position_clock"] / step) * step if step else fitted["position_clock"]
            out.append(("gps", "latency", study.parameters("gps", {"latency": 0.0})["latency"] + lag))
        return out

    def plausibility(self, values, ctx):
        """The point lies inside the vehicle's outline and the clock is off by a stamping delay at most."""
        out = reference_point(values, ctx)
        if abs(values.get("position_clock", 0.0)) > STAMPING_DELAY:
            out.append(f"a clock offset of {values['position_clock']:.2f} s is more than a stamping delay: the "
                       f"channel groups were recorded on different clocks")
        return out
