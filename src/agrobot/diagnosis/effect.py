"""What a diagnosis effect is: a complete object.

An effect names the subsystem it lives in, the replay stages whose residuals it changes, its
parameters (SI, with the bounds searched and a typical scale for the optimiser), the values of
those parameters in the baseline study, a materiality threshold (smaller fitted values are not
worth a model change, whatever the statistics say) and the component options that switch it on
in a study, and the rule that judges its fitted values against the vehicle (``plausibility``). Adding
one is one class in one file of ``src/agrobot/diagnosis/effects/`` plus its test; the catalogue finds it
there and the verdict calls its rule.

It also owns its physics, in two forms the replay (diagnosis.replay) composes without naming it:

- ``enters``: the model quantities (``QUANTITIES``) its values carry: a parameter of a stage's plant
  (the steering's first-order equivalent, the yaw model), of a sensor (the gyro's bias and gain, the
  wheel speed's gain) or of the position reading (its point on the vehicle, its lag). Several effects
  carrying one quantity combine by its rule (offsets add, gains multiply);
- ``wheel_angle``: a transform of the steering reading or command on its way to the road wheels
  (a map of each sample alone, ``pointwise``, or of the signal, a clock's shift), applied in ``order``.
"""
from __future__ import annotations

import math
from typing import ClassVar, Mapping

import numpy as np

from agrobot.estimation import Parameter

from .plausibility import VehicleContext

__all__ = ["Parameter", "BaselineStudy", "Effect", "QUANTITIES", "TYRES"]     # Parameter: the shared estimation type

# The replay's model quantities an effect may carry (``Effect.enters``): name -> (the value without
# any effect, how several effects' values combine: "sum", "product", or "one": a single effect carries
# it, what it is). None: no default (a study always sets it).
QUANTITIES: dict[str, tuple[float | None, str, str]] = {
    "steering.time_constant": (None, "one", "the steering's first-order time constant [s]"),
    "steering.deadband": (0.0, "sum", "the steering's dead-band [rad of wheel angle]"),
    "steering.rate_limit": (math.inf, "one", "the steering's rate limit [rad/s of wheel angle]"),
    "steering.delay": (0.0, "sum", "the steering's transport delay [s]"),
    "yaw.front_scale": (1.0, "product", "the front cornering stiffness, x the study's"),
    "yaw.rear_scale": (1.0, "product", "the rear cornering stiffness, x the study's"),
    "yaw.relaxation_scale": (1.0, "product", "both relaxation lengths, x the study's"),
    "yaw.speed_slope": (0.0, "sum", "the cornering stiffness' change per m/s (yaw_dynamics.cornering_scale)"),
    "yaw.reference_speed": (2.0, "one", "the speed at which the stiffness is the study's [m/s]"),
    "yaw.friction": (math.inf, "one", "the tyres' friction (Magic Formula; inf: linear tyres)"),
    "yaw.shape": (1.3, "one", "the tyres' Magic Formula shape factor"),
    "yaw.steer_offset": (0.0, "sum", "an angle added to the wheel angle the yaw model is driven by [rad]"),
    "yaw.slope_east": (0.0, "sum", "a lateral acceleration g sin(phi) cos(psi_d) from a side slope [m/s2]"),
    "yaw.slope_north": (0.0, "sum", "a lateral acceleration g sin(phi) sin(psi_d) from a side slope [m/s2]"),
    "gyro.bias": (0.0, "sum", "the gyro reads gain x the yaw rate + bias [rad/s]"),
    "gyro.gain": (1.0, "product", "the gyro reads gain x the yaw rate + bias"),
    "gyro.time_constant": (0.0, "one", "the gyro reads through a first-order low-pass of this time constant [s]"),
    "speed.gain": (1.0, "product", "the wheel speed reads gain x the ground speed"),
    "position.forward": (0.0, "sum", "the position's point ahead of the rear axle [m]"),
    "position.left": (0.0, "sum", "the position's point left of the vehicle's centre line [m]"),
    "position.lag": (0.0, "sum", "the position reads the point this late [s] (negative: early)"),
}

# the quantities of the tyres' lateral force F = C alpha (its stiffnesses, their change with speed, its
# saturation): an effect carrying one acts on the tyres (Effect.on_tyres)
TYRES = ("yaw.front_scale", "yaw.rear_scale", "yaw.relaxation_scale", "yaw.speed_slope", "yaw.reference_speed",
         "yaw.friction", "yaw.shape")


