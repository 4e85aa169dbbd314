"""The tractor as one component (a composite): a tractor-side study (default
studies/tractor_side.toml) stepped by the orchestrator's engine inside this component's step.

Its ports are those of ``hardware_tractor``, so a study swaps simulation for hardware by changing
this component's line only. Set-points go to ``steering.steer_angle_cmd`` and
``speed_controller.speed_desired`` of the sub-study; outputs come from its ``gps``, ``steering``,
``tractor`` and ``drivetrain`` components (the truth outputs x_cg, y_cg, heading too; hardware has
none and reports NaN); ``fix_quality`` is RTK fixed while the simulated GPS delivers and 0 in an
outage. The sub-study's seed is drawn from this component's random stream.
"""
from __future__ import annotations

from pathlib import Path

from orchestrator.component import Component, inp, out, par

from .hardware.nmea import RTK_FIXED

STUDIES = Path(__file__).resolve().parent.parent / "studies"

TRACTOR_PORTS = (
    inp("steer_angle_cmd", "rad", 0.0, "wheel-angle set-point"),
    inp("speed_cmd", "m/s", 0.0, "speed set-point"),
    inp("safe_state", "1", 0.0, "1 while the guidance holds the tractor safe"),
    out("gps_x", "m", 0.0, "GPS antenna east position"),
    out("gps_y", "m", 0.0, "GPS antenna north position"),
    out("gps_vel_east", "m/s", 0.0, "GPS east velocity"),
    out("gps_vel_north", "m/s", 0.0, "GPS north velocity"),
    out("fix_valid", "1", 0.0, "1 when a new good fix arrived"),
    out("fix_age", "s", 0.0, "time since the last good fix"),
    out("fix_quality", "1", 0.0, "GGA fix quality (4 RTK fixed)"),
    out("steer_angle_measured", "rad", 0.0, "measured wheel angle"),
    out("yaw_rate", "rad/s", 0.0, "measured yaw rate"),
    out("speed_measured", "m/s", 0.0, "measured speed"),
    out("x_cg", "m", 0.0, "truth: CG east position (NaN on hardware)"),
    out("y_cg", "m", 0.0, "truth: CG north position (NaN on hardware)"),
    out("heading", "rad", 0.0, "truth: heading (NaN on hardware)"),
)

INPUTS = {"steer_angle_cmd": ("steering", "steer_angle_cmd"), "speed_cmd": ("speed_controller", "speed_desired")}
OUTPUTS = {"gps_x": ("gps", "x"), "gps_y": ("gps", "y"), "gps_vel_east": ("gps", "vel_east"),
           "gps_vel_north": ("gps", "vel_north"), "fix_valid": ("gps", "fix_valid"), "fix_age": ("gps", "fix_age"),
           "steer_angle_measured": ("steering", "steer_angle_measured"), "yaw_rate": ("tractor", "yaw_rate"),
           "speed_measured": ("drivetrain", "speed"), "x_cg": ("tractor", "x_cg"), "y_cg": ("tractor", "y_cg"),
           "heading": ("tractor", "heading")}


def resolve_study(name: str) -> Path:
    """An absolute path, a path from the working folder, or a file of the project's studies/."""
    path = Path(name)
    if path.is_absolute() or path.exists():
        return path
    return STUDIES / name


class SimulatedTractor(Component):
    sampled = False
    variables = TRACTOR_PORTS + (
        par("study", "", "tractor_side.toml", "tractor-side study (path, or a file of studies/)"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        from orchestrator.build import build_system
        from orchestrator.engine import Simulation
        from orchestrator.study import StudyError, load_study

        path = resolve_study(self.p["study"])
        seed = int(self.rng.integers(0, 2**31 - 1))
        try:
            study = load_study(path, [f"study.seed={seed}", f"study.start_time={t0}"])
            system = build_system(study)
        except StudyError as exc:
            self.require(False, f"tractor-side study: {exc}")
        for role in {c for c, _ in (*INPUTS.values(), *OUTPUTS.values())}:
            self.require(role in system.nodes, f"tractor-side study {path} needs a component named {role!r}")
        sub = study.study.base_step
        self.substeps = int(round(dt / sub))
        self.require(abs(self.substeps * sub - dt) < 1e-9 and self.substeps >= 1,
                     f"step {dt} s must be a multiple of the tractor-side base step {sub} s")
        self.sim = Simulation(system, record=False)
        self.nodes = system.nodes
        self.fix_latency = float(system.nodes["gps"].component.p.get("latency", 0.0))   # fix_age of a fresh fix
        self.sim.start()
        self._publish()

    def _publish(self) -> None:
        y = self.y
        for port, (comp, name) in OUTPUTS.items():
            y[port] = self.nodes[comp].component.y[name]
        y["fix_quality"] = RTK_FIXED if y["fix_age"] <= self.fix_latency + 1e-9 else 0.0

    def step(self, t: float, dt: float) -> None:
        for port, (comp, name) in INPUTS.items():
            self.nodes[comp].component.u[name] = self.u[port]
        self.sim.advance(self.sim.k + self.substeps)
        self._publish()

    def terminate(self) -> None:
        if getattr(self, "sim", None) is not None:
            self.sim.terminate()


COMPONENT = SimulatedTractor
