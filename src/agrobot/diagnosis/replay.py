"""Replaying a log through the baseline model, one subsystem at a time.

- steering: delta_cmd -> delta (the closed-loop first-order equivalent, components.models.steering_equivalent);
- yaw: measured delta and speed -> yaw rate (the study's LPV yaw model);
- position: measured yaw rate and speed -> antenna track, dead-reckoned and aligned to the GPS
  track window by window (a rigid 2-D fit per window removes the unknown start pose); its residual
  is weighed by the noise the dead reckoning integrates (TrackWhitening).

Every function takes the parameter values (SI units) as a mapping and returns arrays on the log's
sample times. The linear systems (the yaw model, the gyro's filter) hold their inputs linear
between the samples (an exact first-order hold: ``first_order_hold``), so a vehicle whose yaw follows
the wheels within a row's step replays without the half-row lag a held mean of the two samples
would give; the speed that schedules a step's system is that mean (the step's system held).

No effect is named here: the values reach the model as the quantities the catalogue's effects carry
(diagnosis.effect.QUANTITIES, catalogue.CATALOGUE.quantities: the steering's and the yaw model's
parameters, the gyro's and the wheel speed's, the position's point and lag), and the wheel angle
driving the yaw stage, and the rear axle's side-slip the track reads, passes through the effects'
transforms of the steering (Effect.wheel_angle).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Mapping

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.signal import lfilter

from agrobot.components.models import steering_equivalent
from agrobot.diagnosis import replay_kernels
from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.components.tractor_yaw_plant import steer_input
from agrobot.identification.driving import ACKERMANN, SMALL_ANGLE, DrivingLog, Segments, YawModel, phi_steps
from agrobot.measurements.log import chords
from agrobot.components.models.yaw_dynamics import (TractorParameters, body_to_world, cornering_scale, lateral_disturbance_column,
                                            state_space)


def steering_replay(cmd: np.ndarray, h: float, v: Mapping[str, float], delta0: float,
                    kernel: str = "auto") -> np.ndarray:
    """The steering's first-order equivalent (components.models.steering_equivalent) with the
    replay's values (its quantities, ``steering_plant``); ``kernel``: replay_kernels.KERNELS (the C
    loop, or the Python reference)."""
    q = steering_plant(v)
    if replay_kernels.choose(kernel) == "c":
        pieces = steering_equivalent.step_pieces(cmd, h, q["time_constant"], q["rate_limit"], q["delay"])
        return replay_kernels.steering_first_order(pieces, q["deadband"], delta0)
    return steering_equivalent.simulate(cmd, h, q["time_constant"], q["deadband"], q["rate_limit"], q["delay"], delta0)


def steering_plant(v: Mapping[str, float]) -> dict[str, float]:
    """The steering's first-order equivalent under ``v``: time_constant, deadband, rate_limit, delay."""
    return CATALOGUE.quantities(v, "steering")


def yaw_plant(v: Mapping[str, float]) -> dict[str, float]:
    """The yaw model's quantities under ``v`` (effect.QUANTITIES ``yaw.*``)."""
    return CATALOGUE.quantities(v, "yaw")


def nonlinear(q: Mapping[str, float]) -> tuple[float, float, float, float, float]:
    """The yaw model's quantities that enter it nonlinearly, as YawReplay.responses takes them."""
    return q["front_scale"], q["rear_scale"], q["speed_slope"], q["reference_speed"], q["relaxation_scale"]


def saturates(v: Mapping[str, float]) -> bool:
    """Whether the tyres under ``v`` saturate (a finite friction: the Magic Formula replay)."""
    return math.isfinite(yaw_plant(v)["friction"])


def wheel_angle_input(measured: np.ndarray, replayed: np.ndarray | None, t: np.ndarray,
                      v: Mapping[str, float]) -> np.ndarray | None:
    """The wheel angle driving the yaw stage under ``v``: the ``replayed`` angle (from the command),
    or the ``measured`` one, through the transforms of the effects present (Effect.wheel_angle, in
    their order); None: the measured angle as it is."""
    delta = replayed
    for effect in CATALOGUE.transforms(v):
        x = effect.wheel_angle(measured if delta is None else delta, v, t)
        if x is not None:
            delta = x
    return delta


