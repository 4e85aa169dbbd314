"""Tiny components for orchestrator tests (no tractor in sight)."""
from __future__ import annotations

from agrobot.orchestrator.component import Component, ComponentError, inp, out, par


class Clock(Component):
    """Sampled source: value = t."""

    sampled = True
    variables = (out("value", "s", -1.0, "time of the last sample"),)

    def step(self, t, dt):
        self.y["value"] = t


class Gain(Component):
    """Sampled, direct feedthrough: y = k u."""

    sampled = True
    variables = (inp("u", "s", 0.0, "input"), par("k", "1", 1.0, "gain"), out("y", "s", 0.0, "k u"))
    feedthrough = {"y": ("u",)}

    def step(self, t, dt):
        self.y["y"] = self.p["k"] * self.u["u"]


class Metres(Component):
    sampled = True
    variables = (inp("u", "m", 0.0, "input in metres"), out("y", "m", 0.0, "copy"))
    feedthrough = {"y": ("u",)}

    def step(self, t, dt):
        self.y["y"] = self.u["u"]


class Counter(Component):
    """Continuous: counts its steps and integrates its input (forward Euler)."""

    sampled = False
    variables = (inp("u", "s", 0.0, "rate"), out("steps", "1", 0.0, "number of steps taken"),
                 out("integral", "s", 0.0, "integral of u"), out("time", "s", 0.0, "time reached"))

    def initialize(self, t0, dt):
        self.calls = []
        self.y["time"] = t0

    def step(self, t, dt):
        self.calls.append((t, dt))
        self.y["steps"] += 1
        self.y["integral"] += dt * self.u["u"]
        self.y["time"] = t + dt


class FailAt(Component):
    """Sampled; raises at a chosen time."""

    sampled = True
    variables = (par("fail_time", "s", 1.0, "when to fail"), out("value", "s", 0.0, "t"))

    def step(self, t, dt):
        if t >= self.p["fail_time"] - 1e-12:
            raise ComponentError(f"{self.name}: deliberate failure")
        self.y["value"] = t


class YawRateInDegrees(Component):
    """A component a user might add: reports the yaw rate in degrees per second."""

    sampled = True
    variables = (inp("yaw_rate", "rad/s", 0.0, "yaw rate"), out("yaw_rate_deg", "deg/s", 0.0, "yaw rate in deg/s"))
    feedthrough = {"yaw_rate_deg": ("yaw_rate",)}

    def step(self, t, dt):
        self.y["yaw_rate_deg"] = self.u["yaw_rate"] * 180.0 / 3.141592653589793


class Sleeper(Component):
    """Sleeps ``sleep`` seconds every ``every`` steps: a component that overruns its slot."""

    sampled = True
    variables = (par("sleep", "s", 0.0, "sleep"), par("every", "1", 10, "period in steps"),
                 out("count", "1", 0.0, "steps taken"))

    def step(self, t, dt):
        import time

        self.y["count"] += 1
        if self.p["sleep"] and int(self.y["count"]) % int(self.p["every"]) == 0:
            time.sleep(self.p["sleep"])


class RateSource(Component):
    """Sampled: rate = 1 + t (a yaw rate, to drive FMU inputs)."""

    sampled = True
    variables = (out("rate", "rad/s", 0.0, "1 + t"), out("count", "1", 0.0, "1 + floor(t)"),
                 out("on", "1", 0.0, "t >= 0.5"))

    def step(self, t: float, dt: float) -> None:
        self.y["rate"], self.y["count"], self.y["on"] = 1.0 + t, float(1 + int(t + 1e-9)), float(t >= 0.5)


class RateSink(Component):
    """Sampled, direct feedthrough: copies a yaw rate (reads an FMU output at the same instant)."""

    sampled = True
    variables = (inp("u", "rad/s", 0.0, "input"), out("y", "rad/s", 0.0, "copy"))
    feedthrough = {"y": ("u",)}

    def step(self, t: float, dt: float) -> None:
        self.y["y"] = self.u["u"]


class AngleSink(Component):
    """Sampled: an input in radians."""

    sampled = True
    variables = (inp("angle", "rad", 0.0, "input"), out("y", "rad", 0.0, "copy"))
    feedthrough = {"y": ("angle",)}

    def step(self, t: float, dt: float) -> None:
        self.y["y"] = self.u["angle"]
