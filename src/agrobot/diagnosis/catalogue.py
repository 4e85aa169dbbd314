"""The catalogue of model extensions a diagnosis tests: every ``Effect`` class of the modules in
``src/agrobot/diagnosis/effects/`` (one effect per module, see diagnosis.effect), ordered by id, and
any registered from elsewhere (``Catalogue.register``: a plug-in, a test); the baseline's re-fitted
parameters of each stage; and the model quantities their values carry into the replay
(``Catalogue.quantities``, ``Catalogue.transforms``: how diagnosis.replay composes them).
"""
from __future__ import annotations

import importlib
import math
import pkgutil
from collections.abc import Sequence
from contextlib import contextmanager
from typing import Iterator, Mapping

from . import effects as _effects
from .effect import QUANTITIES, Effect, Parameter


def _collect() -> list[Effect]:
    found = []
    for info in pkgutil.iter_modules(_effects.__path__):
        module = importlib.import_module(f"{_effects.__name__}.{info.name}")
        found += [obj() for obj in vars(module).values()
                  if isinstance(obj, type) and issubclass(obj, Effect) and obj is not Effect
                  and obj.__module__ == module.__name__]
    return found


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
# the model quantities (effect.QUANTITIES) the re-fitted parameters carry, as an effect's ``enters``
UNCERTAIN_ENTERS = {"steering.time_constant": "steering_time_constant", "yaw.front_scale": "cornering_front_scale",
                    "yaw.rear_scale": "cornering_rear_scale", "yaw.relaxation_scale": "relaxation_scale"}


class Catalogue(Sequence):
    """The effects a diagnosis tests, ordered by id (a sequence of Effect)."""

    def __init__(self, effects=()) -> None:
        self._effects: tuple[Effect, ...] = ()
        self._routes: dict[str, list[tuple[str, tuple[str, ...], float | None, str]]] | None = None
        for effect in effects:
            self.register(effect)

    def __getitem__(self, i):
        return self._effects[i]

    def __len__(self) -> int:
        return len(self._effects)

    def __add__(self, other) -> tuple:
        return self._effects + tuple(other)

    def register(self, effect: Effect) -> Effect:
        """Add ``effect`` (an Effect instance): the selection tests it, the baseline reads its values, the
        replay composes its physics. Refused (ValueError) when its id is taken, it names a quantity the
        replay does not know, or it carries a single-valued quantity another already carries."""
        if any(e.id == effect.id for e in self._effects):
            raise ValueError(f"diagnosis effect {effect.id!r}: an effect with this id is registered already")
        unknown = sorted(set(effect.enters) - set(QUANTITIES))
        if unknown:
            raise ValueError(f"diagnosis effect {effect.id!r}: enters {unknown}: not a replay quantity "
                             f"(diagnosis.effect.QUANTITIES: {sorted(QUANTITIES)})")
        taken = self._carriers()
        for quantity, name in effect.enters.items():
            if QUANTITIES[quantity][1] == "one" and taken.get(quantity, {name}) != {name}:
                raise ValueError(f"diagnosis effect {effect.id!r}: {quantity} is carried by {sorted(taken[quantity])} "
                                 f"already (one value only)")
        self._effects = tuple(sorted(self._effects + (effect,), key=lambda e: e.id))
        self._routes = None
        return effect

    def unregister(self, effect_id: str) -> Effect:
        """Take the effect ``effect_id`` out (KeyError when none is registered)."""
        effect = next((e for e in self._effects if e.id == effect_id), None)
        if effect is None:
            raise KeyError(f"no diagnosis effect {effect_id!r} is registered")
        self._effects = tuple(e for e in self._effects if e is not effect)
        self._routes = None
        return effect

    @contextmanager
    def registered(self, *effects: Effect, replacing: tuple[str, ...] = ()) -> Iterator[None]:
        """``effects`` registered (the ids ``replacing`` taken out) for the duration of the block.
        This process only: a diagnosis on several workers computes its fits in fresh interpreters,
        which find the effects of the ``effects`` folder alone (run it on one worker)."""
        removed = [self.unregister(i) for i in replacing]
        added = []
        try:
            for effect in effects:
                added.append(self.register(effect))
            yield
        finally:
            for effect in added:
                self.unregister(effect.id)
            for effect in removed:
                self.register(effect)

    def _carriers(self) -> dict[str, set[str]]:
        """quantity -> the value names carrying it (the baseline's refit and every effect)."""
        out: dict[str, set[str]] = {}
        for enters in [UNCERTAIN_ENTERS] + [e.enters for e in self._effects]:
            for quantity, name in enters.items():
                out.setdefault(quantity, set()).add(name)
        return out

    def _routing(self) -> dict[str, list[tuple[str, tuple[str, ...], float | None, str]]]:
        """place -> [(quantity, the value names carrying it in catalogue order, default, rule)]."""
        if self._routes is None:
            names: dict[str, list[str]] = {q: [] for q in QUANTITIES}
            for enters in [UNCERTAIN_ENTERS] + [e.enters for e in self._effects]:
                for quantity, name in enters.items():
                    if name not in names[quantity]:
                        names[quantity].append(name)
            routes: dict[str, list] = {}
            for quantity, (default, rule, _) in QUANTITIES.items():
                place, short = quantity.split(".", 1)
                routes.setdefault(place, []).append((short, tuple(names[quantity]), default, rule))
            self._routes = routes
        return self._routes

    def quantities(self, v: Mapping[str, float], place: str) -> dict[str, float]:
        """The model quantities of ``place`` ("steering", "yaw", "gyro", "speed", "position"; the
        names after the dot in effect.QUANTITIES) under the values ``v``: the values of ``v`` that carry
        each, combined by its rule in catalogue order; its default where ``v`` holds none."""
        out = {}
        for short, names, default, rule in self._routing()[place]:
            present = [v[n] for n in names if n in v]
            if not present:
                if default is None:
                    raise KeyError(f"{place}.{short}: no value among {list(names)}")
                out[short] = default
                continue
            x = present[0]
            for y in present[1:]:
                x = x * y if rule == "product" else x + y
            out[short] = x
        return out

    def transforms(self, v: Mapping[str, float], pointwise: bool = False) -> list[Effect]:
        """The effects present in ``v`` (every parameter of theirs set) that act on the steering's
        way to the wheels (Effect.wheel_angle), in their order; ``pointwise``: the maps of each
        sample alone only."""
        found = [e for e in self._effects if type(e).wheel_angle is not Effect.wheel_angle
                 and (e.pointwise or not pointwise) and all(p.name in v for p in e.parameters)]
        return sorted(found, key=lambda e: e.order)


CATALOGUE = Catalogue(_collect())
EFFECT_IDS = tuple(e.id for e in CATALOGUE)          # the effects of the effects folder

SIGNALS = {"steering": ("delta", "rad"), "yaw": ("yaw_rate", "rad/s"), "position": ("antenna_position", "m"),
           "speed": ("track_speed", "m/s")}
# What a person reads (reports, plots, messages): angles and angular rates in degrees, SI otherwise.
DISPLAY = {"steering": (180 / math.pi, "deg"), "yaw": (180 / math.pi, "deg/s"), "position": (1.0, "m"),
           "speed": (1.0, "m/s")}


def shown(stage: str, value: float, digits: int = 3) -> str:
    """A stage's SI value in its display unit, with the unit."""
    k, unit = DISPLAY[stage]
    return f"{k * value:.{digits}g} {unit}"
