"""The catalogue of model extensions a diagnosis tests: every ``Effect`` class
of the modules in ``src/agrobot/diagnosis/effects/`` (one effect per module, see diagnosis.effect), ordered by
id, and the baseline's re-fitted parameters of each stage."""
from __future__ import annotations

import importlib
import math
import pkgutil

from . import effects as _effects
from .effect import Effect, Parameter


def _collect() -> tuple[Effect, ...]:
    found = []
    for info in pkgutil.iter_modules(_effects.__path__):
        module = importlib.import_module(f"{_effects.__name__}.{info.name}")
        found += [obj() for obj in vars(module).values()
                  if isinstance(obj, type) and issubclass(obj, Effect) and obj is not Effect
                  and obj.__module__ == module.__name__]
    ids = [e.id for e in found]
    if len(set(ids)) != len(ids):
        raise RuntimeError(f"diagnosis effects with the same id: {sorted(ids)}")
    return tuple(sorted(found, key=lambda e: e.id))


CATALOGUE: tuple[Effect, ...] = _collect()
EFFECT_IDS = tuple(e.id for e in CATALOGUE)

# the baseline's re-fitted ("uncertain") parameters of each stage
# (searched first in the prior range, widened to the physical limit when a fit ends on its edge)
UNCERTAIN = {
    "steering": (Parameter("steering_time_constant", "s", 0.05, 0.005, 1.0, limit=(0.001, 3.0)),),
    "yaw": (Parameter("cornering_front_scale", "1", 0.2, 0.4, 2.5, limit=(0.05, 20.0)),
            Parameter("cornering_rear_scale", "1", 0.2, 0.4, 2.5, limit=(0.05, 20.0)),
            Parameter("relaxation_scale", "1", 0.2, 0.3, 3.0, limit=(0.05, 10.0))),
    "position": (),
    "speed": (),
}

SIGNALS = {"steering": ("delta", "rad"), "yaw": ("yaw_rate", "rad/s"), "position": ("antenna_position", "m"),
           "speed": ("track_speed", "m/s")}
# What a person reads (reports, plots, messages): angles and angular rates in degrees, SI otherwise.
DISPLAY = {"steering": (180 / math.pi, "deg"), "yaw": (180 / math.pi, "deg/s"), "position": (1.0, "m"),
           "speed": (1.0, "m/s")}


def shown(stage: str, value: float, digits: int = 3) -> str:
    """A stage's SI value in its display unit, with the unit."""
    k, unit = DISPLAY[stage]
    return f"{k * value:.{digits}g} {unit}"
