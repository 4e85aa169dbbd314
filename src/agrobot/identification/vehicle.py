"""The study's ``[vehicle]`` table: what kind of vehicle a log comes from, and the ranges a fitted
parameter may take on it.

    [vehicle]
    class = "scale_car"        # tractor | car | sports_car | truck | scale_car | robot
    wheelbase = 0.32           # m
    length = 0.55              # m, overall
    width = 0.30               # m, overall
    steering = "angle"         # angle (the command is a wheel angle) | torque (an electric steering's
                               # torque) | none (skid-steered: no steering angle)
    drive = "ackermann"        # ackermann | skid | differential (both: identification.skid_steer) | articulated
    steering_ratio = 1.0       # handwheel / road-wheel angle (a recording's CAN handwheel angle)

Ranges a class gives (a fitted value outside them is not a property of such a vehicle): the gyro
bias a gyro of that class can have, the steering offset its angle sensor can have, the slope a road or a field can have, the friction its tyres
can have on their ground; an antenna lever arm must lie inside the vehicle's outline.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

DEG = math.pi / 180.0


class VehicleClass(NamedTuple):
    """The ranges a class of vehicle gives a fitted parameter."""

    gyro_bias: float                # rad/s: the largest zero-rate offset of its gyro
    slope: float                    # rad: the steepest ground it drives on
    friction: tuple[float, float]   # its tyres' friction on their ground
    steer_offset: float             # rad: the largest zero offset of its wheel-angle sensor or linkage
    what: str


# a tractor's guidance gyro is an industrial MEMS part with no ESC learning its offset at standstill
# (a car's CAN yaw rate has that): zero-rate offsets up to about 2 deg/s over temperature; a
# steering angle sensor's zero (a potentiometer's or encoder's) is off a few degrees after a repair
# or a knock, a small machine's cheap linkage more
CLASSES = {
    "tractor": VehicleClass(2.0 * DEG, 15 * DEG, (0.2, 1.2), 3 * DEG,
                            "an agricultural tractor (industrial MEMS gyro, field slopes)"),
    "car": VehicleClass(1.0 * DEG, 7 * DEG, (0.1, 1.3), 2 * DEG,
                        "a road car (automotive-grade gyro, road gradients up to about 12 %)"),
    "sports_car": VehicleClass(1.0 * DEG, 7 * DEG, (0.3, 2.0), 2 * DEG,
                               "a sports or GT car on road-legal or racing tyres (friction up to about 1.6-2 dry)"),
    "truck": VehicleClass(1.0 * DEG, 7 * DEG, (0.1, 1.1), 2 * DEG, "a road truck"),
    "scale_car": VehicleClass(3.0 * DEG, 5 * DEG, (0.2, 1.8), 5 * DEG,
                              "a 1:10 to 1:5 model car (hobby MEMS gyro, indoor floors)"),
    "robot": VehicleClass(3.0 * DEG, 10 * DEG, (0.2, 1.5), 5 * DEG, "a small mobile robot (hobby MEMS gyro)"),
}
STEERING = ("angle", "torque", "none")
DRIVES = ("ackermann", "skid", "differential", "articulated")


class VehicleError(ValueError):
    """The [vehicle] table has a value outside what it may say."""


@dataclass(frozen=True)
class Vehicle:
    """What the tools know of the vehicle (None: the study does not say)."""

    kind: str | None = None              # the table's ``class``
    wheelbase: float | None = None
    length: float | None = None
    width: float | None = None
    steering: str = "angle"
    drive: str = "ackermann"
    steering_ratio: float | None = None
    declared: bool = False               # the study has a [vehicle] table

    @classmethod
    def of(cls, study) -> "Vehicle":
        table = (study.section("vehicle") if study is not None else None) or {}
        return cls.from_table(table, getattr(study, "path", "study"))

    @classmethod
    def from_table(cls, table: dict, where="study") -> "Vehicle":
        kind = table.get("class")
        if kind is not None and kind not in CLASSES:
            raise VehicleError(f"{where}: vehicle.class = {kind!r}; expected one of {sorted(CLASSES)}")
        steering = table.get("steering", "angle")
        if steering not in STEERING:
            raise VehicleError(f"{where}: vehicle.steering = {steering!r}; expected one of {list(STEERING)}")
        drive = table.get("drive", "ackermann")
        if drive not in DRIVES:
            raise VehicleError(f"{where}: vehicle.drive = {drive!r}; expected one of {list(DRIVES)}")
        numbers = {}
        for key in ("wheelbase", "length", "width", "steering_ratio"):
            value = table.get(key)
            if value is not None:
                try:
                    value = float(value)
                except (TypeError, ValueError):
                    raise VehicleError(f"{where}: vehicle.{key} = {value!r}; expected a number") from None
                if not value > 0:
                    raise VehicleError(f"{where}: vehicle.{key} = {value:g}; expected a positive number")
            numbers[key] = value
        return cls(kind, numbers["wheelbase"], numbers["length"], numbers["width"], steering, drive,
                   numbers["steering_ratio"], bool(table))

    @property
    def gyro_bias_bound(self) -> float | None:
        return CLASSES[self.kind].gyro_bias if self.kind else None

    @property
    def steer_offset_bound(self) -> float:
        """The largest steering offset [rad] of the class (5 deg without a class)."""
        return CLASSES[self.kind].steer_offset if self.kind else 5 * DEG

    @property
    def slope_bound(self) -> float | None:
        return CLASSES[self.kind].slope if self.kind else None

    @property
    def friction_range(self) -> tuple[float, float]:
        return CLASSES[self.kind].friction if self.kind else (0.1, 2.0)

    def lever_arm_bounds(self) -> tuple[tuple[float, float], tuple[float, float]] | None:
        """((forward lo, hi), (left lo, hi)) of a point on the vehicle measured from the rear axle:
        within the outline (the rear overhang taken as a quarter of the length)."""
        if self.length is None or self.width is None:
            return None
        return (-0.25 * self.length, self.length), (-0.5 * self.width, 0.5 * self.width)

    def physical_limits(self) -> dict[str, tuple[float, float]]:
        """How far a fitted parameter's range widens when the fit ends on the class's bound: the
        values no vehicle of the class can exceed, beyond which a fit means something else (a
        position reference elsewhere, a clock, a unit). A value between the class's range and this
        limit is fitted, and judged against the class (diagnosis.plausibility)."""
        out = {"yaw_rate_bias": (-10 * DEG, 10 * DEG), "tyre_friction": (0.05, 3.0)}
        if self.slope_bound:
            out["slope_east"] = out["slope_north"] = (-9.81 * math.sin(30 * DEG), 9.81 * math.sin(30 * DEG))
        if self.length is not None and self.width is not None:
            out["antenna_forward"] = (-2.0 * self.length, 3.0 * self.length)
            out["antenna_left"] = (-2.0 * self.width, 2.0 * self.width)
        return out

    def not_applicable(self) -> dict[str, str]:
        """Stages of the single-track (Ackermann, angle-steered) replay that do not apply to this
        vehicle, and why."""
        why = {}
        if self.drive != "ackermann":
            why["yaw"] = (f"the vehicle is {self.drive}-steered (vehicle.drive); the single-track yaw model "
                          f"describes an Ackermann-steered vehicle")
        if self.steering == "none":
            why["steering"] = "the vehicle has no steering angle (vehicle.steering = 'none')"
            why.setdefault("yaw", "the vehicle has no steering angle to drive the yaw model (vehicle.steering = 'none')")
        elif self.steering == "torque":
            why["steering"] = ("the steering is commanded in torque (vehicle.steering = 'torque'): delta_cmd is not "
                               "a wheel angle the steering follows")
        return why
