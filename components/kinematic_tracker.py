"""Kinematic trajectory controller (paper section VI-A.1, after Martins et al.).

    xdot_d = xdot_r + k_s tanh(k_c e_x),   ydot_d = ydot_r + k_s tanh(k_c e_y),   e = ref - CG
    [v_d, gamma_fb]^T = [[cos psi, sin psi], [-sin psi / l_r, cos psi / l_r]] [xdot_d, ydot_d]^T

Look-ahead (an option; ``lookahead`` a = 0 or a = l_r is the paper's law): steer a point P at
a > l_r ahead of the rear axle so that the CG still follows the reference. P - CG = (a - l_r)
(cos psi, sin psi), so P's desired velocity is the CG's plus (a - l_r) gamma_r (-sin psi, cos psi)
with the reference's yaw rate gamma_r as feed-forward; inverting P's kinematics gives

    gamma_d = (l_r gamma_fb + (a - l_r) gamma_r) / a

The heading feedback gain drops from v/l_r to v/a (5 -> 1.7 rad/s at 2 m/s for a = 1.2 m), which
the yaw-rate loop can follow with actuator delay; on a curve the feed-forward keeps the CG on the
path. v_d is unchanged (P and CG move alike along the heading).

Crab (``lateral_velocity`` v_c, an estimate of the rear axle's sideways velocity: wheel slip on a
side slope or in a turn; 0 without an estimator that gives it): R moves at v (cos psi, sin psi) +
v_c (-sin psi, cos psi), so the body-lateral velocity the law asks of the CG is made by the yaw
rate minus the crab, gamma_fb = (lateral - v_c) / l_r; a steady side force then leaves no
steady offset (the feedback needs no error to cancel the crab).

Imported where used: control (start-up: 0.8 s of CPU, measured, that every run holding the tracker would pay;
only the linear analyses use it).
"""
from __future__ import annotations

from pathlib import Path
import math
from typing import Mapping

import numpy as np

from agrobot.orchestrator.compiled.cores import CoreDescription
from agrobot.orchestrator.component import Component, inp, out, par
from .models.c_sources import GUIDANCE_LAWS


def inverse_kinematics(xdot: float, ydot: float, psi: float, l_r: float, crab: float = 0.0) -> tuple[float, float]:
    """(v_x, gamma) that move the CG with velocity (xdot, ydot) when the rear axle slips sideways at
    ``crab`` (left positive; 0: no slip)."""
    c, s = math.cos(psi), math.sin(psi)
    return c * xdot + s * ydot, (-s * xdot + c * ydot - crab) / l_r


# the ports every tracker shares (kinematic, pure pursuit, Stanley): swappable in a study
TRACKER_INPUTS = (
    inp("x_ref", "m", 0.0, "reference CG east position"),
    inp("y_ref", "m", 0.0, "reference CG north position"),
    inp("xdot_ref", "m/s", 0.0, "reference east velocity"),
    inp("ydot_ref", "m/s", 0.0, "reference north velocity"),
    inp("x", "m", 0.0, "estimated CG east position"),
    inp("y", "m", 0.0, "estimated CG north position"),
    inp("heading", "rad", 0.0, "estimated yaw angle"),
    inp("yaw_rate_ref", "rad/s", 0.0, "reference yaw rate gamma_r (feed-forward)"),
    inp("lateral_velocity", "m/s", 0.0, "estimated crab of the rear axle, left positive (feed-forward; 0: none)", optional=True),
)
TRACKER_OUTPUTS = (
    out("speed_desired", "m/s", 0.0, "desired speed v_d"),
    out("yaw_rate_desired", "rad/s", 0.0, "desired yaw rate gamma_d"),
    out("error_x", "m", 0.0, "e_x = x_ref - x"),
    out("error_y", "m", 0.0, "e_y = y_ref - y"),
)
TRACKER_FEEDTHROUGH = {o.name: tuple(i.name for i in TRACKER_INPUTS) for o in TRACKER_OUTPUTS}
SPEED_LAW = (par("k_s", "m/s", 0.6, "saturation constant"), par("k_c", "1/m", 1.5, "gain"))


