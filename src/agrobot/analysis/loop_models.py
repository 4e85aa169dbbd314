"""The guidance loop of a study as a linear network: its own components, linearised about a
straight line, wired by its own connections, run on the orchestrator's schedule.

Operating point: the tractor drives a straight line heading east (psi = 0) at speed v, on its
reference, wheels centred; on a side slope (the yaw plant's plane) wheels and tyres hold the line
against the pull, the IMU reads the slope's roll, pitch and specific force, and the INS has learnt the
crab (the plant's ``linear_ground``; the crab angle itself, 0.5 deg on 10 deg, is left out of psi).
First-order deviations split into a longitudinal channel (east positions,
speeds) and a lateral channel (north positions and velocities, heading, yaw rate, wheel angles); on a
straight the two do not couple, so the steering loop is the lateral channel alone and the speed loop
(speed PID, drivetrain, speed KF) only sets the operating point.

Each component on the loop becomes a discrete block at its own step, inputs and outputs named by port:

- trackers and routes declare theirs (``lateral_linearisation(speed, dt, along_track_error)``: a python-control
  StateSpace whose labels are port names);
- the other components build theirs in their class (a method ``linear_model(step, speed)`` returning a
  components.models.loop_blocks.Block: the yaw plant, steering, GPS, gyro, IMU, pose EKF, GNSS/INS EKF,
  yaw-rate MPC, notch, computation delay and watchdog), each from its own step equations and parameters
  without the nonlinearities a small signal beyond the dead bands does not see (dead bands, quantisation,
  saturations); a class may instead name a function, ``LINEAR_MODEL = "module:function"`` taking the
  component first;
- a composite subsystem is its inner network lifted over its step.

A block may change from step to step with a period of its own (``Block.phases``: the INS EKF takes
a fix on every n-th of its steps); the network's period then covers that cycle too.

Schedule (orchestrator.engine): at each base instant continuous blocks publish the state they
reached, sampled blocks step in the study's evaluation order (y = C x + D u, then x <- A x + B u),
then continuous blocks integrate with the inputs of the instant held (their A, B: the exact
zero-order-hold step). Over one period (the least common multiple of the steps) the network is
time-invariant: running the schedule once on matrices instead of numbers gives its period map

    X+ = Phi X + Gamma w,    z = H X + J w

with w injected at chosen inputs (a loop opened there) and z what their sources delivered: exact
for the linear blocks, the multirate sampling included.
"""
from __future__ import annotations

import functools
import inspect
import math
from dataclasses import dataclass, field, replace

import numpy as np

from agrobot.components.models.loop_blocks import LEVEL, Block, Ground, NoLinearModel, OperatingPoint
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.composite import CompositeComponent
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.registry import import_study_module
from agrobot.orchestrator.resolver import resolve


# --- the network -----------------------------------------------------------------------------------

