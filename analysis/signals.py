"""Find a component's signal in a result table by the component's declared role (not its study name)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from orchestrator.study import Study


class MissingSignal(KeyError):
    pass


def component_named(study: Study, role: str) -> str:
    """The one component declaring ``role`` (Component.roles)."""
    names = study.find(role=role)
    if len(names) != 1:
        raise MissingSignal(f"the analysis needs exactly one component with role {role!r}, "
                            f"the study has {len(names)}" + (f" ({', '.join(names)})" if names else ""))
    return names[0]


def signal(frame: pd.DataFrame, study: Study, role: str, port: str) -> np.ndarray:
    column = f"{component_named(study, role)}.{port}"
    if column not in frame:
        raise MissingSignal(f"result table has no column {column!r}")
    return frame[column].to_numpy()


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")
