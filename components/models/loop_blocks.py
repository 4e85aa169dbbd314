"""The pieces of a linear guidance-loop network (analysis.loop_models; each component builds its own block,
``linear_model``): the operating point, a discrete block with named ports (y = C x + D u, x <- A x + B u,
possibly periodic), delay lines, pass-throughs and the lifting of a fast block over a slower step.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from agrobot.orchestrator.errors import InputError


class NoLinearModel(InputError):
    """The study's loop holds a component this module cannot linearise, or has no loop."""


@dataclass(frozen=True)
class Ground:
    """The ground under the tractor at the operating point (heading east; the yaw plant's
    linear_ground): its roll and pitch and their change with the heading, the in-plane gravity across
    the heading a_lat = P . (-sin psi, cos psi) (left positive) and its change with the heading, the
    left specific force the IMU reads when driving straight there (g sin(roll) cos(pitch)), and the
    rear axle's steady sideways velocity (its crab, left positive). All zero: level ground."""

    roll: float = 0.0
    pitch: float = 0.0
    roll_per_heading: float = 0.0        # d roll / d psi
    pitch_per_heading: float = 0.0       # d pitch / d psi
    pull: float = 0.0                    # a_lat [m/s2]
    pull_per_heading: float = 0.0        # d a_lat / d psi [m/s2/rad]
    specific_force: float = 0.0          # f_y [m/s2]
    crab: float = 0.0                    # [m/s]

    @property
    def level(self) -> bool:
        return not any((self.roll, self.pitch, self.roll_per_heading, self.pitch_per_heading, self.pull,
                        self.pull_per_heading, self.specific_force, self.crab))

    def slip_compliance(self, speed: float) -> float:
        """k of the INS's crab model v_lat = -k f_y v that matches this crab (0 on level ground)."""
        return -self.crab / (self.specific_force * speed) if self.specific_force and speed else 0.0


LEVEL = Ground()


@dataclass(frozen=True)
class OperatingPoint:
    """A straight line heading east at ``speed``, the CG on the reference's line
    ``along_track_error`` behind its point (a time-based reference: what the speed loop leaves), on
    ``ground`` (None: the ground of the study's yaw plant, found when its network is built)."""

    speed: float
    along_track_error: float = 0.0
    label: str = ""
    ground: Ground | None = None


@dataclass
class Block:
    """A discrete linear block at ``ratio`` base steps: sampled y = C x + D u, x <- A x + B u;
    continuous (D = 0) x <- A x + B u, published y = C x at its next instant."""

    name: str
    inputs: list[str]
    outputs: list[str]
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    ratio: int = 1
    sampled: bool = True
    phases: list | None = None

    @classmethod
    def of(cls, name: str, inputs, outputs, A=None, B=None, C=None, D=None, ratio: int = 1,
           sampled: bool = True) -> "Block":
        """Missing matrices are empty (no state) or zero (no feedthrough)."""
        n = 0 if A is None else np.atleast_2d(A).shape[0]
        A = np.zeros((n, n)) if A is None else np.atleast_2d(np.asarray(A, float))
        B = np.zeros((n, len(inputs))) if B is None else np.asarray(B, float).reshape(n, len(inputs))
        C = np.zeros((len(outputs), n)) if C is None else np.asarray(C, float).reshape(len(outputs), n)
        D = np.zeros((len(outputs), len(inputs))) if D is None else np.asarray(D, float).reshape(len(outputs), len(inputs))
        return cls(name, list(inputs), list(outputs), A, B, C, D, ratio, sampled)

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def cycle(self) -> int:
        """Its own steps per period: 1, or the length of ``phases``."""
        return len(self.phases) if self.phases else 1

    def at(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) of its ``j``-th own step: the same each step, or ``phases[j mod cycle]`` for a
        periodically time-varying block (an estimator that takes a fix every n-th of its steps)."""
        return self.phases[j % len(self.phases)] if self.phases else (self.A, self.B, self.C, self.D)


def delay_line(name: str, inputs: list[str], outputs: list[str], samples: int) -> Block:
    """out_k = in_{k - n} per channel (a deque of n + 1 read at its oldest end)."""
    m = len(inputs)
    if samples == 0:
        return Block.of(name, inputs, outputs, D=np.eye(m))
    n = samples * m
    A = np.zeros((n, n))
    A[m:, :-m] = np.eye(n - m)                       # registers [u_{k-1}; ...; u_{k-n}]
    B = np.zeros((n, m))
    B[:m] = np.eye(m)
    C = np.zeros((m, n))
    C[:, -m:] = np.eye(m)
    return Block.of(name, inputs, outputs, A, B, C)


def passthrough(name: str, pairs: dict[str, str]) -> Block:
    """A memoryless unit gain from each input to the output it names."""
    return Block.of(name, list(pairs), list(pairs.values()), D=np.eye(len(pairs)))


def lifted(A: np.ndarray, B: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """m steps of x <- A x + B u with u held: (A^m, sum_i A^i B)."""
    Am, Bm = np.eye(A.shape[0]), np.zeros_like(B)
    for _ in range(m):
        Bm = A @ Bm + B
        Am = A @ Am
    return Am, Bm
