"""Offset-free tracking MPC for a SISO model, condensed into a small dense QP (paper section V).

Model: G(s) discretised with a zero-order hold at T_s -> (A, B, C). An internal model runs in
parallel with the applied inputs, x_k = A x_{k-1} + B u_{k-1}; the output disturbance
d_k = y_meas - C x_k is held over the horizon (this gives zero steady-state error).

Decision: input moves DU = [du_0 .. du_{Nc-1}], u_{k+j} = u_{k-1} + sum_{l<=min(j,Nc-1)} du_l.
Predicted outputs Y = f + Phi DU with f_i = C A^i x_k + s_i u_{k-1} + d_k and
Phi[i-1, l] = s_{i-l} (step-response coefficients s_m = sum_{q=1..m} C A^{q-1} B), i = 1..Np.

    minimise   Q ||r 1 - Y||^2 + R ||DU||^2
    subject to |du_l| <= du_max,   |u_{k-1} + sum_{m<=l} du_m| <= u_max

i.e. 0.5 DU' H DU + g' DU with H = 2 (Q Phi'Phi + R I), g = 2 Q Phi'(f - r 1).
The paper writes the weights as x'Qx + u'Ru; weighting the tracking error and the input moves is
what makes the yaw-rate tracking free of steady-state error, as the paper reports.
"""
from __future__ import annotations

from dataclasses import dataclass

import daqp
import numpy as np
from proxsuite import proxqp

from .yaw_dynamics import controllable_canonical, zoh_discretize

SOLVERS = ("daqp", "proxsuite")


@dataclass
class QPData:
    H: np.ndarray
    g: np.ndarray
    A: np.ndarray          # general constraints lower <= A x <= upper
    lower: np.ndarray
    upper: np.ndarray
    box: np.ndarray        # |x_i| <= box_i


def polish(qp: QPData, x: np.ndarray, tol: float = 1e-4) -> np.ndarray:
    """Refine an approximate QP solution: guess the active set from the constraints within
    ``tol`` of their bounds, solve that equality-constrained KKT system exactly and keep the
    result when it is feasible with multipliers of the right sign."""
    n = len(x)
    rows, rhs = [], []
    for i in range(n):
        if abs(x[i] - qp.box[i]) < tol:
            rows.append(np.eye(n)[i]); rhs.append(qp.box[i])
        elif abs(x[i] + qp.box[i]) < tol:
            rows.append(-np.eye(n)[i]); rhs.append(qp.box[i])
    Ax = qp.A @ x
    for i in range(len(Ax)):
        if abs(Ax[i] - qp.upper[i]) < tol:
            rows.append(qp.A[i]); rhs.append(qp.upper[i])
        elif abs(Ax[i] - qp.lower[i]) < tol:
            rows.append(-qp.A[i]); rhs.append(-qp.lower[i])
    k = len(rows)
    if k > n:
        return x
    G = np.array(rows).reshape(k, n)
    kkt = np.block([[qp.H, G.T], [G, np.zeros((k, k))]])
    try:
        sol = np.linalg.solve(kkt, np.concatenate([-qp.g, rhs]))
    except np.linalg.LinAlgError:
        return x
    xp, lam = sol[:n], sol[n:]
    feasible = (np.all(np.abs(xp) <= qp.box + 1e-9) and np.all(qp.A @ xp <= qp.upper + 1e-9)
                and np.all(qp.A @ xp >= qp.lower - 1e-9))
    return xp if feasible and np.all(lam >= -1e-9) else x


