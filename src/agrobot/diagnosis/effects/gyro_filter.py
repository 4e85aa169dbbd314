"""The gyro reads its yaw rate through a low-pass filter (the sensor's own, or the driver's
smoothing of the logged channel): the reading lags every change of the yaw rate and rounds its
steps, while its steady value is right.

Reading: a first-order filter of time constant tau_g on the yaw rate the gyro would read,

    tau_g d(r_m)/dt = r_gyro - r_m,     r_m[k] = a r_m[k-1] + (1 - a) r_gyro[k],  a = exp(-h / tau_g)

(a moving average over a window T lags its input about as one of tau_g = T / 2). It shifts the
measurement, not the input: the yaw model's response to the wheel angle keeps its shape and the
reading follows it late, in every turn and at any speed."""
from ..effect import Effect, Parameter

SENSOR_FILTER = 0.5           # s: a yaw-rate filter slower than this is a heading estimate, no gyro's


class GyroFilter(Effect):
    id = "gyro_filter"
    subsystem = "gyro (low-pass filter)"
    stages = ("yaw",)
    parameters = (Parameter("gyro_time_constant", "s", 0.05, 0.0, 0.5, "s", 1.0, (0.0, 1.0)),)
    starts = ((0.05,), (0.15,))
    enters = {"gyro.time_constant": "gyro_time_constant"}
    threshold = "tau_g >= 0.04 s"
    hypothesis = ("the gyro reads a low-pass filtered yaw rate (the sensor's filter or the logger's smoothing): "
                  "the reading lags the yaw rate by its time constant")
    experiment = ("steering steps standing on the brake (the wheels turn, the yaw rate stays zero), then the same "
                  "steps driving: the wheel angle reading shows no lag, the yaw rate's rise is an exponential of "
                  "tau_g on top of the vehicle's own; or log the gyro's raw channel beside the filtered one")
    imitated_by = ("clock_offset", "clock_unchecked", "response_leads_input", "stamp_vs_receive")

    def baseline(self, study):
        return {"gyro_time_constant": 0.0}

    def material(self, fitted, base):
        return fitted["gyro_time_constant"] >= 0.04

    def options(self, fitted, base, study):
        raise KeyError("gyro filter's time constant (the study's gyro is unfiltered: log the gyro's raw channel, or "
                       "shift the log's yaw_rate earlier by tau_g before simulating)")

    def plausibility(self, values, ctx):
        """A filter slower than a sensor's is a heading estimate or a clock, no gyro's."""
        tau = values.get("gyro_time_constant", 0.0)
        if tau > SENSOR_FILTER:
            return [f"a yaw-rate filter of {tau:.2f} s is slower than a gyro's or a logger's ({SENSOR_FILTER:g} s): "
                    f"the yaw-rate channel is probably a heading filter's output or stamped on another clock"]
        return []