def measured_yaw_rate(rate: np.ndarray, v: Mapping[str, float], h: float = 0.0) -> np.ndarray:
    """The yaw stage's reading of a replayed yaw rate (the gyro's bias in it): the gyro reads
    s r + b; a wheel speed k x the ground speed drives the LPV model k times too fast, which near
    the kinematic yaw rate v delta / L is a yaw rate k times too high: (s / k) (rate - b) + b;
    read through the gyro's first-order filter of time constant tau on samples ``h`` apart."""
    gyro = CATALOGUE.quantities(v, "gyro")
    scale = gyro["gain"] / CATALOGUE.quantities(v, "speed")["gain"]
    out = rate if scale == 1.0 else scale * (rate - gyro["bias"]) + gyro["bias"]
    return low_pass(out, h, gyro["time_constant"]) if gyro["time_constant"] > 0 and h > 0 else out


def low_pass(x: np.ndarray, h: float, tau: float) -> np.ndarray:
    """tau y' = x - y on samples h apart, x linear between them (first_order_hold, exact), from rest
    at x[0]: y[k] = a y[k-1] + g0 x[k-1] + g1 x[k], a = exp(-h / tau), g1 = 1 - (tau / h)(1 - a),
    g0 = (tau / h)(1 - a) - a."""
    a = math.exp(-h / tau)
    g1 = 1.0 - tau / h * -math.expm1(-h / tau)
    g0 = 1.0 - a - g1
    return lfilter([g1, g0], [1.0, -a], x, zi=[(1.0 - g1) * x[0]])[0]


