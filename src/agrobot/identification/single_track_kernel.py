"""The yaw model's segment simulation at compiled speed: single_track_kernel.c (the single-track
model of components.models.tyre through the steering lag with a first-order hold (a held input's
with a zero-order hold), one row at a time: linear tyres by the exact discretisation at each sample's mean speed, as
identification.driving.exact_steps; the Magic Formula by ROS2 substeps) compiled once per content by the compiled engine's toolchain
(orchestrator.compiled.toolchain: $CC, cc or gcc; cached by hash under $AGROBOT_CACHE) and called
through ctypes. identification.driving.YawModel keeps the Python path as the reference; ``choose``
picks between them (``auto``: C where a compiler is found, else Python, said once).
"""
from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from agrobot.orchestrator.compiled.optional_library import KERNELS as KERNELS  # the kernels a caller may ask
from agrobot.orchestrator.compiled.optional_library import OptionalLibrary
from agrobot.orchestrator.compiled.toolchain import library

SOURCE = Path(__file__).with_suffix(".c")
HEADER = SOURCE.with_name("phi_step.h")     # the exact first-order-hold step (driving.phi_steps' C twin)
DEFAULT = "auto"             # what a YawModel runs unless told (``python``: the reference everywhere)
MODELS = {"bicycle": 0, "rlf": 1, "rlfr": 2}
# per-row parameters in the C file's P_ order
PARAMETERS = ("lag_decay", "hold_gain", "lag", "delay", "C_f", "C_r", "mu", "shape", "cornering_speed_slope",
              "cornering_reference_speed", "sigma_f", "sigma_r", "m", "I", "l_f", "l_r", "F_zf", "F_zr")


def _load() -> ctypes.CDLL:
    lib, _, _ = library({SOURCE.name: SOURCE.read_text()}, [HEADER.parent], [HEADER])
    dbl = ctypes.POINTER(ctypes.c_double)
    lib.single_track_simulate.argtypes = [ctypes.c_int, ctypes.c_long, ctypes.c_long, ctypes.c_long, ctypes.c_int,
                                          ctypes.c_double, dbl, dbl, dbl, dbl, dbl, dbl]
    lib.single_track_simulate.restype = ctypes.c_long
    lib.single_track_parameter_count.restype = ctypes.c_long
    if lib.single_track_parameter_count() != len(PARAMETERS):
        raise RuntimeError(f"{SOURCE.name}: the C file reads {lib.single_track_parameter_count()} parameters per "
                           f"row, the module packs {len(PARAMETERS)}")
    return lib


LIBRARY = OptionalLibrary(_load, "the yaw model's simulations run in Python, 10 to 40 times slower than in C")
choose = LIBRARY.choose


def simulate(model: str, sub: int, h: float, w: np.ndarray, v: np.ndarray, par: np.ndarray,
             phase: np.ndarray | None = None):
    """(yaw rate, lateral velocity), each (rows, L): row i driven by the wheel angle asked w[i] at
    the speed v[i mod S] (v: (S, L)) with the parameters par[i] (PARAMETERS' order), from the
    kinematic state; ``sub`` ROS2 substeps per sample step h (Magic Formula rows). ``phase``
    (rows, L): a held input (zero-order hold), w[i, j] for phase[i, j] of step j, then w[i, j + 1]
    (identification.driving.DrivingLog.hold_phases); None: w linear between samples."""
    lib = LIBRARY.lib()
    w = np.ascontiguousarray(w, float)
    v = np.ascontiguousarray(v, float)
    par = np.ascontiguousarray(par, float)
    rows, L = w.shape
    if phase is not None:
        phase = np.ascontiguousarray(phase, float)
    if (par.shape != (rows, len(PARAMETERS)) or v.shape[1] != L or rows % max(len(v), 1)
            or (phase is not None and phase.shape != w.shape)):
        raise ValueError(f"shapes: w {w.shape}, v {v.shape}, par {par.shape}"
                         + ("" if phase is None else f", phase {phase.shape}"))
    yaw, vy = np.empty((rows, L)), np.empty((rows, L))
    dbl = ctypes.POINTER(ctypes.c_double)
    failed = lib.single_track_simulate(MODELS[model], rows, len(v), L, int(sub), float(h), w.ctypes.data_as(dbl),
                                       v.ctypes.data_as(dbl), par.ctypes.data_as(dbl),
                                       None if phase is None else phase.ctypes.data_as(dbl), yaw.ctypes.data_as(dbl),
                                       vy.ctypes.data_as(dbl))
    if failed >= 0:
        raise np.linalg.LinAlgError(f"Singular matrix (the Rosenbrock step of row {failed})")
    return yaw, vy
