"""Stanley tracker (Hoffmann et al. 2007, Stanford's DARPA vehicle; in AgOpenGPS too), on the
time-based reference, as a drop-in for the kinematic tracker. The front axle F = CG + l_f
(cos psi, sin psi) is steered onto the reference line through the reference point:

    delta = psi_e + atan(k e_cross / (v_soft + v)),   psi_e = psi_r - psi,
    e_cross = (F - ref) x t_r (positive left of the line),
    gamma_d = v_d tan(delta) / L,   v_d = v_r + k_s tanh(k_c e_along)

with psi_r the reference heading (of its velocity) and L = l_f + l_r; the wheel angle goes to the
yaw-rate MPC as the yaw rate it makes (the same steering, estimation and speed stack). With a crab
(``lateral_velocity``) the heading error is taken from the course, psi_e = psi_r - (psi + beta).
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, par

from .kinematic_tracker import (LATERAL_INPUTS, SPEED_LAW, TRACKER_FEEDTHROUGH, TRACKER_INPUTS, TRACKER_OUTPUTS,
                                static_law)
from .pure_pursuit import along_track, crab_angle


class Stanley(Component):
    sampled = True
    roles = ("tracker",)
    variables = TRACKER_INPUTS + SPEED_LAW + TRACKER_OUTPUTS + (
        par("k", "1", 1.0, "cross-track gain"),
        par("v_soft", "m/s", 1.0, "softening speed (keeps the law finite at low speed)"),
        par("l_f", "m", 1.0, "front axle to CG"),
        par("l_r", "m", 0.4, "rear axle to CG"),
        par("steer_limit", "rad", math.radians(45.0), "|delta| bound of the law"),
    )
    feedthrough = TRACKER_FEEDTHROUGH

    def step(self, t: float, dt: float) -> None:
        u, p, y = self.u, self.p, self.y
        ex, ey, tx, ty, v_d = along_track(u, p)
        psi = u["heading"]
        fx = u["x"] + p["l_f"] * math.cos(psi) - u["x_ref"]
        fy = u["y"] + p["l_f"] * math.sin(psi) - u["y_ref"]
        cross = tx * fy - ty * fx                              # left of the line > 0
        course = psi + crab_angle(u["lateral_velocity"], math.hypot(u["xdot_ref"], u["ydot_ref"]))
        psi_e = math.atan2(math.sin(math.atan2(ty, tx) - course), math.cos(math.atan2(ty, tx) - course))
        delta = psi_e - math.atan(p["k"] * cross / (p["v_soft"] + max(v_d, 0.0)))
        delta = min(max(delta, -p["steer_limit"]), p["steer_limit"])
        y["speed_desired"] = v_d
        y["yaw_rate_desired"] = v_d * math.tan(delta) / (p["l_f"] + p["l_r"])
        y["error_x"], y["error_y"] = ex, ey

    def lateral_linearisation(self, speed: float, dt: float, along_track_error: float = 0.0):
        """Small deviations about a straight reference heading east at ``speed``, the CG on its
        line e = ``along_track_error`` behind the reference point (v_d = v + k_s tanh(k_c e), the
        steering bound inactive). With c = k / (v_soft + v_d): e_cross = d y - d y_ref + l_f d psi -
        (l_f - e) d ydot_ref / v, psi_e = d ydot_ref / v - d psi - d v_c / v (the crab's course), and

            d gamma_d = (v_d / L) (psi_e - c e_cross)

        A static gain (python-control StateSpace, ports as names)."""
        p = self.p
        e = along_track_error
        v_d = speed + p["k_s"] * math.tanh(p["k_c"] * e)
        c = p["k"] / (p["v_soft"] + max(v_d, 0.0))
        g = v_d / (p["l_f"] + p["l_r"])
        gains = {"yaw_rate_desired": {"y_ref": g * c, "y": -g * c, "heading": -g * (1.0 + c * p["l_f"]),
                                      "ydot_ref": g * (1.0 + c * (p["l_f"] - e)) / speed,
                                      "lateral_velocity": -g / speed if speed > 0.1 else 0.0},
                 "error_y": {"y_ref": 1.0, "y": -1.0}}
        return static_law(gains, LATERAL_INPUTS, dt)


COMPONENT = Stanley