def first_order_hold(A: np.ndarray, B: np.ndarray, h: float, kernel: str = "python"
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Phi, G0, G1) of x' = A x + B u, u linear over each step h: x_{k+1} = Phi x_k + G0 u_k + G1 u_{k+1},

        Phi = e^{Ah},  Gamma0 = int_0^h e^{As} ds B,  Gamma1 = int_0^h e^{As} (h - s) ds B,
        x(h) = Phi x0 + Gamma0 u0 + Gamma1 (u1 - u0) / h:  G1 = Gamma1 / h,  G0 = Gamma0 - G1

    (the top block row of exp([[A, B, 0], [0, 0, I/h], [0, 0, 0]] h) is [Phi, Gamma0, Gamma1 / h]).
    A stack (k, n, n), B (k, n, p), by identification.driving.phi_steps (Gamma0 = h phi1(hA) B,
    Gamma1 / h = h phi2(hA) B: scaling and squaring of the n x n block, Pade and Horner; ``kernel``
    "c": its C twin identification/phi_step.h through replay_kernels.first_order_hold)."""
    if kernel == "c":
        return replay_kernels.first_order_hold(A, B, h)
    P, g1, g2 = phi_steps(A, B, np.full(len(A), float(h)))
    return P, g1 - g2, g2


def exact(values) -> tuple[float, ...]:
    """A cache key of parameter values, exact: a hit returns what a fresh replay would compute (the
    replays are pure functions of the values, so a fit's result does not depend on what ran before it)."""
    return tuple(float(x) for x in values)


def midpoints(x: np.ndarray) -> np.ndarray:
    """Mean of consecutive samples; the last sample repeats."""
    return np.append(0.5 * (x[1:] + x[:-1]), x[-1])


class YawReplay:
    """Responses of the yaw model to the four inputs that enter it linearly:
    [measured delta, a unit steering offset, a_lat = cos(psi), a_lat = -sin(psi)], so that

        gamma = R0 + offset R1 + s_north R2 + s_east R3 + bias

    (a side slope with fall line psi_d and angle phi: s_east, s_north = g sin(phi) (cos, sin)(psi_d)).
    Simulations are cached on the parameters that enter nonlinearly (exact). ``kernel``
    (replay_kernels.KERNELS): the recursion and the hold's exponentials in C, or the Python reference
    (blocked_recursion, first_order_hold). ``geometry``: the plant's steering_geometry; under "tan" a wheel
    angle drives the model as tan(delta) (tractor_yaw_plant.steer_input) and the offset's input is
    its first-order share, d tan(delta) / d delta = 1 + tan(delta)^2."""

    def __init__(self, model: str, params: TractorParameters, h: float, delta: np.ndarray, v: np.ndarray,
                 heading: np.ndarray, speed_grid: float = 0.02, min_speed: float = 0.3, kernel: str = "auto",
                 geometry: str = "w"):
        self.model, self.params, self.h, self.geometry = model, params, h, geometry
        self.kernel = replay_kernels.choose(kernel)
        psi = np.asarray(heading, float)
        offset = np.ones(len(delta)) if geometry == "w" else 1.0 + steer_input(delta, geometry) ** 2
        self.inputs = np.column_stack([self.steer(delta), offset, np.cos(psi), -np.sin(psi)])
        self.bins = np.round(np.maximum(midpoints(v), min_speed) / speed_grid).astype(int)
        self.grid = speed_grid
        self.speeds = np.unique(self.bins) * speed_grid
        self.index = np.searchsorted(np.unique(self.bins), self.bins)
        self._parts: list[np.ndarray] | None = None
        self._cache: dict[tuple, np.ndarray] = {}
        self._scales: dict[tuple[float, float], np.ndarray] = {}

    def steer(self, delta: np.ndarray) -> np.ndarray:
        """The input a wheel angle gives the recursion, on the samples: steer_input(delta)."""
        return steer_input(np.asarray(delta, float), self.geometry)

    def responses(self, front_scale: float, rear_scale: float, speed_slope: float, v_ref: float,
                  relaxation_scale: float = 1.0, steering: np.ndarray | None = None) -> np.ndarray:
        """The four responses (N, 4); with ``steering`` (a wheel angle, N) its yaw-rate response
        too, as a fifth column of the same recursion (each column's arithmetic is its own)."""
        key = exact((front_scale, rear_scale, speed_slope, v_ref, relaxation_scale))
        hit = self._cache.get(key)
        if hit is not None and steering is None:
            return hit
        return self._recurse([(front_scale, rear_scale, speed_slope, v_ref, relaxation_scale)], [steering])[0]

    def _recurse(self, yaws: list[tuple], steerings: list[np.ndarray | None]) -> list[np.ndarray]:
        """``responses`` of several sets of the nonlinear values (front, rear, slope, v_ref,
        relaxation), each with its wheel angle or None, in one blocked recursion (the sets side by
        side; a set's arithmetic is that of its own recursion); cached like ``responses``."""
        wide = any(s is not None for s in steerings)
        columns = [0, 0, 1, 1] + ([0] if wide else [])
        systems, inputs = [], []
        for yaw, steering in zip(yaws, steerings):
            systems.append(self._discrete(*yaw))
            u = self.inputs
            if wide:
                extra = np.zeros(len(u)) if steering is None else self.steer(steering)
                u = np.column_stack([u, extra])
            inputs.append(u)
        both = self._recursion(systems, columns, inputs, (1, 0))
        if len(self._cache) + 2 * len(yaws) > 64:
            self._cache.clear()
        for yaw, steering, z in zip(yaws, steerings, both):
            key = exact(yaw)
            self._cache[key] = z[:, 0, :4]
            self._cache[key + ("v_y",)] = z[:, 1, :4]
            if steering is not None:        # the wheel angle's yaw-rate and lateral-velocity responses
                self._cache[("input", id(steering)) + key] = (steering, z[:, 0, 4], z[:, 1, 4])
        return [z[:, 0, :] for z in both]

    def prepare(self, sets: list[Mapping[str, float]], inputs: list[np.ndarray | None]) -> None:
        """Compute, in one batched recursion, what ``yaw_rate`` of each set (with its wheel angle
        or None) would simulate one set at a time, into the caches it reads."""
        if len(self._cache) + 3 * len(sets) > 64:      # room for them all: nothing they need is dropped
            self._cache.clear()
        todo: dict[tuple, tuple] = {}
        for v, delta in zip(sets, inputs):
            yaw = nonlinear(yaw_plant(v))
            key = exact(yaw)
            memo = None if delta is None else self._cache.get(("input", id(delta)) + key)
            if (key in self._cache or key in todo) and (delta is None or (memo is not None and memo[0] is delta)):
                continue
            todo[key if delta is None else key + ("input", id(delta))] = (yaw, delta, key)
        if len(todo) < 2:
            return
        jobs = list(todo.values())
        self._recurse([y for y, _, _ in jobs], [d for _, d, _ in jobs])

    def _recursion(self, systems: list[tuple[np.ndarray, np.ndarray, np.ndarray]], columns: list[int],
                   inputs: list[np.ndarray], rows) -> np.ndarray:
        """Rows ``rows`` of Z_{k-1}, Z_k = Phi(v_k) Z_{k-1} + G0(v_k)[:, columns] * u_k + G1(v_k)[:, columns] * u_{k+1}
        (u_N = u_{N-1}), for each system (Phi, G0, G1 at the log's speeds) and its inputs u (N, m):
        (R, N, len(rows), m)."""
        if self.kernel == "c":
            A, G0, G1 = (np.stack(x) for x in zip(*systems))
            return replay_kernels.indexed_recursion(A, G0, self.index, columns, np.stack(inputs), rows, G1)
        A = [Ad[self.index] for Ad, _, _ in systems]
        b = [G0[:, :, columns][self.index] * u[:, None, :] + G1[:, :, columns][self.index] * np.vstack([u[1:], u[-1:]])[:, None, :]
             for (_, G0, G1), u in zip(systems, inputs)]       # the columns taken at each speed, then the samples
        if len(systems) == 1:
            return blocked_recursion(A[0], b[0], row=tuple(rows))[None]
        return blocked_recursion(np.stack(A), np.stack(b), row=tuple(rows))

    def _discrete(self, front_scale: float, rear_scale: float, speed_slope: float, v_ref: float,
                  relaxation_scale: float = 1.0):
        """First-order hold (Phi, G0, G1; each G [delta, lateral]) at each speed of the log, batched. A and B are affine in
        the cornering stiffnesses and in 1/sigma (the relaxation lengths) at a given speed (every
        physical model), so they are assembled from parts computed once:
        A = A_0(v) + (1/s - 1) A_sigma(v) + c(v) (s_f C_f A_f(v) + s_r C_r A_r(v)), s the scale
        on both relaxation lengths, A_sigma the part of A_0 proportional to 1/sigma; likewise B, whose
        delta column holds C_f in the bicycle model (B_f)."""
        if self._parts is None:
            zero = replace(self.params, C_f=0.0, C_r=0.0)
            longer = replace(zero, sigma_f=2 * zero.sigma_f, sigma_r=2 * zero.sigma_r)
            parts = []
            for speed in self.speeds:
                A0, B, _ = state_space(self.model, zero, speed)
                A2, B2, _ = state_space(self.model, longer, speed)
                front = state_space(self.model, replace(zero, C_f=self.params.C_f), speed)
                Af, Bf = front[0] - A0, front[1] - B        # the bicycle model's B holds C_f too
                Ar = state_space(self.model, replace(zero, C_r=self.params.C_r), speed)[0] - A0
                E = lateral_disturbance_column(len(B))
                parts.append((A0, 2 * (A0 - A2), Af, Ar, np.column_stack([B, E]),
                              np.column_stack([2 * (B - B2), np.zeros_like(E)]), np.column_stack([Bf, np.zeros_like(E)])))
            self._parts = [np.array(x) for x in zip(*parts)]
        A0, As, Af, Ar, B, Bs, Bf = self._parts
        c = self._scales.get((speed_slope, v_ref))
        if c is None:
            c = self._scales[(speed_slope, v_ref)] = np.array([cornering_scale(v, speed_slope, v_ref)
                                                               for v in self.speeds])[:, None, None]
            if len(self._scales) > 64:
                self._scales = {(speed_slope, v_ref): c}
        k = 1.0 / relaxation_scale - 1.0
        A, B = A0 + k * As + c * (front_scale * Af + rear_scale * Ar), B + k * Bs + c * front_scale * Bf
        return first_order_hold(A, B, self.h, self.kernel)

    def response_to(self, u: np.ndarray, v: Mapping[str, float], through_geometry: bool = True) -> np.ndarray:
        """Yaw-rate responses (N, m) of the model under ``v`` to the steering-angle inputs u (N, m);
        ``through_geometry`` False: u is the dynamics' input itself (a static map's basis)."""
        system = self._discrete(*nonlinear(yaw_plant(v)))
        u = np.column_stack([self.steer(col) if through_geometry else col for col in np.asarray(u, float).T])
        return self._recursion([system], [0] * u.shape[1], [u], (1,))[0, :, 0, :]

    def yaw_rate(self, v: Mapping[str, float], delta: np.ndarray | None = None) -> np.ndarray:
        """The yaw rate under ``v``, driven by the measured wheel angle, or by ``delta`` (a wheel
        angle replayed from the command, when the log has none measured)."""
        q = yaw_plant(v)
        yaw = nonlinear(q)
        first = self.responses(*yaw)[:, 0] if delta is None else self.driven(delta, yaw)[0]
        R = self.responses(*yaw)
        return first + q["steer_offset"] * R[:, 1] + q["slope_north"] * R[:, 2] + \
            q["slope_east"] * R[:, 3] + CATALOGUE.quantities(v, "gyro")["bias"]

    def driven(self, delta: np.ndarray, yaw: tuple) -> tuple[np.ndarray, np.ndarray]:
        """(yaw rate, lateral velocity v_y): the responses to the wheel angle ``delta`` of the model
        with the nonlinear values ``yaw``, memoised on the input array and the values."""
        key = exact(yaw)
        hit = self._cache.get(("input", id(delta)) + key)
        if hit is None or hit[0] is not delta:
            if key in self._cache:              # the four responses known: the input's alone
                u = self.steer(delta)[:, None]
                z = self._recursion([self._discrete(*yaw)], [0], [u], (1, 0))[0]
                hit = (delta, z[:, 0, 0], z[:, 1, 0])
                if len(self._cache) > 64:
                    self._cache.clear()
                self._cache[("input", id(delta)) + key] = hit
            else:                               # all five in one recursion
                self.responses(*yaw, steering=delta)
                hit = self._cache[("input", id(delta)) + key]
        return hit[1], hit[2]

    def with_slope(self, rate: np.ndarray, v: Mapping[str, float]) -> np.ndarray:
        """``rate`` plus this linear model's response to the side slope's lateral pull under ``v``
        (a saturating replay's share of a slope)."""
        q = yaw_plant(v)
        if not (q["slope_north"] or q["slope_east"]):
            return rate
        R = self.responses(*nonlinear(q))
        return rate + q["slope_north"] * R[:, 2] + q["slope_east"] * R[:, 3]

    def rear_lateral_velocity(self, v: Mapping[str, float], delta: np.ndarray | None = None) -> np.ndarray:
        """Lateral velocity of the rear-axle point R in the body frame, v_y - l_r gamma, from the
        model's states (the side-slip a dead reckoning along the heading leaves out: nothing for
        a tractor at 2 m/s, metres over 10 s for a car at 30 m/s), driven like ``yaw_rate`` by the
        measured wheel angle or by ``delta`` (the wheels' angle through a steering map: a gain of
        0.8 turns the wheels, and so slips the rear axle, 0.8 x as much as the reading)."""
        q = yaw_plant(v)
        key = exact(nonlinear(q))
        self.responses(*key)
        V = self._cache[key + ("v_y",)]
        first = V[:, 0] if delta is None else self.driven(delta, key)[1]
        vy = first + q["steer_offset"] * V[:, 1] + q["slope_north"] * V[:, 2] + q["slope_east"] * V[:, 3]
        return vy - self.params.l_r * (self.yaw_rate(v, delta) - CATALOGUE.quantities(v, "gyro")["bias"])


def blocked_recursion(A: np.ndarray, b: np.ndarray, row, block: int = 0) -> np.ndarray:
    """Row ``row`` of Z_{k-1} for the time-varying recursion Z_k = A_k Z_{k-1} + b_k, Z_{-1} = 0
    (A: (N, n, n), b: (N, n, m)); the output at sample k is the state before its update, (N, m),
    or (N, len(row), m) for a tuple of rows. R recursions at once: A (R, N, n, n), b (R, N, n, m),
    output with a leading R axis.

    Blocked: the N steps are cut into ~sqrt(N) blocks run side by side from a zero state, with
    Phi = A_last ... A_first of each block; the block ends are chained, Z_end(j) = Zl_end(j) +
    Phi(j) Z_end(j-1), and the blocks run again side by side from their true start states. About
    3 sqrt(N) Python steps instead of N; the blocks (of every recursion) sit on the last axis
    (contiguous), so each step is a few elementwise products over all blocks."""
    many = b.ndim == 4
    A, b = (A, b) if many else (A[None], b[None])
    R, N, n, m = b.shape
    L = block or max(1, int(math.ceil(0.5 * math.sqrt(N))))
    J = -(-N // L)
    pad = J * L - N
    if pad:
        A = np.concatenate([A, np.broadcast_to(np.eye(n), (R, pad, n, n))], axis=1)
        b = np.concatenate([b, np.zeros((R, pad, n, m))], axis=1)
    # (L, n, n, R J) and (L, n, m, R J): step k of every block side by side
    At = np.ascontiguousarray(A.reshape(R, J, L, n, n).transpose(2, 3, 4, 0, 1)).reshape(L, n, n, R * J)[:, :, :, None, :]
    bt = np.ascontiguousarray(b.reshape(R, J, L, n, m).transpose(2, 3, 4, 0, 1)).reshape(L, n, m, R * J)
    z = np.zeros((n, m, R * J))
    phi = np.broadcast_to(np.eye(n)[:, :, None], (n, n, R * J))
    for k in range(L):
        z = (At[k] * z[None]).sum(axis=1) + bt[k]
        phi = (At[k] * phi[None]).sum(axis=1)
    start = np.zeros((R, J, n, m))                    # true state before each block
    end_z = z.reshape(n, m, R, J).transpose(2, 3, 0, 1)
    end_phi = phi.reshape(n, n, R, J).transpose(2, 3, 0, 1)
    for r in range(R):
        for j in range(1, J):
            start[r, j] = end_z[r, j - 1] + end_phi[r, j - 1] @ start[r, j - 1]
    rows = [row] if isinstance(row, int) else list(row)
    Z = np.empty((L, len(rows), m, R * J))            # state before step k of each block
    z = start.transpose(2, 3, 0, 1).reshape(n, m, R * J)
    for k in range(L):
        Z[k] = z[rows]
        z = (At[k] * z[None]).sum(axis=1) + bt[k]
    Z = Z.reshape(L, len(rows), m, R, J).transpose(3, 4, 0, 1, 2).reshape(R, J * L, len(rows), m)[:, :N]
    Z = Z[..., 0, :] if isinstance(row, int) else Z
    return Z if many else Z[0]


def integrate(x: np.ndarray, h: float) -> np.ndarray:
    """Cumulative trapezoid from 0 (scipy), on the log's even step ``h``."""
    return cumulative_trapezoid(x, dx=h, initial=0.0)


def antenna_track(t: np.ndarray, yaw_rate: np.ndarray, speed: np.ndarray, v: Mapping[str, float],
                  lateral: np.ndarray | None = None) -> np.ndarray:
    """Dead-reckoned position reading (N, 2) in an arbitrary frame, under the quantities of ``v``: the
    gyro reads s gamma + b and the wheel speed k v, so psi = int((gamma_measured - b) / s),
    dR/dt = (v_measured / k) (cos psi, sin psi) + u (-sin psi, cos psi) with u the rear axle's lateral
    velocity (the yaw model's side-slip, where known), the point read = R + Rot(psi) (forward, left),
    ``lag`` late (negative: a clock ahead)."""
    h = float(t[1] - t[0])
    gyro, point = CATALOGUE.quantities(v, "gyro"), CATALOGUE.quantities(v, "position")
    speed = speed / CATALOGUE.quantities(v, "speed")["gain"]
    psi = integrate((yaw_rate - gyro["bias"]) / gyro["gain"], h)
    psi_mid = 0.5 * (psi[1:] + psi[:-1])
    v_mid = 0.5 * (speed[1:] + speed[:-1])
    u_mid = 0.5 * (lateral[1:] + lateral[:-1]) if lateral is not None else 0.0
    c, s = np.cos(psi_mid), np.sin(psi_mid)
    x = np.concatenate([[0.0], np.cumsum(h * (v_mid * c - u_mid * s))])
    y = np.concatenate([[0.0], np.cumsum(h * (v_mid * s + u_mid * c))])
    dx, dy = body_to_world(point["forward"], point["left"], np.cos(psi), np.sin(psi))
    ax, ay = x + dx, y + dy
    lat = point["lag"]
    if lat:
        ax, ay = np.interp(t - lat, t, ax), np.interp(t - lat, t, ay)
    return np.column_stack([ax, ay])


def aligned_residuals(predicted: np.ndarray, measured: np.ndarray, windows: np.ndarray) -> np.ndarray:
    """Per window (rows of sample indices, shape (W, L)): the rigid motion (rotation + translation)
    that best maps the predicted track onto the measured one, in closed form; returns the
    residuals measured - aligned, shape (W, L, 2)."""
    P, M = predicted[windows], measured[windows]
    P = P - P.mean(axis=1, keepdims=True)
    M = M - M.mean(axis=1, keepdims=True)
    cross = np.sum(P[..., 0] * M[..., 1] - P[..., 1] * M[..., 0], axis=1)
    dot = np.sum(P[..., 0] * M[..., 0] + P[..., 1] * M[..., 1], axis=1)
    th = np.arctan2(cross, dot)[:, None]
    c, s = np.cos(th), np.sin(th)
    return np.stack([M[..., 0] - (c * P[..., 0] - s * P[..., 1]), M[..., 1] - (s * P[..., 0] + c * P[..., 1])], axis=-1)


def track_residual_vector(res: np.ndarray) -> np.ndarray:
    """Aligned track residuals (W, L, 2) as one vector ordered by time within each window's east,
    then north, series ((W, 2, L) raveled): the order a lag-1 autocorrelation reads
    (estimation.effective_size), which on east, north interleaved would pair the two axes."""
    return np.asarray(res, float).transpose(0, 2, 1).ravel()


class TrackWhitening:
    """The generalised-least-squares transform T of one window's aligned track residual r (2L,),
    laid out (east over time, north over time), given the window's track ``points`` (L, 2).

    The dead-reckoned track integrates the gyro's and the wheel speed's white noise (per row
    sigma_gyro, sigma_speed): a heading error h n_i at row i turns the rest of the track about p_i,
    a speed error h nu_i moves it along the heading psi_i, so at row k > i

        dp_k = sum_{i<k} h n_i J (p_k - p_i) + h nu_i (cos psi_i, sin psi_i),   J a quarter turn,

    and the residual's covariance is C = sigma_gps^2 I + U U', U = h [sigma_gyro G_g, sigma_speed
    G_v]: a random walk of the heading, integrated (its share grows as v^2 T^3; at a car's 30 m/s, a
    0.002 rad/s gyro at 20 Hz drifts the track by a GPS noise's worth within a 10 s window). Least
    squares on the raw residual takes that drift for a rear-axle side-slip or an antenna lever arm;
    on T r = sigma_gps Pi_W C^(-1/2) r, Pi_W the projection off the whitened rigid motion of the
    window's alignment (W = C^(-1/2) A, A: two translations and the rotation about the centroid), it
    weighs each frequency by its noise. With U = Y S Z' (thin SVD),

        sigma_gps C^(-1/2) = I + Y (sigma_gps / sqrt(sigma_gps^2 + S^2) - 1) Y',

    so T costs O(L r); the noise is taken in ``blocks`` sums per window (the drift lives at low
    frequencies: within a block the columns of G hardly differ), r <= 2 blocks. Where the GPS's is
    the only noise T = I - Pi_A leaves an aligned residual as it is: in metres, at the GPS's level
    where the model is right.

    Why the gyro and not the model's own yaw rate: the track's heading is the integral of a yaw
    rate; the gyro's errors are white and of a level read from the log, the yaw model's are its
    misfit (slow, unknown, the yaw stage's to judge), and a track from the model would no longer
    see the gyro's own scale and bias."""

    def __init__(self, points: np.ndarray, h: float, sigma_gps: float, sigma_gyro: float, sigma_speed: float,
                 blocks: int = 64) -> None:
        P = np.asarray(points, float)
        L = len(P)
        step = np.diff(P, axis=0, append=P[-1:] + (P[-1:] - P[-2:-1]))
        along = step / np.maximum(np.hypot(step[:, :1], step[:, 1:]), 1e-12)       # (cos psi_i, sin psi_i)
        a = np.arange(0, L, -(-L // blocks))
        b = np.append(a[1:], L)
        m = np.clip(np.arange(L)[:, None], a, b)                # row k: block j's rows i < k are a_j .. m_kj - 1

        def summed(x):                                          # sum_{i in block j, i < k} x_i: (L, blocks, 2)
            c = np.vstack([np.zeros((1, 2)), np.cumsum(x, axis=0)])
            return c[m] - c[a][None]

        # a block's noises as one noise of their summed level (its columns hardly differ): / sqrt(size)
        turn = ((m - a)[..., None] * P[:, None, :] - summed(P)) / np.sqrt(b - a)[None, :, None]     # sum p_k - p_i
        slide = summed(along) / np.sqrt(b - a)[None, :, None]
        U = h * np.hstack([sigma_gyro * np.vstack([-turn[..., 1], turn[..., 0]]),
                           sigma_speed * np.vstack([slide[..., 0], slide[..., 1]])])
        self.Y, S, _ = np.linalg.svd(U, full_matrices=False)
        s = max(float(sigma_gps), 1e-9)
        self.gain = s / np.sqrt(s * s + S * S) - 1.0
        c = P - P.mean(axis=0)
        A = np.zeros((2 * L, 3))
        A[:L, 0], A[L:, 1], A[:L, 2], A[L:, 2] = 1.0, 1.0, -c[:, 1], c[:, 0]
        self.Q = np.linalg.qr(self._whiten(A.T).T)[0]

    def _whiten(self, r: np.ndarray) -> np.ndarray:
        """sigma_gps C^(-1/2) r along the last axis."""
        return r + ((r @ self.Y) * self.gain) @ self.Y.T

    def __call__(self, r: np.ndarray) -> np.ndarray:
        """T r along the last axis (2L)."""
        z = self._whiten(np.asarray(r, float))
        return z - (z @ self.Q) @ self.Q.T


def heading_estimate(t: np.ndarray, gps: np.ndarray, yaw_rate: np.ndarray, speed: np.ndarray,
                     span: float = 10.0, min_speed: float = 0.3) -> np.ndarray:
    """Absolute heading: the integrated gyro, its offset taken from the GPS course over 1 s chords
    (circular mean over ``span`` seconds of moving samples). Good to a degree or two: enough to
    resolve the direction of a side slope."""
    h = float(t[1] - t[0])
    psi = integrate(yaw_rate, h)
    k, d = chords(gps, h)
    moving = (np.hypot(d[:, 0], d[:, 1]) > min_speed * 2 * k * h) & (speed[k:-k] > min_speed)
    z = np.zeros(len(t), dtype=complex)
    z[k:-k] = np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - psi[k:-k])) * moving
    w = max(1, int(round(span / h)))
    zs = np.convolve(z, np.ones(w), "same")
    good = np.abs(zs) > 1e-9
    if not np.any(good):
        return psi
    offset = np.interp(np.arange(len(t)), np.flatnonzero(good), np.unwrap(np.angle(zs[good])))
    return psi + offset


class SaturatedYawReplay:
    """The yaw model with Magic Formula tyres (components.models.tyre) on every sample of the log.

    A nonlinear model has no response to superpose: it is simulated, in pieces of ``piece`` s run
    side by side (identification.driving.YawModel), each from a kinematic state ``burn_in`` s
    before it, so a simulation costs one pass over a piece (the slip dynamics forget their start
    within a few time constants, tenths of a second). A side slope enters through the linear
    model's response to it (its share of the lateral force is small beside the turn's)."""

    def __init__(self, model: str, params: TractorParameters, t: np.ndarray, h: float, delta: np.ndarray,
                 v: np.ndarray, min_speed: float, piece: float = 2.0, burn_in: float = 1.0,
                 geometry: str = "w") -> None:
        n = len(t)
        P, B = max(2, int(round(piece / h))), int(round(burn_in / h))
        rows = [(max(0, a - B), a, min(n, a + P)) for a in range(0, n, P)]
        L = max(b - s for s, _, b in rows)
        idx = np.empty((len(rows), L), int)
        for i, (s, a, b) in enumerate(rows):
            idx[i, : b - s] = np.arange(s, b)
            idx[i, b - s:] = b - 1
        self.rows = rows
        self.log = DrivingLog(np.asarray(t, float), np.asarray(delta, float), np.asarray(v, float), np.zeros(n),
                              np.zeros(n, int), h, "delta")
        segs = Segments(idx, np.ones_like(idx, bool), np.zeros(len(rows), bool))
        self.model = YawModel(model, params, self.log, segs, max_substep=0.04, min_sim_speed=min_speed,
                              geometry=ACKERMANN if geometry == "tan" else SMALL_ANGLE)
        self.loads = self.model.loads
        self.params = params

    def yaw_rate(self, v: Mapping[str, float], delta: np.ndarray | None = None) -> np.ndarray:
        """The gyro's yaw rate under the replay's values ``v`` (without the slope's share)."""
        return self.yaw_rates([v], [self.log.u if delta is None else delta])[0]

    def yaw_rates(self, sets: list[Mapping[str, float]], inputs: list[np.ndarray]) -> list[np.ndarray]:
        """``yaw_rate`` under each set, driven by its wheel angle: the sets of one wheel angle in one
        batched simulation (YawModel.simulate_many), each row with its own relaxation lengths."""
        p = self.params
        Fzf, Fzr = self.loads
        S = len(self.rows)
        out: list[np.ndarray | None] = [None] * len(sets)
        groups: dict[bytes, list[int]] = {}
        for i, d in enumerate(inputs):
            groups.setdefault(np.asarray(d, float).tobytes(), []).append(i)
        for members in groups.values():
            self.log.u = np.asarray(inputs[members[0]], float)
            plants = [yaw_plant(sets[i]) for i in members]
            scales = [float(q["relaxation_scale"]) for q in plants]
            if len(set(scales)) == 1:
                sigma_f, sigma_r = p.sigma_f * scales[0], p.sigma_r * scales[0]
            else:                           # per row (rates() broadcasts them with the states)
                sigma_f = np.repeat([p.sigma_f * k for k in scales], S)
                sigma_r = np.repeat([p.sigma_r * k for k in scales], S)
            self.model.p = replace(p, sigma_f=sigma_f, sigma_r=sigma_r)
            values = [{"c_f": q["front_scale"] * p.C_f / Fzf, "c_r": q["rear_scale"] * p.C_r / Fzr,
                       "steer_offset": q["steer_offset"], "gyro_bias": CATALOGUE.quantities(sets[i], "gyro")["bias"],
                       "friction": q["friction"], "shape": q["shape"], "cornering_speed_slope": q["speed_slope"],
                       "cornering_reference_speed": q["reference_speed"]} for i, q in zip(members, plants)]
            sims = self.model.simulate_many(values)
            for i, sim in zip(members, sims):
                rate = np.empty(len(self.log.t))
                for j, (s, a, b) in enumerate(self.rows):
                    rate[a:b] = sim[j, a - s: b - s]
                out[i] = rate
        return out
