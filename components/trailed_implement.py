"""A trailed implement on a drawbar, with an optional side-shift that steers it onto its line.

The hitch H sits ``hitch_offset`` c behind the tractor's rear axle R; the implement's axle A is
``drawbar`` L behind H and does not slip sideways except for the side slope's pull. With the
rear axle's velocity V_R (the plant's), the tractor's yaw rate gamma and heading psi:

    V_H = V_R + c gamma (sin psi, -cos psi)
    d psi_i / dt = (V_H . n_i - |V_H| beta) / L,      n_i = (-sin psi_i, cos psi_i)
    beta = m_i (P . n_i) / C_i = m_i g sin(phi) sin(psi_d - psi_i) / C_i     (the slope's slip, downhill)

P is the slope's in-plane pull g sin(phi) (cos psi_d, sin psi_d), from the tractor (its
``slope_angle`` option moves both). On a straight line the implement runs L beta to the
downhill side of the hitch's track.
    A = H - L (cos psi_i, sin psi_i),     working point W = A + e_s n_i

e_s is the side-shift, a frame moving the tools sideways: a first-order actuator (time constant,
rate and stroke limits) following e_cmd = -(k_p xte + k_i int xte) of the implement's cross-track
error (from the route) while ``active`` (the route straight under the implement: a swath and its
run-in), centred in turns; k_p = 0 is a passive implement. L = 0 is a mounted implement (psi_i = psi).
Integrated at ``internal_step`` (Heun) within each step.

Its roll and pitch (outputs) are those of a body at heading psi_i on the plane whose pull is P
(models.terrain: the ground under the tractor, taken to hold under the implement too).
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par

from .models.terrain import attitude, gradient_of_pull


class TrailedImplement(Component):
    sampled = False
    roles = ("implement",)
    OFF_THE_LATERAL_LOOP = True   # moves nothing of the lateral channel at first order (margins)
    variables = (
        inp("x_rear", "m", 0.0, "tractor rear axle east"),
        inp("y_rear", "m", 0.0, "tractor rear axle north"),
        inp("vel_east_rear", "m/s", 0.0, "rear axle velocity east"),
        inp("vel_north_rear", "m/s", 0.0, "rear axle velocity north"),
        inp("heading", "rad", 0.0, "tractor heading psi"),
        inp("yaw_rate", "rad/s", 0.0, "tractor yaw rate"),
        inp("cross_track", "m", 0.0, "the implement's cross-track error (from the route), left positive"),
        inp("active", "1", 1.0, "1: the side-shift holds the line; 0 (in turns): it centres and forgets"),
        inp("slope_pull_east", "m/s2", 0.0, "the side slope's in-plane gravity, east (from the tractor)"),
        inp("slope_pull_north", "m/s2", 0.0, "north"),
        par("hitch_offset", "m", 0.6, "c: hitch behind the rear axle"),
        par("drawbar", "m", 2.5, "L: hitch to implement axle (0: mounted)"),
        par("mass", "kg", 800.0, "implement mass (the slope's pull)"),
        par("cornering_stiffness", "N/rad", 40000.0, "the implement's tyres"),
        par("side_shift_gain", "1", 0.0, "k_p of the side-shift on the cross-track error (0: passive)"),
        par("side_shift_integral", "1/s", 0.0, "k_i [1/s] on the integrated cross-track error"),
        par("side_shift_limit", "m", 0.3, "stroke, each side"),
        par("side_shift_rate", "m/s", 0.2, "fastest shift"),
        par("side_shift_time_constant", "s", 0.15, "actuator lag"),
        par("internal_step", "s", 0.01, "integration step"),
        out("x", "m", 0.0, "working point east"),
        out("y", "m", 0.0, "working point north"),
        out("heading", "rad", 0.0, "implement heading psi_i"),
        out("hitch_angle", "rad", 0.0, "psi - psi_i"),
        out("side_shift", "m", 0.0, "e_s, left positive"),
        out("roll", "rad", 0.0, "roll on the ground, positive: left side up"),
        out("pitch", "rad", 0.0, "pitch on the ground, positive: nose up"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(p["hitch_offset"] >= 0 and p["drawbar"] >= 0, "hitch_offset and drawbar must be >= 0")
        self.require(p["cornering_stiffness"] > 0 and p["mass"] >= 0, "cornering_stiffness > 0 and mass >= 0")
        self.substeps = max(1, int(round(dt / p["internal_step"])))
        self.psi_i = float(self.u["heading"])
        self.shift = self.integral = 0.0
        self._publish()

    def _rates(self, psi_i: float) -> float:
        u, p = self.u, self.p
        L = p["drawbar"]
        if L <= 0:
            return 0.0
        psi, gamma, c = u["heading"], u["yaw_rate"], p["hitch_offset"]
        vx = u["vel_east_rear"] + c * gamma * math.sin(psi)
        vy = u["vel_north_rear"] - c * gamma * math.cos(psi)
        normal = -math.sin(psi_i) * vx + math.cos(psi_i) * vy
        beta = p["mass"] * (-math.sin(psi_i) * u["slope_pull_east"] + math.cos(psi_i) * u["slope_pull_north"]) \
            / p["cornering_stiffness"]
        return (normal - math.hypot(vx, vy) * beta) / L

    def step(self, t: float, dt: float) -> None:
        p, u = self.p, self.u
        h = dt / self.substeps
        if p["drawbar"] <= 0:
            self.psi_i = float(u["heading"])
        else:
            for _ in range(self.substeps):
                k1 = self._rates(self.psi_i)
                k2 = self._rates(self.psi_i + h * k1)
                self.psi_i += 0.5 * h * (k1 + k2)
        xte = float(u["cross_track"])
        cmd = 0.0
        if u["active"] < 0.5:
            self.integral = 0.0
        elif p["side_shift_gain"] > 0 or p["side_shift_integral"] > 0:
            self.integral = max(-p["side_shift_limit"], min(p["side_shift_limit"],
                                                             self.integral + p["side_shift_integral"] * xte * dt))
            cmd = max(-p["side_shift_limit"], min(p["side_shift_limit"], -(p["side_shift_gain"] * xte + self.integral)))
        alpha = 1.0 - math.exp(-dt / p["side_shift_time_constant"])
        move = max(-p["side_shift_rate"] * dt, min(p["side_shift_rate"] * dt, alpha * (cmd - self.shift)))
        self.shift += move
        self._publish()

    def _publish(self) -> None:
        u, p, y = self.u, self.p, self.y
        psi = u["heading"]
        hx = u["x_rear"] - p["hitch_offset"] * math.cos(psi)
        hy = u["y_rear"] - p["hitch_offset"] * math.sin(psi)
        c, s = math.cos(self.psi_i), math.sin(self.psi_i)
        y["x"] = hx - p["drawbar"] * c - self.shift * s
        y["y"] = hy - p["drawbar"] * s + self.shift * c
        y["heading"] = self.psi_i
        y["hitch_angle"] = math.atan2(math.sin(psi - self.psi_i), math.cos(psi - self.psi_i))
        y["side_shift"] = self.shift
        y["roll"], y["pitch"] = attitude(*gradient_of_pull(u["slope_pull_east"], u["slope_pull_north"]), self.psi_i)


COMPONENT = TrailedImplement
