"""Kinematic trajectory controller (paper section VI-A.1, after Martins et al.).

    xdot_d = xdot_r + k_s tanh(k_c e_x),   ydot_d = ydot_r + k_s tanh(k_c e_y),   e = ref - CG
    [v_d, gamma_d]^T = [[cos psi, sin psi], [-sin psi / l_r, cos psi / l_r]] [xdot_d, ydot_d]^T
"""
from __future__ import annotations

import math

from orchestrator.component import Component, inp, out, par


def inverse_kinematics(xdot: float, ydot: float, psi: float, l_r: float) -> tuple[float, float]:
    """(v_x, gamma) that move the CG with velocity (xdot, ydot) when the rear axle does not slip."""
    c, s = math.cos(psi), math.sin(psi)
    return c * xdot + s * ydot, (-s * xdot + c * ydot) / l_r


class KinematicTracker(Component):
    sampled = True
    roles = ("tracker",)
    variables = (
        inp("x_ref", "m", 0.0, "reference CG east position"),
        inp("y_ref", "m", 0.0, "reference CG north position"),
        inp("xdot_ref", "m/s", 0.0, "reference east velocity"),
        inp("ydot_ref", "m/s", 0.0, "reference north velocity"),
        inp("x", "m", 0.0, "estimated CG east position"),
        inp("y", "m", 0.0, "estimated CG north position"),
        inp("heading", "rad", 0.0, "estimated yaw angle"),
        par("k_s", "m/s", 0.6, "saturation constant"),
        par("k_c", "1/m", 1.5, "gain"),
        par("l_r", "m", 0.4, "rear axle to CG"),
        out("speed_desired", "m/s", 0.0, "desired speed v_d"),
        out("yaw_rate_desired", "rad/s", 0.0, "desired yaw rate gamma_d"),
        out("error_x", "m", 0.0, "e_x = x_ref - x"),
        out("error_y", "m", 0.0, "e_y = y_ref - y"),
    )
    feedthrough = {k: ("x_ref", "y_ref", "xdot_ref", "ydot_ref", "x", "y", "heading")
                   for k in ("speed_desired", "yaw_rate_desired", "error_x", "error_y")}

    def step(self, t: float, dt: float) -> None:
        u, p = self.u, self.p
        ex, ey = u["x_ref"] - u["x"], u["y_ref"] - u["y"]
        xdot_d = u["xdot_ref"] + p["k_s"] * math.tanh(p["k_c"] * ex)
        ydot_d = u["ydot_ref"] + p["k_s"] * math.tanh(p["k_c"] * ey)
        v_d, gamma_d = inverse_kinematics(xdot_d, ydot_d, u["heading"], p["l_r"])
        y = self.y
        y["speed_desired"], y["yaw_rate_desired"], y["error_x"], y["error_y"] = v_d, gamma_d, ex, ey


COMPONENT = KinematicTracker
