"""Time-based 8-shaped reference trajectory of the CG (paper section VI-B).

Path: models.figure8_path (straights and arcs, each sample labelled). Progress along the path
s(t) = v t^2 / (2 T) for t < T (start ramp), v (t - T/2) afterwards; the reference velocity
(xdot_r, ydot_r) = ds/dt (cos h, sin h) and yaw rate = ds/dt * curvature.
"""
from __future__ import annotations

from pathlib import Path
import math

from agrobot.orchestrator.compiled.cores import CoreDescription
from agrobot.orchestrator.component import Component, out, par

from .models.figure8_path import Figure8Path


class Figure8Reference(Component):
    sampled = True
    roles = ("reference",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"))   # its C model core, beside this file
    variables = (
        par("speed", "m/s", 2.0, "reference speed along the path"),
        par("radius", "m", 10.0, "radius of the two loops"),
        par("centre_offset", "m", 20.0, "distance of each loop centre from the crossing"),
        par("ramp_time", "s", 4.0, "time to reach the reference speed from rest"),
        par("x_origin", "m", 0.0, "east position of the crossing point"),
        par("y_origin", "m", 0.0, "north position of the crossing point"),
        out("x_ref", "m", 0.0, "reference CG east position"),
        out("y_ref", "m", 0.0, "reference CG north position"),
        out("xdot_ref", "m/s", 0.0, "reference east velocity"),
        out("ydot_ref", "m/s", 0.0, "reference north velocity"),
        out("heading_ref", "rad", 0.0, "reference heading"),
        out("yaw_rate_ref", "rad/s", 0.0, "reference yaw rate"),
        out("speed_ref", "m/s", 0.0, "reference path speed"),
        out("segment", "1", 0.0, "0 on a straight, 1 on a curve"),
        out("path_length", "m", 0.0, "arc length travelled by the reference"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(p["speed"] > 0, "speed must be > 0")
        self.require(p["ramp_time"] >= 0, "ramp_time must be >= 0")
        try:
            self.path = Figure8Path(p["radius"], p["centre_offset"])
        except ValueError as exc:
            self.require(False, str(exc))
        self.t0 = t0
        self.step(t0, dt)

    def progress(self, t: float) -> tuple[float, float]:
        """(s, ds/dt) at time t."""
        v, T = self.p["speed"], self.p["ramp_time"]
        tau = max(t - self.t0, 0.0)
        if tau < T:
            return v * tau * tau / (2.0 * T), v * tau / T
        return v * (tau - T / 2.0), v

    def step(self, t: float, dt: float) -> None:
        s, sdot = self.progress(t)
        x, y, h, kappa, label = self.path.pose(s)
        out_ = self.y
        out_["x_ref"], out_["y_ref"] = x + self.p["x_origin"], y + self.p["y_origin"]
        out_["xdot_ref"], out_["ydot_ref"] = sdot * math.cos(h), sdot * math.sin(h)
        out_["heading_ref"], out_["yaw_rate_ref"] = h, sdot * kappa
        out_["speed_ref"], out_["segment"], out_["path_length"] = sdot, float(label), s

    def operating_points(self) -> dict[str, dict[str, float | None]]:
        """Where the guidance loop is linearised: the path's speed after the start ramp (its
        straights; its loops have ``radius``); the reference is time based, so the tracker's
        along-track error is what the speed loop leaves (None: not known here). It reads nothing,
        so it adds nothing to the loop."""
        return {"path": {"speed": float(self.p["speed"]), "along_track_error": None, "turn_radius": float(self.p["radius"])}}


COMPONENT = Figure8Reference
