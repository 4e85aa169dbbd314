"""The baseline model a diagnosis starts from, read from a study file.

The steering enters the replay as its closed-loop first-order equivalent (paper section II: a PI
around a valve whose flow sets the wheel rate)::

    ddelta/dt = clip(dz(delta_cmd(t - d) - delta, D) / tau, -r, r)

with, from the study's steering component, tau = V_rad (V_max - V_n - V_db) / (k_p Q_max) + tau_valve
(the small-signal loop gain plus the spool lag), D = V_db / k_p (+ angle_deadband), r = Q_max / V_rad
(or rate_limit if lower) and d = command_delay. The yaw dynamics are the study's plant model at the
measured speed; the gyro bias, GPS latency and antenna lever arm are the study's sensor values.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from components.gps_sensor import GPSSensor
from components.gyro_sensor import GyroSensor
from components.models.yaw_dynamics import GRAVITY, PHYSICAL_MODELS, TractorParameters
from components.steering_hydraulics import SteeringHydraulics
from components.tractor_yaw_plant import TractorYawPlant
from orchestrator.build import build_system
from orchestrator.study import Study, StudyError

ROLES = {"steering": SteeringHydraulics, "tractor": TractorYawPlant, "gps": GPSSensor, "gyro": GyroSensor}


@dataclass(frozen=True)
class Baseline:
    """Every value the replay needs, SI units; ``values`` holds the extension parameters."""

    study_path: Path | None
    components: dict[str, str]                  # role -> component name in the study
    yaw_model: str
    tractor: TractorParameters
    values: dict[str, float] = field(default_factory=dict)


def baseline_from_study(study: Study) -> Baseline:
    where = str(study.path) if study.path else "<study>"
    system = build_system(study)
    found: dict[str, str] = {}
    for name, node in system.nodes.items():
        for role, cls in ROLES.items():
            if isinstance(node.component, cls) and role not in found:
                found[role] = name
    for role in ("steering", "tractor"):
        if role not in found:
            raise StudyError(f"{where}: components: the diagnosis needs a {ROLES[role].__module__.split('.')[-1]} "
                             f"component (the {role}); found {sorted(system.nodes)}")
    sp = system.nodes[found["steering"]].component.p
    tp = system.nodes[found["tractor"]].component.p
    if tp["model"] not in PHYSICAL_MODELS:
        raise StudyError(f"{where}: components.{found['tractor']}.parameters.model: the diagnosis needs a "
                         f"physical yaw model {PHYSICAL_MODELS}, got {tp['model']!r}")
    kp = float(sp["kp"])
    span = sp["voltage_max"] - sp["neutral_voltage"] - sp["deadband"]
    valve_rate = sp["max_flow"] / sp["volume_per_rad"]
    rate = min(valve_rate, sp["rate_limit"]) if sp["rate_limit"] > 0 else valve_rate
    gyro = system.nodes[found["gyro"]].component.p if "gyro" in found else {"bias": 0.0}
    gps = system.nodes[found["gps"]].component.p if "gps" in found else {"latency": 0.0}
    values = {
        "steering_time_constant": sp["volume_per_rad"] * span / (kp * sp["max_flow"]) + sp["valve_time_constant"],
        "steering_deadband": sp["deadband"] / kp + sp["angle_deadband"],
        "steering_rate_limit": rate,
        "command_delay": sp["command_delay"],
        "steer_angle_offset": tp["steer_angle_offset"],
        "cornering_speed_slope": tp["cornering_speed_slope"],
        "cornering_reference_speed": tp["cornering_reference_speed"],
        "antenna_forward": tp["antenna_forward"], "antenna_left": tp["antenna_left"],
        "yaw_rate_bias": gyro["bias"], "gps_latency": gps["latency"],
        "cornering_front_scale": 1.0, "cornering_rear_scale": 1.0,
    }
    g_sin = GRAVITY * math.sin(tp["slope_angle"])
    values["slope_east"] = g_sin * math.cos(tp["slope_downhill_heading"])
    values["slope_north"] = g_sin * math.sin(tp["slope_downhill_heading"])
    params = TractorParameters(tp["m"], tp["I"], tp["l_f"], tp["l_r"], tp["C_f"], tp["C_r"], tp["sigma_f"], tp["sigma_r"])
    return Baseline(study.path, found, tp["model"], params, values)
