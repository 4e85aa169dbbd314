"""The steering system's status as ISO 11783-7 Guidance Machine Info reports it: ready for
automatic steering, and the operator's mechanical lockout. A simulated tractor is ready and not
locked out unless a fault is injected (``not_ready_after``, ``lockout_after``; negative = never,
``*_until`` ends it; negative = for good)."""
from __future__ import annotations

from agrobot.orchestrator.component import Component, out, par


class SteeringStatus(Component):
    sampled = True
    OFF_THE_LATERAL_LOOP = True   # moves nothing of the lateral channel at first order (margins)
    variables = (
        par("not_ready_after", "s", -1.0, "fault injection: not ready from this time"),
        par("not_ready_until", "s", -1.0, "ready again from this time (negative: never)"),
        par("lockout_after", "s", -1.0, "fault injection: the operator sets the lockout at this time"),
        par("lockout_until", "s", -1.0, "the lockout is released at this time (negative: never)"),
        out("ready", "1", 1.0, "1 while the steering system is ready for automatic steering"),
        out("lockout", "1", 0.0, "1 while the mechanical lockout is active"),
    )
    feedthrough = {}

    def step(self, t: float, dt: float) -> None:
        p = self.p

        def active(start: float, end: float) -> bool:
            return 0 <= start <= t and not (0 <= end <= t)

        self.y["ready"] = float(not active(p["not_ready_after"], p["not_ready_until"]))
        self.y["lockout"] = float(active(p["lockout_after"], p["lockout_until"]))


COMPONENT = SteeringStatus
