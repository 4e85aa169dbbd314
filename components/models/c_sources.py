"""What the components' C cores share: the guidance laws and the QP solver the tracker, the speed PID
and the MPC include (the controller FMU includes them too), the one rounding of a delay to whole
steps, and the one substep count of a continuous component."""
from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).parent
GUIDANCE_LAWS = (HERE / "guidance_laws.c",)
QP_SOLVER = (HERE / "qp_active_set.c", HERE / "qp_active_set.h")


def delay_steps(delay: float, step: float) -> int:
    """A transport delay as whole steps of the component that applies it: round(d / h)."""
    return int(round(float(delay) / float(step)))


def substeps(step: float, internal_step: float) -> int:
    """Internal steps per step of a component that integrates at ``internal_step``: max(1, round(h / h_i))."""
    return max(1, int(round(float(step) / float(internal_step))))


def substeps_define(comp, period: float) -> str:
    """``SUBSTEPS`` of a C core that integrates at the component's ``internal_step``."""
    return f"#define SUBSTEPS {substeps(period, comp.p['internal_step'])}\n"
