"""What a fitted value is judged against: the vehicle it would be a property of, and the rules more
than one effect shares.

Each effect judges its own values (``Effect.plausibility``, diagnosis.effect); the verdict calls the
rule of every judged effect in a loop (diagnosis.verdict). A value that no vehicle of the class has
is not a mounting, an actuator or a tyre but a sign of something else, and the rule says what.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping

if TYPE_CHECKING:
    from agrobot.identification.vehicle import Vehicle

CALIBRATION = (0.7, 1.4)      # a scale factor or a gain errs inside this; outside it is a unit or a channel


@dataclass(frozen=True)
class VehicleContext:
    """The vehicle a value is judged against: its ``[vehicle]`` table, the wheelbase and the rear
    axle's distance from the centre of gravity ``l_r`` [m], and the log's median moving speed [m/s]."""

    vehicle: Vehicle
    wheelbase: float
    l_r: float
    speed: float

    def outline(self) -> tuple[tuple[float, float], tuple[float, float], str]:
        """((forward lo, hi), (left lo, hi)) of the vehicle from its rear axle, and how it is known:
        the [vehicle] table's length and width, else a wheelbase-sized box (overhangs of half a
        wheelbase, a width of one)."""
        arm, wb = self.vehicle.lever_arm_bounds(), self.wheelbase
        if arm:
            return arm[0], arm[1], f"its outline ({self.vehicle.length:g} m long, {self.vehicle.width:g} m wide)"
        return ((-0.5 * wb, 1.5 * wb), (-0.5 * wb, 0.5 * wb),
                f"a {wb:.3g} m wheelbase with half a wheelbase of overhang (the study has no [vehicle] length)")


def reference_point(values: Mapping[str, float], ctx: VehicleContext) -> list[str]:
    """The point the positions are put at (the antenna's place plus a reference point's offset, each
    0 where the effect has no such parameter) must lie inside the outline; outside it, the clock
    offset that moves the track as far is |forward - l_r| / speed."""
    fwd = values.get("antenna_forward", 0.0) + values.get("position_forward", 0.0)
    left = values.get("antenna_left", 0.0) + values.get("position_left", 0.0)
    (f_lo, f_hi), (l_lo, l_hi), how = ctx.outline()
    if f_lo <= fwd <= f_hi and l_lo <= left <= l_hi:
        return []
    speed = ctx.speed
    lag = abs(fwd - ctx.l_r) / speed if speed > 0 else math.nan
    return [f"the point it puts the positions at, {fwd:.2f} m ahead of the rear axle and {left:.2f} m left, "
            f"lies outside {how}: no antenna is mounted there; at the log's median speed "
            f"{speed:.2g} m/s a clock offset of about {lag:.2g} s between the positions and the gyro "
            f"moves the track as far, or the positions are an estimate of another frame"]


def scale_factor(what: str, s: float | None) -> list[str]:
    """A sensor's scale factor outside ``CALIBRATION`` is no sensor error but a unit or a channel."""
    lo, hi = CALIBRATION
    if s is None or lo <= s <= hi:
        return []
    return [f"a {what} scale factor of {s:.3g} is no sensor error: a unit or a channel is wrong"]
