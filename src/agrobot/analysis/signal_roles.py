"""Find a component's signal in a result table by the component's declared role (not its study name)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study


class MissingSignal(KeyError):
    pass


def component_named(study: Study, role: str) -> str:
    """The one component declaring ``role`` (Component.roles)."""
    names = resolve(study).find(role=role)
    if len(names) != 1:
        raise MissingSignal(f"the analysis needs exactly one component with role {role!r}, "
                            f"the study has {len(names)}" + (f" ({', '.join(names)})" if names else ""))
    return names[0]


def signal(frame: pd.DataFrame, study: Study, role: str, port: str) -> np.ndarray:
    column = f"{component_named(study, role)}.{port}"
    if column not in frame:
        raise MissingSignal(f"result table has no column {column!r}")
    return frame[column].to_numpy()


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, last + 1) of each run of True in ``mask``."""
    edges = np.diff(np.concatenate([[0], np.asarray(mask).astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")


def sample_rows(frame: pd.DataFrame, study: Study, role: str) -> np.ndarray:
    """Rows at the instants the sampled component with ``role`` computed its outputs (t0 + k step,
    counted from the study's start, not the table's)."""
    spec = study.components.get(component_named(study, role))
    step = (spec.step if spec is not None and spec.step else None) or study.study.base_step
    k = (frame["t"].to_numpy(float) - study.study.start_time) / step
    return np.abs(k - np.round(k)) < 1e-6


def between_samples(frame: pd.DataFrame, study: Study, role: str, ports: tuple[str, ...]) -> list[np.ndarray]:
    """The outputs of the sampled component with ``role`` at every instant of ``frame``,
    interpolated linearly between the instants it computed them (t0 + k step) instead of held
    from one to the next: a 20 Hz reference compared with a 100 Hz plant then adds no sawtooth of
    up to speed x 50 ms. Rows after the last sample keep it."""
    t = frame["t"].to_numpy(float)
    own = sample_rows(frame, study, role)
    values = [signal(frame, study, role, port) for port in ports]
    if own.sum() < 2 or own.all():
        return values
    return [np.interp(t, t[own], v[own]) for v in values]