@dataclass
class Network:
    """Blocks on the orchestrator's schedule. ``sources[(block, input)] = (block, output)``;
    ``order``: the sampled blocks' evaluation order; ``period`` in base steps."""

    blocks: dict[str, Block]
    order: list[str]
    sources: dict[tuple[str, str], tuple[str, str]]
    base_step: float
    period: int = field(init=False)

    def __post_init__(self) -> None:
        self.period = math.lcm(*(b.ratio * b.cycle for b in self.blocks.values())) if self.blocks else 1
        self._layout: dict[str, tuple[slice, slice]] = {}
        i = 0
        for name, b in self.blocks.items():
            self._layout[name] = (slice(i, i + b.n), slice(i + b.n, i + b.n + len(b.outputs)))
            i += b.n + len(b.outputs)
        self.n = i                                    # block states, then each block's published outputs

    @property
    def step(self) -> float:
        return self.period * self.base_step

    def run(self, injected: dict[tuple[str, str], int], n_w: int, zeroed=(), instants: int | None = None):
        """The schedule over ``instants`` base steps (default one period) on matrices over
        [X; w]: returns (X+, captured, S, Y) with ``captured[(block, input)]`` the value the source of
        an injected input delivered when it was first read, S and Y each block's state and
        published outputs at the end."""
        N = self.n + n_w
        E = np.eye(N)
        S = {b: E[self._layout[b][0]] for b in self.blocks}
        Y = {b: E[self._layout[b][1]] for b in self.blocks}
        captured: dict[tuple[str, str], np.ndarray] = {}
        zero = np.zeros(N)
        zeroed = set(zeroed)

        def read(name: str, port: str) -> np.ndarray:
            src = self.sources.get((name, port))
            if src is None or src[0] not in self.blocks or src[1] not in self.blocks[src[0]].outputs:
                return zero
            return Y[src[0]][self.blocks[src[0]].outputs.index(src[1])]

        def gather(name: str) -> np.ndarray:
            rows = []
            for port in self.blocks[name].inputs:
                key = (name, port)
                if key in injected:
                    captured.setdefault(key, read(name, port))
                    rows.append(E[self.n + injected[key]])
                elif key in zeroed:
                    rows.append(zero)
                else:
                    rows.append(read(name, port))
            return np.array(rows).reshape(len(rows), N)

        continuous = [b for b in self.blocks.values() if not b.sampled]
        sampled = [self.blocks[name] for name in self.order if name in self.blocks]
        for k in range(self.period if instants is None else instants):
            for b in continuous:
                if k % b.ratio == 0:
                    Y[b.name] = b.at(k // b.ratio)[2] @ S[b.name]
            for b in sampled:
                if k % b.ratio == 0:
                    U = gather(b.name)
                    A, B, C, D = b.at(k // b.ratio)
                    Y[b.name] = C @ S[b.name] + D @ U
                    S[b.name] = A @ S[b.name] + B @ U
            for b in continuous:
                if k % b.ratio == 0:
                    A, B, _, _ = b.at(k // b.ratio)
                    S[b.name] = A @ S[b.name] + B @ gather(b.name)
        X = np.vstack([np.vstack([S[b], Y[b]]) for b in self.blocks]).reshape(self.n, N)
        return X, captured, S, Y

    def opened_at(self, breaks: list[tuple[str, str]], zeroed=()) -> "OpenLoop":
        """The network opened at the inputs ``breaks``: w injected there, z what their sources
        deliver; ``zeroed`` inputs held at the operating point."""
        X, captured, _, _ = self.run({key: i for i, key in enumerate(breaks)}, len(breaks), zeroed)
        Z = np.array([captured.get(key, np.zeros(self.n + len(breaks))) for key in breaks])
        return OpenLoop(X[:, :self.n], X[:, self.n:], Z[:, :self.n], Z[:, self.n:], self.step)


@dataclass
class OpenLoop:
    """z = G(q) w over one period: X+ = Phi X + Gamma w, z = H X + J w; closing it sets w = z."""

    Phi: np.ndarray
    Gamma: np.ndarray
    H: np.ndarray
    J: np.ndarray
    dt: float

    def response(self, w: np.ndarray) -> np.ndarray:
        """G(e^{j w dt}) for a SISO opening, at the angular frequencies ``w`` [rad/s]."""
        z = np.exp(1j * np.asarray(w, float) * self.dt)
        n = self.Phi.shape[0]
        out = np.empty(len(z), complex)
        for i in range(0, len(z), 256):
            zz = z[i:i + 256]
            M = zz[:, None, None] * np.eye(n) - self.Phi
            x = np.linalg.solve(M, np.broadcast_to(self.Gamma[:, :1], (len(zz), n, 1)))
            out[i:i + 256] = (self.H[:1] @ x)[:, 0, 0] + self.J[0, 0]
        return out

    def closed_loop_poles(self) -> np.ndarray:
        """Eigenvalues of the period map with the loop closed (w = z)."""
        m = self.J.shape[0]
        Acl = self.Phi + self.Gamma @ np.linalg.solve(np.eye(m) - self.J, self.H)
        return np.linalg.eigvals(Acl)

    def spectral_radius(self) -> float:
        poles = self.closed_loop_poles()
        return float(np.max(np.abs(poles))) if len(poles) else 0.0


# --- from a study --------------------------------------------------------------------------------

def _type_name(comp) -> str:
    return getattr(comp, "type_name", None) or type(comp).__name__


def check_tracker(comp, lin, step: float, op: OperatingPoint, steps: int = 4, eps: float = 1e-6) -> None:
    """The tracker's declared linearisation against its own step function: a fresh copy at the
    operating point (east-bound reference, the CG ``along_track_error`` behind it) with each input
    port moved by +-eps for ``steps`` steps; the central differences of its outputs must follow the
    declared system (inputs it leaves out: no effect). A law changed without its linearisation is
    refused here rather than analysed wrongly."""
    trim = {"x_ref": 10.0 + op.along_track_error, "y_ref": 0.0, "xdot_ref": op.speed, "ydot_ref": 0.0, "x": 10.0,
            "y": 0.0, "heading": 0.0, "yaw_rate_ref": 0.0, "lateral_velocity": 0.0}
    ports = [p for p in comp.declared("input") if p in trim]
    outputs = list(lin.output_labels)

    def run(port: str, delta: float) -> np.ndarray:
        fresh = type(comp)(comp.name, comp.p)
        fresh.initialize(0.0, step)
        rows = []
        for k in range(steps):
            fresh.u.update(trim)
            fresh.u[port] += delta
            fresh.step(k * step, step)
            rows.append([fresh.y[o] for o in outputs])
        return np.array(rows)

    A, B, C, D = (np.atleast_2d(np.asarray(m, float)) for m in (lin.A, lin.B, lin.C, lin.D))
    for port in ports:
        measured = (run(port, eps) - run(port, -eps)) / (2 * eps)
        u = np.zeros(len(lin.input_labels))
        if port in lin.input_labels:
            u[lin.input_labels.index(port)] = 1.0
        x = np.zeros(A.shape[0])
        for k in range(steps):
            declared = (C @ x if A.size else np.zeros(len(outputs))) + D @ u
            x = A @ x + B @ u if A.size else x
            bad = np.abs(measured[k] - declared) > 1e-4 * (1.0 + np.abs(declared))
            if bad.any():
                j = int(np.argmax(bad))
                raise NoLinearModel(f"component {comp.name!r} ({_type_name(comp)}): its declared linearisation "
                                    f"disagrees with its step function at {op.speed:g} m/s: d {outputs[j]} / d {port} "
                                    f"after {k + 1} step(s) is declared {declared[j]:.6g}, its step gives "
                                    f"{measured[k][j]:.6g} (finite differences); update lateral_linearisation")


def linear_model_of(comp):
    """f(step, speed, ...) -> Block of the component: its method ``linear_model``, or the
    ``module:function`` its class names in ``LINEAR_MODEL`` (called with the component first); None
    when it has neither."""
    method = getattr(comp, "linear_model", None)
    if callable(method):
        return method
    name = getattr(type(comp), "LINEAR_MODEL", None)
    if not name:
        return None
    module, _, function = name.partition(":")
    try:
        model = getattr(import_study_module(module), function)
    except (ImportError, AttributeError) as exc:
        raise InputError(f"component {comp.name!r} ({type(comp).__module__}.{type(comp).__qualname__}): "
                         f"LINEAR_MODEL = {name!r} cannot be loaded ({exc}); expected 'module:function'") from None
    return functools.partial(model, comp)


def off_the_lateral_loop(comp) -> bool:
    """The component's class says ``OFF_THE_LATERAL_LOOP = True``: its outputs do not move the
    lateral channel at first order on a straight (the speed loop and its estimator set v; an
    implement reads the tractor and nothing reads it back; status and recording)."""
    return bool(getattr(type(comp), "OFF_THE_LATERAL_LOOP", False))


def _ground_argument(model, op: OperatingPoint) -> dict:
    """{"ground": op.ground} for a linear model that takes the ground (the IMU, the INS), else {}."""
    if op.ground is None or "ground" not in inspect.signature(model).parameters:
        return {}
    return {"ground": op.ground}


def ground_of(system, speed: float) -> Ground:
    """The ground under the tractor at the operating point: that of the built system's yaw plant
    (its ``linear_ground``; level when it has no slope)."""
    for node in system.nodes.values():
        comp = node.component
        if hasattr(comp, "linear_ground"):
            ground = comp.linear_ground(speed)
            if ground is not None:
                return ground
    return LEVEL


def study_ground(study, speed: float, resolver=None) -> Ground:
    """ground_of the study's system."""
    return ground_of(build_system(resolve(study, resolver)), speed)


def block_of(comp, step: float, ratio: int, op: OperatingPoint) -> Block | None:
    """The component's block, or None when it has none (network_of then checks that it is off the
    loop: off the lateral channel, reading nothing, or driving nothing the loop reads)."""
    if hasattr(comp, "lateral_linearisation"):
        sys_ = comp.lateral_linearisation(op.speed, step, op.along_track_error)
        if "tracker" in comp.roles:
            check_tracker(comp, sys_, step, op)
        return Block.of(comp.name, list(sys_.input_labels), list(sys_.output_labels), sys_.A, sys_.B, sys_.C, sys_.D,
                        ratio, comp.sampled)
    model = linear_model_of(comp)
    if model is not None:
        block = model(step, op.speed, **_ground_argument(model, op))
        block.ratio = ratio
        return block
    if isinstance(comp, CompositeComponent):
        return composite(comp, step, ratio, op)
    return None


def composite(comp, step: float, ratio: int, op: OperatingPoint) -> Block:
    """A subsystem as one block: its inner network run over its step (the inputs held), its
    outputs what its inner components hold after it (orchestrator.composite)."""
    sub = comp.subsystem.with_values({k: v for k, v in comp.p.items() if v is not None})
    inner = network_of(sub, op, purpose=f"the subsystem {comp.name!r}", resolver=comp.resolver)
    substeps = int(round(step / inner.base_step))
    if comp.sampled or substeps % inner.period:
        raise NoLinearModel(f"component {comp.name!r}: a subsystem whose step ({step} s) is not a whole number of "
                            f"its periods ({inner.step} s) or with only sampled components has no linear model here")
    ex = sub.exports
    inputs = list(ex.inputs)
    injected = {}
    for i, port in enumerate(inputs):
        for target in ex.input_targets(port):
            injected[tuple(target)] = i
    X, _, S, Y = inner.run(injected, len(inputs), instants=substeps)
    N = inner.n + len(inputs)
    # outputs read after the step: a continuous block's state through C (published at the next instant
    # in the host's time), a sampled block's last published value; both are rows of the new state
    outputs, rows = [], []
    for port in ex.outputs:
        name, out = ex.output_source(port)
        b = inner.blocks.get(name)
        if b is None or out not in b.outputs:
            continue
        j = b.outputs.index(out)
        select = np.zeros(inner.n)
        state, published = inner._layout[name]
        if b.sampled:
            select[published.start + j] = 1.0
        else:
            select[state] = b.C[j]
        outputs.append(port)
        rows.append(select)
    C = np.array(rows).reshape(len(rows), inner.n)
    return Block.of(comp.name, inputs, outputs, X[:, :inner.n], X[:, inner.n:N], C, ratio=ratio, sampled=False)


def network_of(study, op: OperatingPoint, purpose: str = "the margins", resolver=None) -> Network:
    """The study's lateral loop at the operating point (see the module docstring); its components'
    classes found by ``resolver`` (orchestrator.resolver; default: the default resolver)."""
    system = build_system(resolve(study, resolver))
    if op.ground is None:
        op = replace(op, ground=ground_of(system, op.speed))
    blocks: dict[str, Block] = {}
    for name, node in system.nodes.items():
        block = block_of(node.component, node.step, node.ratio, op)
        if block is not None:
            blocks[name] = block
    sources = {(c.target, c.input): (c.source, c.output) for c in system.connections}
    order = [n.name for n in system.sampled_order]
    for name, block in blocks.items():
        comp = system.nodes[name].component
        fix = getattr(type(comp), "FIX_INPUT", None)
        source = sources.get((name, fix), (None,))[0] if fix else None
        if source in system.nodes:
            # a model whose gains follow the cadence of its FIX_INPUT (a new fix every n-th of its steps):
            # at the source's instants when the source steps first
            node = system.nodes[name]
            every = max(1, system.nodes[source].ratio // node.ratio)
            first = source in order and order.index(source) < order.index(name)
            model = linear_model_of(comp)
            blocks[name] = model(node.step, op.speed, every, 0 if first else 1, **_ground_argument(model, op))
            blocks[name].ratio = node.ratio
    for (target, port), (source, output) in sources.items():
        if target in blocks and port in blocks[target].inputs and source not in blocks:
            comp = system.nodes[source].component
            if comp.declared("input") and not off_the_lateral_loop(comp):
                raise NoLinearModel(f"{study.where}: {purpose}: component {source!r} ({_type_name(comp)}) drives "
                                    f"{target}.{port} in the guidance loop and has no linear model: give its class "
                                    f"a method lateral_linearisation(speed, dt, along_track_error) returning a "
                                    f"python-control StateSpace labelled by its ports, or a method "
                                    f"linear_model(step, speed) returning a Block (as the shipped components have), "
                                    f"or OFF_THE_LATERAL_LOOP "
                                    f"= True when it moves nothing of the lateral channel")
    return Network(blocks, order, sources, study.study.base_step)