class CondensedTrackingMPC:
    """Per step (all matrices precomputed; the step allocates only what the QP solver returns):

        g  = G [x; u_{k-1}; y_meas - r]     with G = 2 Q Phi' [CApow - 1 C,  s,  1]
        bounds: |du| <= du_max,  -u_max - u_{k-1} <= S du <= u_max - u_{k-1}   (S lower-triangular ones)

    (the disturbance d = y_meas - C x is folded into G, so g is one matrix-vector product)."""

    def __init__(self, num, den, dt: float, Np: int, Nc: int, Q: float, R: float,
                 u_max: float, du_max: float, solver: str = "daqp", tolerance: float = 1e-10) -> None:
        if not (1 <= Nc <= Np):
            raise ValueError(f"need 1 <= control horizon ({Nc}) <= prediction horizon ({Np})")
        if Q < 0 or R <= 0:
            raise ValueError("need Q >= 0 and R > 0")
        if solver not in SOLVERS:
            raise ValueError(f"qp solver {solver!r}; expected one of {SOLVERS}")
        Ac, Bc, Cc = controllable_canonical(num, den)
        self.A, self.B = zoh_discretize(Ac, Bc, dt)
        self.C = Cc
        self.Np, self.Nc, self.Q, self.R = Np, Nc, Q, R
        self.u_max, self.du_max = u_max, du_max
        n = self.A.shape[0]
        # free-response rows C A^i (i = 1..Np) and step-response coefficients s_1..s_Np
        self.CApow = np.zeros((Np, n))
        markov = np.zeros(Np + 1)
        Ai = np.eye(n)
        for i in range(1, Np + 1):
            markov[i] = self.C @ Ai @ self.B          # C A^{i-1} B
            Ai = Ai @ self.A
            self.CApow[i - 1] = self.C @ Ai
        self.step_response = np.cumsum(markov)        # s_0 = 0, s_m
        self.Phi = np.zeros((Np, Nc))
        for i in range(1, Np + 1):
            for l in range(min(i, Nc)):
                self.Phi[i - 1, l] = self.step_response[i - l]
        self.H = 2.0 * (Q * self.Phi.T @ self.Phi + R * np.eye(Nc))
        self.S = np.tril(np.ones((Nc, Nc)))
        ones = np.ones(Np)
        self.G = 2.0 * Q * self.Phi.T @ np.column_stack(
            [self.CApow - np.outer(ones, self.C), self.step_response[1:], ones])
        self.solver_name, self.tolerance = solver, tolerance
        self._n = n
        self._z = np.zeros(n + 2)                     # [x; u_prev; y_meas - r]
        # one product advances the model both ways: W = [A x + B u; A x] with z = [x; u; .]
        self._advance = np.block([[self.A, self.B.reshape(-1, 1), np.zeros((n, 1))],
                                  [self.A, np.zeros((n, 2))]])
        self._w = np.zeros(2 * n)
        self._g = np.zeros(Nc)
        self._bu = np.full(2 * Nc, du_max)            # daqp: [box; general rows]
        self._bl = np.full(2 * Nc, -du_max)
        self._solver = None
        self.reset()

    @property
    def x(self) -> np.ndarray:
        """Internal model state (a view)."""
        return self._z[:self._n]

    @x.setter
    def x(self, value) -> None:
        self._z[:self._n] = value

    @property
    def u_prev(self) -> float:
        return float(self._z[self._n])

    @u_prev.setter
    def u_prev(self, value: float) -> None:
        self._z[self._n] = value

    def reset(self, u_prev: float = 0.0) -> None:
        self._z[:] = 0.0
        self._z[self._n] = u_prev
        self._w[:] = 0.0
        self.last_du = np.zeros(self.Nc)
        self._solver = None

    def qp(self, r: float, y_meas: float) -> QPData:
        """The QP of this instant (no state change)."""
        z = self._z.copy()
        z[-1] = y_meas - r
        u_prev = z[self._n]
        lower = np.full(self.Nc, -self.u_max - u_prev)
        upper = np.full(self.Nc, self.u_max - u_prev)
        return QPData(self.H, self.G @ z, self.S, lower, upper, np.full(self.Nc, self.du_max))

    def _daqp(self, g: np.ndarray, bu: np.ndarray, bl: np.ndarray) -> tuple[np.ndarray, int]:
        if self._solver is None:
            self._solver = daqp.Model()
            self._solver.setup(self.H, g, self.S, bu, bl)
            self._solver.settings = {"primal_tol": self.tolerance, "dual_tol": self.tolerance}
        else:
            self._solver.update(f=g, bupper=bu, blower=bl)
        x, _, flag, _ = self._solver.solve()
        return x, flag

    def _solve(self, qp: QPData) -> tuple[np.ndarray, int]:
        bu = np.concatenate([qp.box, qp.upper])
        bl = np.concatenate([-qp.box, qp.lower])
        if self.solver_name == "daqp":
            x, flag = self._daqp(qp.g, bu, bl)
            return np.asarray(x, dtype=float), int(flag)
        return self._proxsuite(qp, bl, bu)

    def _proxsuite(self, qp: QPData, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, int]:
        # bounds on the moves as ordinary inequality rows: proxsuite's box-constraint mode
        # returned wrong answers (outside the box) on instances of this shape
        if self._solver is None:
            s = proxqp.dense.QP(self.Nc, 0, 2 * self.Nc)
            s.settings.eps_abs, s.settings.eps_rel = self.tolerance, 0.0
            # warm start from the previous result; proxsuite 0.8.0 crashes on update() before
            # the first solve, so the first call goes through init() only
            s.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            s.init(qp.H, qp.g, None, None, np.vstack([np.eye(self.Nc), qp.A]), lower, upper)
            self._solver = s
        else:
            self._solver.update(g=qp.g, l=lower, u=upper)
        self._solver.solve()
        if self._solver.results.info.status != proxqp.QPSolverOutput.PROXQP_SOLVED:
            # a warm start from a distant problem can mislead it: one cold retry
            self._solver.settings.initial_guess = proxqp.InitialGuess.NO_INITIAL_GUESS
            self._solver.solve()
            self._solver.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
        if self._solver.results.info.status != proxqp.QPSolverOutput.PROXQP_SOLVED:
            return np.zeros(self.Nc), -1
        return polish(qp, np.array(self._solver.results.x, dtype=float)), 1

    def step(self, r: float, y_meas: float, u_applied: float | None = None) -> tuple[float, int]:
        """Solve at this instant, apply the first move, advance the internal model.
        ``u_applied``: the input the plant actually received over the last step (a measured
        actuator position): the internal model is advanced with it instead of the last command;
        the moves and their limits stay relative to the last command. Returns (u_k, status > 0)."""
        z, n = self._z, self._n
        if u_applied is not None:           # A x + B u_applied: W's lower half plus B u, element by element
            w, b = self._w.tolist(), self.B.tolist()
            z[:n] = [w[n + i] + b[i] * u_applied for i in range(n)]
        u_prev = float(z[n])                            # Python floats from here: no numpy scalar arithmetic
        z[n + 1] = y_meas - r
        if self.solver_name == "daqp":
            self.G.dot(z, self._g)                      # np.dot without its dispatch
            self._bu[self.Nc:] = self.u_max - u_prev
            self._bl[self.Nc:] = -self.u_max - u_prev
            du, status = self._daqp(self._g, self._bu, self._bl)
        else:
            du, status = self._solve(self.qp(r, y_meas))
        du0 = float(du[0])
        if status <= 0 or du0 != du0:                   # failed or NaN: hold the previous input
            du, du0 = np.zeros(self.Nc), 0.0
        u = min(max(u_prev + du0, -self.u_max), self.u_max)
        z[n] = u
        w = self._w
        self._advance.dot(z, w)
        z[:n] = w[:n]
        self.last_du = du
        return float(u), status
