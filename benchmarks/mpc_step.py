"""One yaw-rate MPC step: ours (model update + QP + bookkeeping) against the bare QP (daqp and
proxsuite, persistent and warm-started, on the same QPs) and against do-mpc on the identical
problem (optional extra: pip install -e ".[bench]"). Answers are checked equal to 1e-6 first.

    python benchmarks/mpc_step.py [--steps 2000]
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np

from agrobot.components.models.condensed_mpc import CondensedTrackingMPC
from agrobot.components.models.paper_models import G_2ND as G2ND

DT, NP, NC, Q, R = 0.05, 8, 3, 0.5, 1.0
U_MAX, DU_MAX = math.radians(45), math.radians(55) * 0.05


def paper_mpc(solver="daqp") -> CondensedTrackingMPC:
    return CondensedTrackingMPC(*G2ND, DT, NP, NC, Q, R, U_MAX, DU_MAX, solver)


def scenario(steps: int, seed: int = 0):
    """Closed loop of the MPC on its own model with a reference that steps and ramps and a noisy
    measurement: realistic warm starts, constraints active part of the time."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) * DT
    ref = 0.4 * np.sign(np.sin(2 * np.pi * t / 6.0)) + 0.3 * np.sin(2 * np.pi * t / 2.3)
    return ref, 0.01 * rng.standard_normal(steps)


def run_ours(steps: int):
    """Returns per-step times [s], the QPs seen (for the bare solvers) and the moves."""
    mpc = paper_mpc()
    plant_x = np.zeros(2)
    ref, noise = scenario(steps)
    times, qps, moves = [], [], []
    for k in range(steps):
        y = float(mpc.C @ plant_x) + noise[k]
        qps.append(mpc.qp(ref[k], y))            # recorded outside the timed call
        t0 = time.perf_counter_ns()
        u, _ = mpc.step(ref[k], y)
        times.append(time.perf_counter_ns() - t0)
        moves.append(mpc.last_du.copy())
        plant_x = mpc.A @ plant_x + mpc.B * u
    return np.array(times) * 1e-9, qps, np.array(moves)


def run_daqp(qps):
    import daqp

    m = daqp.Model()
    q0 = qps[0]
    bu = np.concatenate([q0.box, q0.upper])
    bl = np.concatenate([-q0.box, q0.lower])
    m.setup(q0.H, q0.g, q0.A, bu, bl)
    m.settings = {"primal_tol": 1e-10, "dual_tol": 1e-10}
    times, xs = [], []
    for q in qps:
        bu[len(q.box):], bl[len(q.box):] = q.upper, q.lower
        t0 = time.perf_counter_ns()
        m.update(f=q.g, bupper=bu, blower=bl)
        x, _, _, _ = m.solve()
        times.append(time.perf_counter_ns() - t0)
        xs.append(np.array(x))
    return np.array(times) * 1e-9, np.array(xs)


def run_proxsuite(qps):
    from proxsuite import proxqp

    n = len(qps[0].g)
    C = np.vstack([np.eye(n), qps[0].A])
    s = proxqp.dense.QP(n, 0, 2 * n)
    s.settings.eps_abs, s.settings.eps_rel = 1e-10, 0.0
    s.settings.max_iter = 1000
    s.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
    q0 = qps[0]
    s.init(q0.H, q0.g, None, None, C, np.concatenate([-q0.box, q0.lower]), np.concatenate([q0.box, q0.upper]))
    times, xs = [], []
    for k, q in enumerate(qps):
        lo, up = np.concatenate([-q.box, q.lower]), np.concatenate([q.box, q.upper])
        t0 = time.perf_counter_ns()
        if k:   # proxsuite 0.8.0 segfaults on update() before the first warm-started solve
            s.update(g=q.g, l=lo, u=up)
        s.solve()
        times.append(time.perf_counter_ns() - t0)
        xs.append(np.array(s.results.x))
    return np.array(times) * 1e-9, np.array(xs)