class BaselineStudy:
    """The baseline study as the effects read it: component names and resolved (SI) parameters
    by role (``steering``, ``yaw_plant``, ``gps``, ``gyro``), each optional but the first two."""

    def __init__(self, model, names: Mapping[str, str]) -> None:
        self.model, self.study = model, model.study
        self.names = dict(names)
        self._params = {role: model.parameters(name) for role, name in names.items()}

    def has(self, role: str) -> bool:
        return role in self.names

    def parameters(self, role: str, default: Mapping[str, float] | None = None) -> Mapping[str, float]:
        if role not in self._params:
            if default is None:
                raise KeyError(role)
            return default
        return self._params[role]

    def step(self, role: str) -> float:
        spec = self.study.components[self.names[role]]
        return spec.step or self.study.study.base_step


class Effect:
    """One catalogue entry. Subclasses set the class attributes and implement ``baseline``,
    ``material`` and ``options``."""

    id: ClassVar[str]
    subsystem: ClassVar[str]
    stages: ClassVar[tuple[str, ...]]
    parameters: ClassVar[tuple[Parameter, ...]]
    starts: ClassVar[tuple[tuple[float, ...], ...]]      # starting values of the parameters
    threshold: ClassVar[str]                             # the materiality rule, in words
    hypothesis: ClassVar[str]                            # what it means on the tractor
    experiment: ClassVar[str]                            # the excitation that shows it apart from its rivals
    needs: ClassVar[tuple[str, ...]] = ()                # log columns it reads beyond its stages' (side slope: x, y)
    secondary: ClassVar[tuple[str, ...]] = ()            # parameters whose bound leaves the effect found (each is
                                                         # then "not identifiable" alone: a tyre's shape, not driven
                                                         # past its peak)
    imitated_by: ClassVar[tuple[str, ...]] = ()          # the import audit's finding kinds that can imitate it
    tested_on: ClassVar[tuple[str, ...]] = ()            # stages it shows on only through another part of the
                                                         # model: fitted on its other stages, tested on these too,
                                                         # its held-out gain the best of all (a steering map on the
                                                         # steering stage: the actuator's rate read through it)
                                                         # (a clock offset: a delay, a latency)
    enters: ClassVar[Mapping[str, str]] = {}             # QUANTITIES name -> the value (of this effect's) carrying it
    order: ClassVar[float] = 0.0                         # ``wheel_angle``s apply from the smallest order up
    pointwise: ClassVar[bool] = True                     # ``wheel_angle`` maps each sample alone (the steering
                                                         # stage then runs through it and back); False: it
                                                         # shifts the signal (a clock), the yaw stage's input only

    def on_tyres(self) -> bool:
        """Whether it carries a quantity of the tyres' lateral force (TYRES)."""
        return bool(set(self.enters) & set(TYRES))

    def baseline(self, study: BaselineStudy) -> dict[str, float]:
        """The replay values of this effect's parameters in the baseline study."""
        raise NotImplementedError

    def material(self, fitted: Mapping[str, float], base: Mapping[str, float]) -> bool:
        raise NotImplementedError

    def contradicts(self, fitted: Mapping[str, float], base: Mapping[str, float]) -> list[str]:
        """What the log itself shows against the fitted values (``base``: the baseline's values and
        what the selection reads of the log), one reason each; such a fit is not supported (the
        default: nothing)."""
        return []

    def options(self, fitted: Mapping[str, float], base: Mapping[str, float],
                study: BaselineStudy) -> list[tuple[str, str, float]]:
        """[(role, parameter, SI value)]: the component options that carry the fitted effect."""
        raise NotImplementedError

    def wheel_angle(self, x: np.ndarray, v: Mapping[str, float], t: np.ndarray | None) -> np.ndarray | None:
        """The road wheels' angle for the steering reading (or command) ``x`` under the values ``v``
        (``t``: the log's times, None for a table of readings); None where the effect is absent at
        ``v`` (the default: an effect that does not act on the steering's way to the wheels)."""
        return None

    def plausibility(self, values: Mapping[str, float], ctx: VehicleContext) -> list[str]:
        """What fitted values that no vehicle of this class has suggest instead, one reason per rule
        broken (empty: they fit the vehicle; the default for an effect without a rule)."""
        return []

    def applies(self, replay) -> bool:
        """Whether this log can judge the effect beyond its stages and columns (a command's gain
        needs the command to drive the yaw stage)."""
        return True

    def for_log(self, log: Mapping[str, float]) -> "Effect":
        """The effect with its ranges in the terms of this log (``log``: what the selection reads of
        it, the baseline's values beside; a ratio curve's range at the log's steering angles)."""
        return self

    def hypothesis_for(self, stages) -> str:
        """The hypothesis in terms of the stages this log judged it on (a log without GPS is not
        told about the GPS track)."""
        return self.hypothesis

    def display(self, fitted: Mapping[str, float]) -> dict[str, float]:
        """The fitted parameters as a person reads them ('name [unit]' -> value)."""
        return {f"{p.name} [{p.display_unit or p.unit}]": fitted[p.name] * p.display_factor for p in self.parameters}
