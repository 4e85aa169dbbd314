"""Yaw-rate MPC (paper section V): G_2nd = 291/(s^2+10.9s+242) at the component's step (20 Hz),
N_p = 8, N_c = 3, Q = 0.5, R = 1, |delta| <= 45 deg, |d delta/dt| <= 55 deg/s.
Formulation and solver: models.condensed_mpc (persistent daqp workspace by default)."""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par

from .models.paper_models import G_2ND
from .models.condensed_mpc import CondensedTrackingMPC


class YawRateMPC(Component):
    sampled = True
    roles = ("yaw_rate_controller",)
    LINEAR_MODEL = "agrobot.analysis.component_models:yaw_rate_mpc"   # its block in the margins' loop
    C_CORE = "yaw_rate_mpc"      # its C model core for FMU export: src/agrobot/fmu_export/c/components/yaw_rate_mpc.c
    variables = (
        inp("yaw_rate_ref", "rad/s", 0.0, "desired yaw rate gamma_d"),
        inp("yaw_rate", "rad/s", 0.0, "measured yaw rate"),
        inp("steer_angle", "rad", 0.0, "measured wheel angle (used when model_input = measured)"),
        par("num", "", list(G_2ND.num), "model numerator (steer angle -> yaw rate), highest power first"),
        par("den", "", list(G_2ND.den), "model denominator"),
        par("prediction_horizon", "1", 8, "N_p"),
        par("control_horizon", "1", 3, "N_c"),
        par("Q", "1", 0.5, "weight of the yaw-rate tracking error"),
        par("R", "1", 1.0, "weight of the steering moves"),
        par("steer_limit", "rad", math.radians(45.0), "|delta| bound"),
        par("steer_rate_limit", "rad/s", math.radians(55.0), "|d delta / dt| bound"),
        par("model_input", "", "measured", "drive the internal model with the last 'command' or the 'measured' angle"),
        par("qp_solver", "", "daqp", "daqp or proxsuite"),
        par("qp_tolerance", "1", 1e-10, "primal/dual (daqp) or absolute (proxsuite) tolerance"),
        out("steer_angle_cmd", "rad", 0.0, "desired front wheel angle"),
        out("qp_status", "1", 1.0, "solver exit flag (> 0 solved)"),
    )
    feedthrough = {"steer_angle_cmd": ("yaw_rate_ref", "yaw_rate"), "qp_status": ("yaw_rate_ref", "yaw_rate")}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(p["model_input"] in ("command", "measured"), "model_input must be 'command' or 'measured'")
        self.measured_input, self.t0 = p["model_input"] == "measured", t0
        try:
            self.mpc = CondensedTrackingMPC(p["num"], p["den"], dt, int(p["prediction_horizon"]),
                                            int(p["control_horizon"]), float(p["Q"]), float(p["R"]),
                                            float(p["steer_limit"]), float(p["steer_rate_limit"]) * dt,
                                            p["qp_solver"], float(p["qp_tolerance"]))
        except ValueError as exc:
            self.require(False, str(exc))

    def step(self, t: float, dt: float) -> None:
        applied = float(self.u["steer_angle"]) if self.measured_input and t > self.t0 else None
        u, status = self.mpc.step(float(self.u["yaw_rate_ref"]), float(self.u["yaw_rate"]), applied)
        self.y["steer_angle_cmd"], self.y["qp_status"] = u, float(status)


COMPONENT = YawRateMPC
