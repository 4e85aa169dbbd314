"""The operator stops the tractor at the headland for a while (refilling, a break, a test's wait):
``pauses = [[n, seconds], ...]`` holds the speed command at 0 for that long once the tractor's CG has
left its n-th swath. ISO 12188-2's pass-to-pass figure compares passes driven about 15 minutes
apart; a pause after the first swath gives that interval on a field's first two swaths.
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par


class OperatorPause(Component):
    sampled = True
    roles = ("operator",)
    variables = (
        inp("speed_cmd", "m/s", 0.0, "speed command from the tracker"),
        inp("swath", "1", -1.0, "the swath the CG is on (the route's index, -1 off swaths)"),
        par("pauses", "", [], "[[n, seconds], ...]: stop this long after leaving the n-th swath (n from 1)"),
        out("speed_cmd_out", "m/s", 0.0, "speed command on (0 while paused)"),
        out("paused", "1", 0.0, "1 while the operator holds the tractor"),
    )
    feedthrough = {"speed_cmd_out": ("speed_cmd", "swath"), "paused": ("swath",)}

    def initialize(self, t0: float, dt: float) -> None:
        value = self.p["pauses"]
        self.require(isinstance(value, (list, tuple)), f"parameter pauses = {value!r}: expected [[n, seconds], ...]")
        self.plan: dict[int, float] = {}
        for i, item in enumerate(value):
            ok = (isinstance(item, (list, tuple)) and len(item) == 2
                  and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in item)
                  and item[0] >= 1 and item[0] == int(item[0]) and item[1] >= 0)
            self.require(ok, f"parameter pauses, item {i} = {item!r}: expected [n, seconds] with n a swath count "
                             "from 1 and seconds >= 0")
            self.plan[int(item[0])] = float(item[1])
        self.finished, self.on_swath, self.until = 0, False, -math.inf

    def step(self, t: float, dt: float) -> None:
        on = self.u["swath"] >= 0
        if self.on_swath and not on:
            self.finished += 1
            if self.finished in self.plan:
                self.until = t + self.plan[self.finished]
                self.event(t, f"operator pause after swath {self.finished}: {self.plan[self.finished]:g} s")
        self.on_swath = on
        paused = t < self.until - 1e-9
        self.y["paused"] = float(paused)
        self.y["speed_cmd_out"] = 0.0 if paused else self.u["speed_cmd"]


COMPONENT = OperatorPause
