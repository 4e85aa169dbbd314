"""The anatomy of a study's guidance loop for its margins: where the loop is opened (the steering
command, the tracker's yaw-rate command), which study value sets the actuator delay, and the yaw
plant whose initial offset the simulated check moves.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from agrobot.orchestrator.composite import CompositeComponent
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from agrobot.components.models.loop_blocks import NoLinearModel

@dataclass
class Anatomy:
    """Where the loop is opened and how its actuator delay is set."""

    steering_break: tuple[str, str]          # (component, input) that receives the steering command
    path_break: tuple[str, str]              # (component, input) that receives the tracker's yaw-rate command
    delay_key: str                           # the study value of the steering's command delay
    own_delay: float                         # its value in the study [s]
    delay_step: float                        # the steering's step (the delay's resolution) [s]
    tracker: str
    reference: str
    offset_key: str                          # the yaw plant's initial north position (simulated check)
    own_offset: float
    command_signal: str = ""                 # recorded steering command (component.output)
    command_step: float = 0.05               # its sample time [s]
    steer_limit: float = math.inf            # the yaw-rate controller's bounds on it [rad], [rad/s]
    steer_rate_limit: float = math.inf


def _steering(study: Study, purpose: str) -> tuple[tuple[str, str], str, float, float]:
    """(break, delay key, own delay, step) of the steering, at the top level or inside a subsystem."""
    model = resolve(study)
    found = model.find(role="steering")
    if len(found) == 1:
        name = found[0]
        step = study.components[name].step or study.study.base_step
        return (name, "steer_angle_cmd"), f"{name}.command_delay", float(model.parameters(name)["command_delay"]), step
    if len(found) > 1:
        raise NoLinearModel(f"{study.where}: {purpose}: more than one steering component ({', '.join(found)})")
    for name in study.components:
        cls = model.component_class(name)
        if not issubclass(cls, CompositeComponent):
            continue
        inner = cls.subsystem
        inner_model = cls.resolver.resolve(inner)
        steering = inner_model.find(role="steering")
        if len(steering) != 1:
            continue
        for port in inner.exports.inputs:
            if (steering[0], "steer_angle_cmd") in [tuple(t) for t in inner.exports.input_targets(port)]:
                key = f"{steering[0]}.command_delay"
                value = model.parameters(name).get(key)
                own = float(value if value is not None else inner_model.parameters(steering[0])["command_delay"])
                step = inner.components[steering[0]].step or inner.study.base_step
                return (name, port), f"{name}.{key}", own, step
    hardware = [n for n in model.find(role="tractor") if not issubclass(model.component_class(n), CompositeComponent)]
    if hardware:
        raise NoLinearModel(f"{study.where}: {purpose}: the tractor {hardware[0]!r} "
                            f"({study.components[hardware[0]].type}) is hardware: there is no model of it to derive "
                            f"margins from (its simulated twin has one, e.g. studies/figure8_hardware_layout.toml)")
    raise NoLinearModel(f"{study.where}: {purpose}: no steering component (role 'steering'): no steering loop to analyse")


def anatomy(study: Study, purpose: str = "the margins") -> Anatomy:
    """Find the loop's parts by role; a NoLinearModel (exit 2) says why a study has no loop."""
    steering_break, delay_key, own, step = _steering(study, purpose)
    model = resolve(study)
    trackers = model.find(role="tracker")
    if len(trackers) != 1:
        fed = {(c.target, c.input): c for c in study.connections}.get(steering_break)
        source = f"; its steering command comes from {fed.source}.{fed.output}" if fed else \
            "; its steering command is an input of the study (a subsystem's export)" if study.exports else ""
        raise NoLinearModel(f"{study.where}: {purpose}: no closed guidance loop: "
                            + ("no tracker (role 'tracker') steers the tractor" if not trackers
                               else f"{len(trackers)} trackers ({', '.join(trackers)})") + source)
    tracker = trackers[0]
    targets = [(c.target, c.input) for c in study.connections if c.source == tracker and c.output == "yaw_rate_desired"]
    if len(targets) != 1:
        raise NoLinearModel(f"{study.where}: {purpose}: {tracker}.yaw_rate_desired drives {len(targets)} inputs, expected one")
    references = [n for n in model.find(role="reference") if hasattr(model.component_class(n), "operating_points")]
    if len(references) != 1:
        raise NoLinearModel(f"{study.where}: {purpose}: expected one reference that declares its operating points "
                            f"(role 'reference'), found {len(references)}")
    plant = _plant(study, purpose)
    fed = {(c.target, c.input): c for c in study.connections}.get(steering_break)
    command = f"{fed.source}.{fed.output}" if fed else ""
    command_step = (study.components[fed.source].step or study.study.base_step) if fed else study.study.base_step
    limits = {}
    controllers = model.find(role="yaw_rate_controller")
    if len(controllers) == 1:
        p = model.parameters(controllers[0])
        limits = {"steer_limit": float(p["steer_limit"]), "steer_rate_limit": float(p["steer_rate_limit"])}
    return Anatomy(steering_break, targets[0], delay_key, own, step, tracker, references[0], *plant, command,
                   command_step, **limits)


def _plant(study: Study, purpose: str) -> tuple[str, float]:
    """(key of the yaw plant's initial north position y0, its value), at the top level or in a subsystem."""
    model = resolve(study)
    plants = model.find(role="yaw_plant")
    if len(plants) == 1:
        return f"{plants[0]}.y0", float(model.parameters(plants[0])["y0"])
    for name in study.components:
        cls = model.component_class(name)
        if not issubclass(cls, CompositeComponent):
            continue
        inner = cls.resolver.resolve(cls.subsystem)
        if len(inner.find(role="yaw_plant")) == 1:
            plant = inner.find(role="yaw_plant")[0]
            value = model.parameters(name).get(f"{plant}.y0")
            return f"{name}.{plant}.y0", float(value if value is not None else inner.parameters(plant)["y0"])
    raise NoLinearModel(f"{study.where}: {purpose}: no yaw plant (role 'yaw_plant')")


