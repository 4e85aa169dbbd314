"""Find a component's signal in a result table by the component's type (not its study name)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from orchestrator.study import Study


class MissingSignal(KeyError):
    pass


def component_named(study: Study, type_name: str) -> str:
    names = [n for n, spec in study.components.items() if spec.type.split(":")[0].split(".")[-1] == type_name]
    if len(names) != 1:
        raise MissingSignal(f"the analysis needs exactly one component of type {type_name!r}, "
                            f"the study has {len(names)}")
    return names[0]


def signal(frame: pd.DataFrame, study: Study, type_name: str, port: str) -> np.ndarray:
    column = f"{component_named(study, type_name)}.{port}"
    if column not in frame:
        raise MissingSignal(f"result table has no column {column!r}")
    return frame[column].to_numpy()


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")
