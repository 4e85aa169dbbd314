"""Yaw-rate MPC (paper section V): G_2nd = 291/(s^2+10.9s+242) at the component's step (20 Hz),
N_p = 8, N_c = 3, Q = 0.5, R = 1, |delta| <= 45 deg, |d delta/dt| <= 55 deg/s.
Formulation and solver: models.condensed_mpc (persistent daqp workspace by default)."""
from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from agrobot.orchestrator.compiled.cores import CoreDescription, NoCCore, c_array
from agrobot.orchestrator.component import Component, inp, out, par

from .models.c_sources import GUIDANCE_LAWS, QP_SOLVER
from .models.condensed_mpc import CondensedTrackingMPC
from .models.paper_models import G_2ND
from .models.loop_blocks import Block


def _mpc_compiled(comp, period: float) -> str:
    p = comp.p
    return _mpc_design(tuple(map(float, p["num"])), tuple(map(float, p["den"])), float(period),
                       int(p["prediction_horizon"]), int(p["control_horizon"]), float(p["Q"]), float(p["R"]),
                       float(p["steer_limit"]), float(p["steer_rate_limit"]), p["model_input"] == "measured")


@functools.lru_cache(maxsize=32)
def _mpc_design(num, den, period, horizon, control_horizon, Q, R, steer_limit, steer_rate_limit, measured) -> str:
    """The MPC's compiled design, condensed as models.condensed_mpc does (a sweep's draws share it:
    designed once per process)."""
    m = CondensedTrackingMPC(list(num), list(den), period, horizon, control_horizon, Q, R, steer_limit,
                             steer_rate_limit * period)
    if m.Nc > 10 or m.A.shape[0] > 8:
        raise NoCCore(f"its C core's QP solver handles a control horizon up to 10 (got {m.Nc}) and a model order up "
                      f"to 8")
    return (f"#define NX {m.A.shape[0]}\n#define NC {m.Nc}\n#define MEASURED_INPUT {int(measured)}\n"
            f"static const double MPC_H[NC * NC] = {{{c_array(m.H)}}};\n"
            f"static const double MPC_G[NC * (NX + 2)] = {{{c_array(m.G)}}};\n"
            f"static const double MPC_S[NC * NC] = {{{c_array(m.S)}}};\n"
            f"static const double MPC_ADVANCE[2 * NX * (NX + 2)] = {{{c_array(m._advance)}}};\n"
            f"static const double MPC_B[NX] = {{{c_array(m.B)}}};\n")


def _mpc_dependencies(comp) -> dict[str, list[str]]:
    reads = ["yaw_rate_ref", "yaw_rate"] + (["steer_angle"] if comp.p["model_input"] == "measured" else [])
    return {"steer_angle_cmd": reads, "qp_status": reads}


class YawRateMPC(Component):
    sampled = True
    roles = ("yaw_rate_controller",)
    # its C model core, beside this file: the design compiled in, an exact active-set QP solver of its own
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), _mpc_compiled,
                             ("num", "den", "prediction_horizon", "control_horizon", "Q", "R", "model_input"),
                             ("qp_solver", "qp_tolerance"), dependencies=_mpc_dependencies,
                             extra_sources=GUIDANCE_LAWS + QP_SOLVER)
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

    def linear_model(self, step: float, speed: float) -> Block:
        """The MPC while no constraint is active (components.models.condensed_mpc): the first move
        du = K [x_k; u_{k-1}; gamma - gamma_d], K = -(H^-1 G)[0], with its model advanced by the measured
        wheel angle (x_k = A x_{k-1} + B delta_m) or by its last command (x_k = A x_{k-1} + B u_{k-1});
        state [x_{k-1}; u_{k-1}], inputs (steer_angle, yaw_rate, yaw_rate_ref)."""
        p = self.p
        mpc = CondensedTrackingMPC(p["num"], p["den"], step, int(p["prediction_horizon"]), int(p["control_horizon"]),
                                   float(p["Q"]), float(p["R"]), float(p["steer_limit"]), float(p["steer_rate_limit"]) * step)
        n = mpc.A.shape[0]
        K = -np.linalg.solve(mpc.H, mpc.G)[0]
        Kx, Ku, Ke = K[:n], K[n], K[n + 1]
        Am, Bm = mpc.A, mpc.B.reshape(-1)
        if p["model_input"] == "measured":
            Ax = np.hstack([Am, np.zeros((n, 1))])               # x_k from (x_{k-1}, u_{k-1})
            Bx = np.column_stack([Bm, np.zeros(n), np.zeros(n)])
        else:
            Ax = np.hstack([Am, Bm.reshape(-1, 1)])
            Bx = np.zeros((n, 3))
        urow = np.concatenate([Kx @ Ax[:, :n], [Kx @ Ax[:, n] + 1.0 + Ku]])
        ucol = Kx @ Bx + np.array([0.0, Ke, -Ke])
        A = np.vstack([Ax, urow])
        B = np.vstack([Bx, ucol])
        return Block.of(self.name, ["steer_angle", "yaw_rate", "yaw_rate_ref"], ["steer_angle_cmd"], A, B, urow, ucol)


COMPONENT = YawRateMPC
