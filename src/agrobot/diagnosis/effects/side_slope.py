"""The field is tilted: gravity pulls sideways, by an amount that follows the heading.

Fitted as the lateral-acceleration components (s_east, s_north) = g sin(phi) (cos, sin)(psi_d),
which enter the yaw model linearly; reported and set as slope angle phi and fall-line azimuth psi_d.
"""
import math

from agrobot.components.models.yaw_dynamics import GRAVITY

from ..effect import Effect, Parameter
from ..plausibility import slope

DEG = math.pi / 180.0


def slope_angle_and_heading(v) -> tuple[float, float]:
    """(slope angle, fall-line azimuth) from the lateral-acceleration components g sin(phi) (cos, sin)(psi_d)."""
    mag = math.hypot(v["slope_east"], v["slope_north"])
    return math.asin(min(mag / GRAVITY, 1.0)), math.atan2(v["slope_north"], v["slope_east"])


class SideSlope(Effect):
    id = "side_slope"
    subsystem = "yaw (terrain: a side slope)"
    stages = ("yaw",)
    needs = ("x", "y")            # the heading, from the GPS course, resolves the fall line
    parameters = (Parameter("slope_east", "m/s2", 0.5, -3.0, 3.0, limit=(-4.9, 4.9)),
                  Parameter("slope_north", "m/s2", 0.5, -3.0, 3.0, limit=(-4.9, 4.9)))
    starts = ((0.0, 0.0),)
    enters = {"yaw.slope_east": "slope_east", "yaw.slope_north": "slope_north"}
    threshold = "slope >= 1.5 deg"
    hypothesis = "the field is tilted: gravity pulls sideways, by an amount that follows the heading"
    experiment = "the same straight line driven both ways: a slope's pull reverses with the heading"

    def baseline(self, study):
        p = study.parameters("yaw_plant")
        g_sin = GRAVITY * math.sin(p["slope_angle"])
        return {"slope_east": g_sin * math.cos(p["slope_downhill_heading"]),
                "slope_north": g_sin * math.sin(p["slope_downhill_heading"])}

    def material(self, fitted, base):
        return slope_angle_and_heading(fitted)[0] >= 1.5 * DEG

    def options(self, fitted, base, study):
        phi, psi_d = slope_angle_and_heading(fitted)
        return [("yaw_plant", "slope_angle", phi), ("yaw_plant", "slope_downhill_heading", psi_d)]

    def plausibility(self, values, ctx):
        """A slope no ground of the class has is a lateral pull of another cause."""
        if "slope_east" not in values or "slope_north" not in values:
            return []
        return slope(slope_angle_and_heading(values)[0], ctx.vehicle)

    def display(self, fitted):
        phi, psi_d = slope_angle_and_heading(fitted)
        return {"slope_angle [deg]": math.degrees(phi), "slope_downhill_heading [deg]": math.degrees(psi_d)}
