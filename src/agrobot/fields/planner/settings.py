"""The planner's settings: the implement, the tractor's turning limits, speeds, the order; every
value checked (finite, in range) before any work, the message naming the setting and its value."""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

from ..field import FieldError
from .curves import Limits
from .objectives import OBJECTIVES

POSITIVE = ("working_width", "turn_radius", "wheelbase", "steer_rate", "work_speed", "turn_speed", "acceleration")
NON_NEGATIVE = ("headland_passes", "hitch_offset", "drawbar", "half_width", "settle", "swath_extension", "max_swaths",
                "overlap", "route_seconds")
ORDERS = ("auto", "boustrophedon", "skip", "optimised")
HEADLAND_ORDERS = ("last", "first")
CORNERS = ("tight", "parallel")
PATTERNS = ("straight", "curved")


@dataclass(frozen=True)
class Settings:
    working_width: float = 3.0            # m
    headland_passes: int = 0              # 0: as many as the turns need
    driving_angle: float | None = None    # rad, east = 0, counter-clockwise; None: by the angle objective
    guidance_line: str = ""               # else along this guidance line of the field ("*": its first)
    swath_pattern: str = "straight"       # straight; curved: offsets of the guidance line (a curve), fields.planner.curved_swaths
    angle_objective: str = "fewest_swaths"  # how the driving angle is chosen (fields.planner.objectives)
    turn_radius: float = 4.0              # m: the tractor's smallest (well above its 45 deg lock)
    wheelbase: float = 1.4                # m
    steer_rate: float = math.radians(30)  # rad/s the turns may ask (the hydraulics do 60)
    work_speed: float = 2.0               # m/s
    turn_speed: float = 1.0               # m/s
    acceleration: float = 0.5             # m/s^2
    overlap: float = 0.05                 # m between adjacent passes
    order: str = "auto"                   # auto, boustrophedon, skip, optimised (OR-tools: fields.planner.optimise)
    route_seconds: float = 0.0            # optimised order: 0 a bounded greedy descent (fields.planner.optimise.improvements); else guided local search this long
    half_width: float = 0.8               # m: the tractor's, kept inside the boundary
    hitch_offset: float = 0.6             # m behind the rear axle
    drawbar: float = 2.5                  # m hitch to implement axle (0: a mounted implement)
    headland_work: bool = True            # drive the headland passes
    headland_order: str = "last"          # last: after the swaths (innermost out); first: before them (outermost in)
    leftover_passes: bool = True          # work what the route leaves by passes of their own (fields.planner.leftover_passes)
    headland_corners: str = "parallel"    # parallel: pass k rounds its corners at R + (n - 1 - k) w; tight: every pass at R
    settle: float = 5.0                   # m driven straight before a swath beyond the implement's length
    swath_extension: float = 0.1          # m each swath works on beyond its strip's reach (lift and drop margin)
    max_swaths: int = 0                   # 0: all; else the first N (a section of a field, for tests)
    start_point: tuple[float, float] | None = None   # m, east/north of the field's origin: the route starts here
    end_point: tuple[float, float] | None = None     # and ends here (None: where the last pass ends)

    def check(self, where: str, names: dict[str, str] | None = None) -> None:
        """Refuse a value that is not finite or out of range; ``names``: how the caller calls each
        setting (a command-line option), for the message."""
        def name(key: str) -> str:
            return (names or {}).get(key, key)

        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float) and not math.isfinite(value):
                raise FieldError(f"{where}: {name(f.name)} = {value}: expected a finite number")
            if isinstance(value, tuple) and (len(value) != 2 or not all(math.isfinite(v) for v in value)):
                raise FieldError(f"{where}: {name(f.name)} = {value}: expected two finite numbers (east, north [m])")
        for key in POSITIVE:
            if not getattr(self, key) > 0:
                raise FieldError(f"{where}: {name(key)} = {getattr(self, key)}: expected a positive number")
        for key in NON_NEGATIVE:
            if not getattr(self, key) >= 0:
                raise FieldError(f"{where}: {name(key)} = {getattr(self, key)}: expected zero or more")
        if self.order not in ORDERS:
            raise FieldError(f"{where}: {name('order')} = {self.order!r}: expected {', '.join(ORDERS)}")
        for key, allowed in (("headland_order", HEADLAND_ORDERS), ("headland_corners", CORNERS),
                             ("swath_pattern", PATTERNS)):
            if getattr(self, key) not in allowed:
                raise FieldError(f"{where}: {name(key)} = {getattr(self, key)!r}: expected {' or '.join(allowed)}")
        if self.angle_objective not in OBJECTIVES:
            raise FieldError(f"{where}: {name('angle_objective')} = {self.angle_objective!r}: expected one of "
                             f"{', '.join(OBJECTIVES)}")
        if not self.overlap < 0.5 * self.working_width:
            raise FieldError(f"{where}: {name('working_width')} = {self.working_width:g} m with {name('overlap')} = "
                             f"{self.overlap:g} m between passes: expected an overlap under half the working width")

    @property
    def spacing(self) -> float:
        """Distance between adjacent swaths: the working width less the overlap."""
        return self.working_width - self.overlap

    @property
    def limits(self) -> Limits:
        """The turns' curvature and sharpness limits (at the turn speed)."""
        return Limits.of(self.turn_radius, self.wheelbase, self.steer_rate, self.turn_speed)

    @property
    def lead(self) -> float:
        """Straight run before and after each swath: the implement (hitch + drawbar behind the
        rear axle) is on the line, and the loop has settled, when the work starts."""
        return self.hitch_offset + self.drawbar + self.settle

    @property
    def implement_radius(self) -> float:
        """R_i: the implement's steady radius when the rear axle runs on R (hitch c behind, drawbar L)."""
        r2 = self.turn_radius ** 2 + self.hitch_offset ** 2 - self.drawbar ** 2
        return math.sqrt(max(r2, 0.25 * self.turn_radius ** 2))
