"""What a diagnosis effect is: a complete object.

An effect names the subsystem it lives in, the replay stages whose residuals it changes, its
parameters (SI, with the bounds searched and a typical scale for the optimiser), the values of
those parameters in the baseline study, a materiality threshold (smaller fitted values are not
worth a model change, whatever the statistics say) and the component options that switch it on
in a study, and the rule that judges its fitted values against the vehicle (``plausibility``). Adding
one is one class in one file of ``src/agrobot/diagnosis/effects/`` plus its test; the catalogue finds it
there and the verdict calls its rule.
"""
from __future__ import annotations

from typing import ClassVar, Mapping

from agrobot.estimation import Parameter

from .plausibility import VehicleContext

__all__ = ["Parameter", "BaselineStudy", "Effect"]     # Parameter: the shared estimation type


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

    def baseline(self, study: BaselineStudy) -> dict[str, float]:
        """The replay values of this effect's parameters in the baseline study."""
        raise NotImplementedError

    def material(self, fitted: Mapping[str, float], base: Mapping[str, float]) -> bool:
        raise NotImplementedError

    def options(self, fitted: Mapping[str, float], base: Mapping[str, float],
                study: BaselineStudy) -> list[tuple[str, str, float]]:
        """[(role, parameter, SI value)]: the component options that carry the fitted effect."""
        raise NotImplementedError

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
