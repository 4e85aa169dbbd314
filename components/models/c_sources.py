"""What the components' C cores share: the guidance laws and the QP solver the tracker, the speed PID
and the MPC include (the controller FMU includes them too), the one rounding of a delay to whole
steps, and the substep count of a continuous core."""
from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).parent
GUIDANCE_LAWS = (HERE / "guidance_laws.c",)
QP_SOLVER = (HERE / "qp_active_set.c", HERE / "qp_active_set.h")


def delay_steps(delay: float, step: float) -> int:
    """A transport delay as whole steps of the component that applies it: round(d / h)."""
    return int(round(float(delay) / float(step)))


def substeps_define(comp, period: float) -> str:
    """``SUBSTEPS``: internal steps per sample of a core that integrates at ``internal_step``."""
    return f"#define SUBSTEPS {max(1, delay_steps(period, comp.p['internal_step']))}\n"
