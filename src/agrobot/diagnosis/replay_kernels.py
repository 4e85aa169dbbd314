"""The diagnosis's stage replays at compiled speed: replay_kernels.c (the steering's first-order
equivalent, the yaw replay's indexed time-varying recursion, the exact first-order hold of its systems
at the log's speeds by identification/phi_step.h) compiled once per content by the compiled engine's toolchain
(orchestrator.compiled.toolchain: $CC, cc or gcc; cached by hash under $AGROBOT_CACHE) and called
through ctypes, which lets go of the interpreter lock while C runs. diagnosis.replay keeps the Python
path as the reference; ``choose`` picks between them (``auto``: C where a compiler is found, else
Python, said once per process).
"""
from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from agrobot.orchestrator.compiled.optional_library import KERNELS as KERNELS  # the kernels a caller may ask
from agrobot.orchestrator.compiled.optional_library import OptionalLibrary
from agrobot.orchestrator.compiled.toolchain import library

SOURCE = Path(__file__).with_suffix(".c")
HEADER = Path(__file__).parents[1] / "identification" / "phi_step.h"     # the exact first-order-hold step
MAX_ORDER = 16                 # the C file's largest state (recursion)
HOLD_ORDER, HOLD_INPUTS = 5, 4  # phi_step.h's NX and NU: the largest system and input columns of a hold


def _load() -> ctypes.CDLL:
    lib, _, _ = library({SOURCE.name: SOURCE.read_text()}, [HEADER.parent], [HEADER])
    L, D, I, P = ctypes.c_long, ctypes.c_double, ctypes.c_int, ctypes.c_void_p
    lib.steering_first_order.argtypes = [L, I, P, P, D, D, D, D, D, D, P]
    lib.indexed_recursion.argtypes = [L, L, L, L, L, L, P, P, P, P, P, P, L, P, P]
    lib.first_order_hold.argtypes = [L, L, L, D, P, P, P, P, P]
    lib.first_order_hold.restype = L
    for f in (lib.steering_first_order, lib.indexed_recursion):
        f.restype = None
    lib.hold_limits.restype = L
    if lib.hold_limits() != 100 * HOLD_ORDER + HOLD_INPUTS:
        raise RuntimeError(f"{HEADER.name}: NX, NU {divmod(lib.hold_limits(), 100)}, the module expects "
                           f"{HOLD_ORDER}, {HOLD_INPUTS}")
    return lib


LIBRARY = OptionalLibrary(_load, "the diagnosis's stage replays run in Python, several times slower")
choose = LIBRARY.choose
_lib = LIBRARY.lib


def _as(x, dtype) -> np.ndarray:
    return np.ascontiguousarray(x, dtype)


def steering_first_order(pieces: list[tuple[np.ndarray, float, float]], deadband: float, delta0: float) -> np.ndarray:
    """The first-order equivalent's wheel angle (components.models.steering_equivalent.simulate) from
    its one or two pieces per sample step, each (held command, alpha, r s)."""
    commands = [_as(c, float) for c, _, _ in pieces]
    n = len(commands[0])
    out = np.empty(n)
    (c1, a1, m1), (c2, a2, m2) = [(commands[i], *pieces[i][1:]) for i in (0, -1)]
    _lib().steering_first_order(n, len(pieces), c1.ctypes.data, c2.ctypes.data, float(a1), float(m1), float(a2),
                                float(m2), float(deadband), float(delta0), out.ctypes.data)
    return out


def indexed_recursion(A: np.ndarray, B: np.ndarray, index: np.ndarray, columns, u: np.ndarray, rows,
                      B1: np.ndarray | None = None) -> np.ndarray:
    """Rows ``rows`` of Z_{k-1} for Z_k = A[index_k] Z_{k-1} + B[index_k][:, columns] * u_k
    (+ B1[index_k][:, columns] * u_{k+1}, u_N = u_{N-1}: a first-order hold), Z_{-1} = 0, R sets side
    by side: A (R, S, n, n), B and B1 (R, S, n, p), u (R, N, m); returns (R, N, len(rows), m)."""
    A, B, u = _as(A, float), _as(B, float), _as(u, float)
    B1 = None if B1 is None else _as(B1, float)
    index, columns, rows = _as(index, np.int_), _as(columns, np.int_), _as(rows, np.int_)
    R, S, n, _ = A.shape
    p, (N, m) = B.shape[-1], u.shape[1:]
    if n > MAX_ORDER or m > MAX_ORDER or B.shape[:3] != (R, S, n) or u.shape[0] != R or len(index) != N \
            or len(columns) != m or (N and (index.min() < 0 or index.max() >= S)) or (m and columns.max() >= p) \
            or (B1 is not None and B1.shape != B.shape):
        raise ValueError(f"shapes: A {A.shape}, B {B.shape}, index {index.shape}, columns {columns.shape}, u {u.shape}")
    out = np.empty((R, N, len(rows), m))
    _lib().indexed_recursion(R, S, N, n, p, m, A.ctypes.data, B.ctypes.data, None if B1 is None else B1.ctypes.data,
                             index.ctypes.data, columns.ctypes.data, u.ctypes.data, len(rows), rows.ctypes.data,
                             out.ctypes.data)
    return out


def first_order_hold(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Phi, G0, G1) of each system of a stack, A (k, n, n) and B (k, n, p), n at most HOLD_ORDER, p
    at most HOLD_INPUTS: x_{k+1} = Phi x_k + G0 u_k + G1 u_{k+1} for u linear over the step h
    (diagnosis.replay.first_order_hold, identification/phi_step.h)."""
    A, B = _as(A, float), _as(B, float)
    k, n, p = B.shape
    if n > HOLD_ORDER or p > HOLD_INPUTS or A.shape != (k, n, n):
        raise ValueError(f"shapes: A {A.shape}, B {B.shape} (at most {HOLD_ORDER} states, {HOLD_INPUTS} inputs)")
    Phi, G0, G1 = np.empty_like(A), np.empty_like(B), np.empty_like(B)
    failed = _lib().first_order_hold(k, n, p, float(h), A.ctypes.data, B.ctypes.data, Phi.ctypes.data,
                                     G0.ctypes.data, G1.ctypes.data)
    if failed >= 0:
        raise np.linalg.LinAlgError(f"Singular matrix (the Pade denominator of system {failed})")
    return Phi, G0, G1
