"""Pure-pursuit tracker (Coulter 1992; the steering law AgOpenGPS users know), on the time-based
reference, as a drop-in for the kinematic tracker (same inputs, same outputs to the yaw-rate MPC
and the speed PID).

The rear axle R = CG - l_r (cos psi, sin psi) chases the goal point G = ref + L_d t_r (t_r the
reference's unit velocity; L_d = max(lookahead_min, lookahead_time v_r)). With alpha the angle from
the heading to G - R and D = |G - R|:

    kappa = 2 sin(alpha) / D,   gamma_d = v_d kappa,   v_d = v_r + k_s tanh(k_c e_along)

e_along = (ref - CG) . t_r is the along-track error (the reference is time based). With a crab v_c
(``lateral_velocity``) R moves along its course psi + beta, beta = atan(v_c / v_r): alpha is taken
from the course.
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, par

from .kinematic_tracker import (LATERAL_INPUTS, SPEED_LAW, TRACKER_FEEDTHROUGH, TRACKER_INPUTS, TRACKER_OUTPUTS,
                                static_law)

def along_track(u, p) -> tuple[float, float, float, float, float]:
    """(e_x, e_y, v_r, unit reference direction t_x, t_y) and the speed law's v_d."""
    ex, ey = u["x_ref"] - u["x"], u["y_ref"] - u["y"]
    v_r = math.hypot(u["xdot_ref"], u["ydot_ref"])
    if v_r > 1e-9:
        tx, ty = u["xdot_ref"] / v_r, u["ydot_ref"] / v_r
    else:
        tx, ty = math.cos(u["heading"]), math.sin(u["heading"])
    v_d = v_r + p["k_s"] * math.tanh(p["k_c"] * (ex * tx + ey * ty))
    return ex, ey, tx, ty, v_d


def crab_angle(crab: float, speed: float) -> float:
    """beta = atan(v_c / v): the course's angle from the heading (0 at rest)."""
    return math.atan2(crab, speed) if speed > 0.1 else 0.0


class PurePursuit(Component):
    sampled = True
    roles = ("tracker",)
    variables = TRACKER_INPUTS + SPEED_LAW + TRACKER_OUTPUTS + (
        par("l_r", "m", 0.4, "rear axle to CG"),
        par("lookahead_min", "m", 2.0, "shortest look-ahead distance L_d"),
        par("lookahead_time", "s", 1.5, "look-ahead distance per unit reference speed"),
    )
    feedthrough = TRACKER_FEEDTHROUGH

    def step(self, t: float, dt: float) -> None:
        u, p, y = self.u, self.p, self.y
        ex, ey, tx, ty, v_d = along_track(u, p)
        v_r = math.hypot(u["xdot_ref"], u["ydot_ref"])
        L_d = max(p["lookahead_min"], p["lookahead_time"] * v_r)
        psi = u["heading"]
        c, s = math.cos(psi), math.sin(psi)
        rx, ry = u["x"] - p["l_r"] * c, u["y"] - p["l_r"] * s
        gx, gy = u["x_ref"] + L_d * tx - rx, u["y_ref"] + L_d * ty - ry
        D = max(math.hypot(gx, gy), 1e-6)
        alpha = math.atan2(-s * gx + c * gy, c * gx + s * gy) - crab_angle(u["lateral_velocity"], v_r)
        y["speed_desired"] = v_d
        y["yaw_rate_desired"] = v_d * 2.0 * math.sin(alpha) / D
        y["error_x"], y["error_y"] = ex, ey

    def lateral_linearisation(self, speed: float, dt: float, along_track_error: float = 0.0):
        """Small deviations about a straight reference heading east at ``speed``, the CG on its
        line e = ``along_track_error`` behind the reference point (v_d = v + k_s tanh(k_c e)). The
        goal lies D0 = e + L_d + l_r ahead of R; its lateral offset in the body frame is
        (y_ref - y) + L_d ydot_ref / v - (e + L_d) psi, and the crab turns the course by v_c / v, so

            alpha = ((d y_ref - d y) + L_d d ydot_ref / v - (e + L_d) d psi) / D0 - d v_c / v,
            d gamma_d = 2 v_d alpha / D0

        A static gain (python-control StateSpace, ports as names)."""
        p = self.p
        e = along_track_error
        L_d = max(p["lookahead_min"], p["lookahead_time"] * speed)
        D0 = e + L_d + p["l_r"]
        g = 2.0 * (speed + p["k_s"] * math.tanh(p["k_c"] * e)) / D0 ** 2
        gains = {"yaw_rate_desired": {"y_ref": g, "y": -g, "heading": -g * (e + L_d), "ydot_ref": g * L_d / speed,
                                      "lateral_velocity": -g * D0 / speed if speed > 0.1 else 0.0},
                 "error_y": {"y_ref": 1.0, "y": -1.0}}
        return static_law(gains, LATERAL_INPUTS, dt)


COMPONENT = PurePursuit