def trim_along_track_error(p: Mapping[str, float], speed_excess: float) -> float:
    """The along-track error e at which the speed law v_d = v_r + k_s tanh(k_c e) asks
    ``speed_excess`` = v_d - v_r (what a speed loop with a steady error needs to hold v_r)."""
    ratio = min(max(speed_excess / p["k_s"], -0.999999), 0.999999)
    return math.atanh(ratio) / p["k_c"]


# The lateral channel of a tracker about a straight reference heading east (psi = 0) with the CG on
# it: the ports whose small deviations move the yaw-rate command (north positions and velocities,
# heading, reference yaw rate, the estimated crab); east positions and speeds enter at second order only.
LATERAL_INPUTS = ("y_ref", "ydot_ref", "yaw_rate_ref", "y", "heading", "lateral_velocity")


def static_law(gains: Mapping[str, Mapping[str, float]], inputs: tuple[str, ...], dt: float):
    """A memoryless linear law as a python-control StateSpace with no state, inputs and outputs
    named by port: ``gains[output][input]`` = d output / d input (absent: 0)."""
    import control

    outputs = tuple(gains)
    D = np.array([[float(gains[o].get(i, 0.0)) for i in inputs] for o in outputs])
    return control.ss(np.zeros((0, 0)), np.zeros((0, len(inputs))), np.zeros((len(outputs), 0)), D, dt,
                      inputs=list(inputs), outputs=list(outputs))


class KinematicTracker(Component):
    sampled = True
    roles = ("tracker",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), extra_sources=GUIDANCE_LAWS)
    variables = TRACKER_INPUTS + SPEED_LAW + (
        par("l_r", "m", 0.4, "rear axle to CG"),
        par("lookahead", "m", 0.0, "steered point a ahead of the rear axle (0: a = l_r, the paper's law)"),
    ) + TRACKER_OUTPUTS
    feedthrough = TRACKER_FEEDTHROUGH

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(p["l_r"] > 0, "l_r must be > 0")
        self.require(p["lookahead"] == 0 or p["lookahead"] >= p["l_r"],
                     f"lookahead {p['lookahead']} m must be 0 (the paper's law) or >= l_r {p['l_r']} m")

    def step(self, t: float, dt: float) -> None:
        u, p = self.u, self.p
        ex, ey = u["x_ref"] - u["x"], u["y_ref"] - u["y"]
        xdot_d = u["xdot_ref"] + p["k_s"] * math.tanh(p["k_c"] * ex)
        ydot_d = u["ydot_ref"] + p["k_s"] * math.tanh(p["k_c"] * ey)
        v_d, gamma_d = inverse_kinematics(xdot_d, ydot_d, u["heading"], p["l_r"], u["lateral_velocity"])
        share = p["l_r"] / (p["lookahead"] or p["l_r"])      # l_r / a; 1 for the paper's law
        if share != 1.0:
            gamma_d = share * gamma_d + (1.0 - share) * u["yaw_rate_ref"]
        y = self.y
        y["speed_desired"], y["yaw_rate_desired"], y["error_x"], y["error_y"] = v_d, gamma_d, ex, ey

    def lateral_linearisation(self, speed: float, dt: float, along_track_error: float = 0.0):
        """Small deviations about a straight reference heading east at ``speed``, the CG on its
        line ``along_track_error`` behind the reference point (psi = e_y = 0; xdot_d = v_d = v + k_s
        tanh(k_c e_x)): from gamma_fb = (-sin psi xdot_d + cos psi ydot_d - v_c) / l_r and gamma_d = (l_r / a)
        gamma_fb + (1 - l_r / a) gamma_r,

            d gamma_d = (k_s k_c (d y_ref - d y) - v_d d psi + d ydot_ref - d v_c) / a + (1 - l_r / a) d gamma_r

        (a = l_r: the paper's law). A static gain (python-control StateSpace, ports as names)."""
        p = self.p
        a = p["lookahead"] or p["l_r"]
        k = p["k_s"] * p["k_c"]
        v_d = speed + p["k_s"] * math.tanh(p["k_c"] * along_track_error)
        gains = {"yaw_rate_desired": {"y_ref": k / a, "y": -k / a, "heading": -v_d / a, "ydot_ref": 1.0 / a,
                                      "yaw_rate_ref": 1.0 - p["l_r"] / a, "lateral_velocity": -1.0 / a},
                 "error_y": {"y_ref": 1.0, "y": -1.0}}
        return static_law(gains, LATERAL_INPUTS, dt)


COMPONENT = KinematicTracker
