"""Stability margins of the figure-8 guidance loop, linearised with python-control, against the
delay at which the simulated figure-8 leaves the paper's bounds (issue 19, item 4).

Linear model at the reference speed v, every block taken from the study through its roles:

- yaw-rate MPC without active constraints is a linear controller (models.condensed_mpc): the first
  move du_0 = K [x_k; u_{k-1}; gamma_k - gamma_d] with K = -(H^-1 G)[0]; its model state follows the
  measured wheel angle, x_k = A x_{k-1} + B delta_k; u_k = u_{k-1} + du_0;
- the steering as its closed-loop first-order equivalent 1/(tau s + 1) (models.steering_equivalent)
  with the study's command delay; the yaw plant's model at v (models.yaw_dynamics); both held over
  the MPC step (zero-order hold);
- the path loop on a straight, linearised: psi' = gamma, e' = v psi + l_r gamma (the CG's lateral
  offset), and the tracker's law gamma_d = -(v psi + k_s k_c e) / a (a the look-ahead, l_r for the
  paper's law).

Yaw-rate loop: broken at the steering command. Path loop: broken at gamma_d, with the yaw-rate loop
closed inside. On a curve of the figure-8 the linearised loops are the same (the reference yaw rate
enters as feed-forward, the plant is linear in the wheel angle at fixed speed), so one set of margins
holds for both. Delay margin = phase margin / crossover frequency: the extra actuator delay the
linear loop tolerates.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import control as ct
import numpy as np

from components.models.condensed_mpc import CondensedTrackingMPC
from components.models.steering_equivalent import FirstOrderSteering
from components.models.yaw_dynamics import TractorParameters, controllable_canonical, state_space
from orchestrator.resolver import resolve
from orchestrator.runner import run_study
from orchestrator.study import Study

from .figure8 import PAPER_BOUNDS


@dataclass
class Margins:
    gain: float              # gain margin (factor); inf when the phase never reaches -180 deg
    phase_deg: float         # phase margin; inf when |L| never crosses 1
    crossover: float         # gain crossover [rad/s] (nan without one)
    delay: float             # delay margin [s] = phase margin / crossover (inf without a crossover)


def _margins(L) -> Margins:
    """Margins from L's frequency response (python-control) on a dense grid up to Nyquist: the
    first gain crossover (|L| falls through 1) gives the phase and delay margins, the first phase
    crossover (-180 deg) above it the gain margin. (stability_margins' polynomial method is inaccurate on
    the path loop's double integrator at z = 1.)"""
    w = np.logspace(-2, math.log10(0.999 * math.pi / L.dt), 20000)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")               # the integrators' z = 1 is not on the grid
        resp = ct.frequency_response(L, w)
    mag, phase = np.asarray(resp.magnitude).ravel(), np.asarray(resp.phase).ravel()
    finite = np.isfinite(mag) & np.isfinite(phase)
    w, mag, phase = w[finite], mag[finite], np.unwrap(phase[finite])
    phase -= 2 * math.pi * math.ceil(phase[0] / (2 * math.pi))   # start in (-360, 0] deg
    down = np.flatnonzero((mag[:-1] >= 1.0) & (mag[1:] < 1.0))
    if len(down):
        i = down[0]
        f = (mag[i] - 1.0) / (mag[i] - mag[i + 1])
        wc = w[i] + f * (w[i + 1] - w[i])
        pm = math.degrees(phase[i] + f * (phase[i + 1] - phase[i])) + 180.0
        delay = math.radians(pm) / wc
    else:
        wc, pm, delay = math.nan, math.inf, math.inf
    above = w[:-1] > (wc if np.isfinite(wc) else 0.0)     # the upper gain margin (above the crossover)
    cross = np.flatnonzero(above & (phase[:-1] > -math.pi) & (phase[1:] <= -math.pi))
    gm = float(1.0 / mag[cross[0]]) if len(cross) else math.inf
    return Margins(gm, pm, wc, delay)


def mpc_controller(study: Study) -> ct.StateSpace:
    """The unconstrained yaw-rate MPC: inputs (delta_m, gamma, gamma_d), output u."""
    model = resolve(study)
    name = model.one(role="yaw_rate_controller", purpose="margins")
    p = model.parameters(name)
    Ts = study.components[name].step or study.study.base_step
    mpc = CondensedTrackingMPC(p["num"], p["den"], Ts, int(p["prediction_horizon"]), int(p["control_horizon"]),
                               float(p["Q"]), float(p["R"]), float(p["steer_limit"]), float(p["steer_rate_limit"]) * Ts)
    n = mpc.A.shape[0]
    K = -np.linalg.solve(mpc.H, mpc.G)[0]
    Kx, Ku, Ke = K[:n], K[n], K[n + 1]
    A, B = mpc.A, mpc.B.reshape(-1, 1)
    kb = float(Kx @ B.ravel())
    # state [x_{k-1}; u_{k-1}]
    Ac = np.block([[A, np.zeros((n, 1))], [(Kx @ A).reshape(1, -1), np.array([[1.0 + Ku]])]])
    Bc = np.block([[B, np.zeros((n, 2))], [np.array([[kb, Ke, -Ke]])]])
    Cc = np.concatenate([Kx @ A, [1.0 + Ku]]).reshape(1, -1)
    Dc = np.array([[kb, Ke, -Ke]])
    return ct.ss(Ac, Bc, Cc, Dc, Ts)


def actuator_and_plant(study: Study, speed: float, Ts: float, delay: float) -> ct.StateSpace:
    """u -> (delta, gamma): steering equivalent (with the delay in whole MPC steps, the remainder
    as a first-order Pade term) and the yaw model at ``speed``, held over Ts."""
    model = resolve(study)
    steer = FirstOrderSteering.of(model.parameters(model.one(role="steering", purpose="margins")))
    plant = model.parameters(model.one(role="yaw_plant", purpose="margins"))
    if plant["model"] == "transfer_function":
        Ay, By, Cy = controllable_canonical(plant["tf_num"], plant["tf_den"])
    else:
        Ay, By, Cy = state_space(plant["model"], TractorParameters.of(plant), speed)
    m, tau = Ay.shape[0], steer.time_constant
    Ap = np.block([[np.array([[-1.0 / tau]]), np.zeros((1, m))], [By.reshape(-1, 1), Ay]])
    Bp = np.concatenate([[1.0 / tau], np.zeros(m)]).reshape(-1, 1)
    Cp = np.block([[np.array([[1.0]]), np.zeros((1, m))], [np.zeros((1, 1)), Cy.reshape(1, -1)]])
    total = steer.delay + delay
    whole = int(math.floor(total / Ts + 1e-9))
    rest = total - whole * Ts
    P = ct.ss(Ap, Bp, Cp, np.zeros((2, 1)))
    if rest > 1e-9:
        P = P * ct.ss(ct.tf(*ct.pade(rest, 1)))
    Pd = ct.c2d(P, Ts, "zoh")
    if whole:
        Pd = Pd * ct.ss(ct.tf([1.0], [1.0] + [0.0] * whole, Ts))
    return Pd


def loops(study: Study, speed: float | None = None, extra_delay: float = 0.0):
    """(yaw-rate loop L_in, path loop L_out, closed yaw-rate loop T), negative-feedback convention."""
    C = mpc_controller(study)
    Ts = C.dt
    model = resolve(study)
    tracker = model.parameters(model.one(role="tracker", purpose="margins"))
    v = speed if speed is not None else float(model.parameters(model.one(role="reference", purpose="margins"))["speed"])
    P = actuator_and_plant(study, v, Ts, extra_delay)
    Cfb, Cr = C[:, :2], C[:, 2]
    L_in = -(Cfb * P)
    closed = ct.feedback(P, Cfb, sign=1)                # u = v_ext + Cfb y
    T = closed[1, :] * Cr                               # gamma_d -> gamma
    a = tracker.get("lookahead") or tracker["l_r"]
    k = tracker["k_s"] * tracker["k_c"]
    s = ct.tf("s")
    path = (v / a) / s + (k / a) * (v / s ** 2 + tracker["l_r"] / s)   # gamma -> -gamma_d
    L_out = ct.ss2tf(T) * ct.c2d(path, Ts, "tustin")     # as polynomials: exact at z near 1
    return L_in, L_out, T


def predicted(study: Study, speed: float | None = None) -> dict:
    L_in, L_out, _ = loops(study, speed)
    return {"yaw_rate_loop": _margins(L_in), "path_loop": _margins(L_out)}


def within_bounds(study: Study, delay: float) -> bool:
    m = run_study(study.with_values({"steering.command_delay": delay}), None, plots=False).metrics
    return m["euclid_max_straight"] < PAPER_BOUNDS["euclid_max_straight"] and \
        m["euclid_max_curved"] < PAPER_BOUNDS["euclid_max_curved"]


def simulated_delay_limit(study: Study, high: float = 1.0, tolerance: float = 0.01) -> float:
    """Smallest steering.command_delay at which the simulated figure-8 leaves the bounds
    (bisection; assumes within at the study's own delay); inf when still within at ``high``."""
    model = resolve(study)
    steering = model.one(role="steering", purpose="margins")
    low = float(model.parameters(steering)["command_delay"])
    if within_bounds(study, high):
        return math.inf
    while high - low > tolerance:
        mid = 0.5 * (low + high)
        low, high = (mid, high) if within_bounds(study, mid) else (low, mid)
    return high


def report(study: Study, simulate: bool = True) -> str:
    result = predicted(study)
    model = resolve(study)
    steering = model.one(role="steering", purpose="margins")
    own = float(model.parameters(steering)["command_delay"])
    lines = [f"{'loop':<16}{'gain margin':>13}{'phase margin':>14}{'crossover':>14}{'delay margin':>14}",
             "-" * 71]
    for name, m in result.items():
        gm = f"{m.gain:.2f} ({20 * math.log10(m.gain):.1f} dB)" if np.isfinite(m.gain) else "inf"
        pm = f"{m.phase_deg:.1f} deg" if np.isfinite(m.phase_deg) else "inf"
        wc = f"{m.crossover:.2f} rad/s" if np.isfinite(m.crossover) else "none"
        dm = f"{m.delay:.3f} s" if np.isfinite(m.delay) else "inf"
        lines.append(f"{name:<16}{gm:>13}{pm:>14}{wc:>14}{dm:>14}")
    limit = own + min(m.delay for m in result.values())
    lines.append(f"\npredicted: the loop loses stability at an actuator delay of {limit:.3f} s "
                 f"(the study's {own:.3f} s + the smallest delay margin); on a straight and on a curve alike")
    if simulate:
        sim = simulated_delay_limit(study)
        lines.append(f"simulated: the figure-8 leaves the paper's bounds at steering.command_delay = "
                     + (f"{sim:.3f} s (bisection to 0.01 s)" if np.isfinite(sim) else "more than 1 s"))
    return "\n".join(lines)