def run_do_mpc(steps: int):
    """The same problem in do-mpc: state [x; u_prev; d; r], input du; cost Q (r - Cx - d)^2 +
    R du^2 over N_p steps; moves beyond N_c forced to zero by a time-varying mask."""
    import casadi as ca
    import do_mpc

    if hasattr(ca, "setNumpyMode"):
        ca.setNumpyMode(-1)               # keep casadi's legacy conversion, without its notice

    ref_mpc = paper_mpc()
    A, B, Cm = ref_mpc.A, ref_mpc.B, ref_mpc.C
    model = do_mpc.model.Model("discrete")
    x = model.set_variable("_x", "x", shape=(2, 1))
    up = model.set_variable("_x", "u_prev")
    d = model.set_variable("_x", "d")
    r = model.set_variable("_x", "r")
    du = model.set_variable("_u", "du")
    mask = model.set_variable("_tvp", "mask")
    u = up + mask * du
    model.set_rhs("x", ca.DM(A) @ x + ca.DM(B) * u)
    model.set_rhs("u_prev", u)
    model.set_rhs("d", d)
    model.set_rhs("r", r)
    model.setup()
    mpc = do_mpc.controller.MPC(model)
    mpc.settings.n_horizon = NP
    mpc.settings.t_step = DT
    mpc.settings.store_full_solution = False
    mpc.settings.nlpsol_opts = {"ipopt.print_level": 0, "print_time": 0, "ipopt.sb": "yes",
                                "ipopt.tol": 1e-12, "ipopt.acceptable_tol": 1e-12}
    err = r - ca.DM(Cm).T @ x - d
    # stage k penalises x_k (k = 0 is a constant) and the move; the terminal term x_Np
    mpc.set_objective(lterm=Q * err**2 + R * du**2 * mask, mterm=Q * err**2)
    mpc.bounds["lower", "_u", "du"] = -DU_MAX
    mpc.bounds["upper", "_u", "du"] = DU_MAX
    mpc.bounds["lower", "_x", "u_prev"] = -U_MAX
    mpc.bounds["upper", "_x", "u_prev"] = U_MAX
    tvp = mpc.get_tvp_template()

    def tvp_fun(_t):
        for k in range(NP + 1):
            tvp["_tvp", k, "mask"] = 1.0 if k < NC else 0.0
        return tvp

    mpc.set_tvp_fun(tvp_fun)
    mpc.setup()

    ours = paper_mpc()
    plant_x = np.zeros(2)
    ref, noise = scenario(steps)
    times, diffs = [], []
    for k in range(steps):
        y = float(ours.C @ plant_x) + noise[k]
        d_k = y - float(ours.C @ ours.x)
        state = np.concatenate([ours.x, [ours.u_prev, d_k, ref[k]]]).reshape(-1, 1)
        if k == 0:
            mpc.x0 = state
            mpc.set_initial_guess()
        t0 = time.perf_counter_ns()
        du0 = float(np.asarray(mpc.make_step(state)).ravel()[0])
        times.append(time.perf_counter_ns() - t0)
        u, _ = ours.step(ref[k], y)
        diffs.append(abs(du0 - ours.last_du[0]))
        plant_x = ours.A @ plant_x + ours.B * u
    return np.array(times) * 1e-9, float(np.max(diffs))


def stats(t: np.ndarray) -> tuple[float, float]:
    return float(np.median(t)) * 1e6, float(np.percentile(t, 99)) * 1e6


def measure(steps: int = 2000, do_mpc_steps: int = 200) -> dict:
    """Per-step times [s] of each method on the same scenario, after checking the answers agree."""
    ours_t, qps, moves = run_ours(steps)
    daqp_t, daqp_x = run_daqp(qps)
    prox_t, prox_x = run_proxsuite(qps)
    worst = max(np.abs(daqp_x - moves).max(), np.abs(prox_x - moves).max())
    if worst > 1e-6:
        raise AssertionError(f"bare solvers disagree with our MPC by {worst:.2e}")
    rows = {"ours: full MPC step (daqp)": ours_t, "bare QP: daqp": daqp_t, "bare QP: proxsuite": prox_t}
    result = {"rows": rows, "steps": steps,
              "active": float(np.mean(np.any(np.isclose(np.abs(moves), DU_MAX), axis=1)))}
    try:
        if do_mpc_steps <= 0:
            raise ImportError("skipped")
        dm_t, dm_err = run_do_mpc(do_mpc_steps)
    except ImportError:
        result["do_mpc"] = "not installed (pip install -e '.[bench]')"
    else:
        if dm_err > 1e-6:
            raise AssertionError(f"do-mpc disagrees with our MPC by {dm_err:.2e}")
        rows["do-mpc make_step (IPOPT)"] = dm_t
        result["do_mpc"] = f"max |du0 difference| {dm_err:.1e} over {do_mpc_steps} steps"
    return result


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--do-mpc-steps", type=int, default=200)
    args = parser.parse_args()
    res = measure(args.steps, args.do_mpc_steps)
    rows = res["rows"]
    base = np.median(rows["bare QP: daqp"])
    print(f"MPC step, G_2nd at 20 Hz, Np={NP}, Nc={NC}; {res['steps']} steps, rate limit active in "
          f"{100 * res['active']:.0f}% of them; answers equal to 1e-6; do-mpc: {res['do_mpc']}")
    print(f"{'':<36}{'median [us]':>12}{'p99 [us]':>10}{'x bare daqp':>13}")
    for name, t in rows.items():
        med, p99 = stats(t)
        print(f"{name:<36}{med:>12.1f}{p99:>10.1f}{np.median(t) / base:>13.2f}")
    if "do-mpc make_step (IPOPT)" in rows:
        ratio = np.median(rows["do-mpc make_step (IPOPT)"]) / np.median(rows["ours: full MPC step (daqp)"])
        print(f"do-mpc / ours (median): {ratio:.0f}x")


if __name__ == "__main__":
    main()
