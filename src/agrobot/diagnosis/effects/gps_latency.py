"""The GPS reports where the antenna was a moment ago."""
from ..effect import Effect, Parameter

RECEIVER_LATENCY = 0.5        # s: a GNSS receiver or a localisation filter reports within this


class GPSLatency(Effect):
    id = "gps_latency"
    subsystem = "gps"
    stages = ("position",)
    parameters = (Parameter("gps_latency", "s", 0.1, 0.0, 1.0, "s", 1.0, (0.0, 2.0)),)
    starts = ((0.05,), (0.25,))
    enters = {"position.lag": "gps_latency"}
    threshold = "latency >= 0.05 s"
    hypothesis = "the GPS reports where the antenna was a moment ago"
    experiment = "straight runs at 1 and 3 m/s: a latency puts the fix behind by speed x latency, along the track"
    imitated_by = ("clock_offset", "clock_unchecked", "response_leads_input", "stamp_vs_receive", "gap_bridged")

    def baseline(self, study):
        return {"gps_latency": study.parameters("gps", {"latency": 0.0})["latency"]}

    def material(self, fitted, base):
        return fitted["gps_latency"] - base["gps_latency"] >= 0.05

    def options(self, fitted, base, study):
        """The sensor delays by whole samples: the latency is rounded to its step."""
        step = study.step("gps")
        return [("gps", "latency", round(fitted["gps_latency"] / step) * step)]

    def plausibility(self, values, ctx):
        """A latency longer than a receiver or a filter takes is a clock offset."""
        if values.get("gps_latency", 0.0) > RECEIVER_LATENCY:
            return [f"a position latency of {values['gps_latency']:.2f} s is longer than a receiver or a localisation "
                    f"filter takes ({RECEIVER_LATENCY:g} s): the positions' clock is offset"]
        return []
