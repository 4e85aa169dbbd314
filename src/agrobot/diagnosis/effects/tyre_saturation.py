"""The tyres saturate: in hard turns the lateral force falls behind C alpha.

Simplified Magic Formula per axle (components.models.tyre): F = mu F_z sin(C atan(B alpha)),
B = C_alpha / (C mu F_z), with the friction mu and the shape factor C fitted; the cornering
stiffnesses stay the baseline's refitted ones (the small-slip slope). The linear tyre is mu = inf.
"""
import math

from agrobot.components.models.tyre import SHAPE_BOUNDS, force_limit_share, linear_share_limit
from agrobot.components.models.yaw_dynamics import GRAVITY

from ..effect import Effect, Parameter

LATERAL_KEY = "log_lateral_acceleration_p99"     # the log's 99th percentile of |v r| [m/s2], set by the selection
CARRIED = 1.1        # the tyres' force limit may fall this far short of the log's |v r| (transients, gyro noise)


def friction_text(saturation: dict) -> str:
    """Identify's friction as a reader should take it: "at least" where it ended on the class's top;
    the front's, with the rear's ratio to it, where identify fitted one per axle (axle_friction)."""
    ratio = saturation.get("friction_ratio", 1.0)
    axle = f" front, rear / front {ratio:.3g}" if ratio != 1.0 else ""
    return ("at least " if saturation.get("friction_at_least") else "") + f"{saturation['friction']:.3g}{axle}"


class TyreSaturation(Effect):
    id = "tyre_saturation"
    subsystem = "yaw (tyres: lateral force saturation, simplified Magic Formula)"
    stages = ("yaw",)
    parameters = (Parameter("tyre_friction", "1", 0.3, 0.1, 2.0, limit=(0.05, 3.0)), Parameter("tyre_shape", "1", 0.3, *SHAPE_BOUNDS))
    starts = ((1.0, 1.3), (0.3, 1.3))
    enters = {"yaw.friction": "tyre_friction", "yaw.shape": "tyre_shape"}
    secondary = ("tyre_shape",)
    at_least = ("tyre_friction",)       # on its upper bound: the turns bend the tyre curve but reach no peak
    undecided = {"tyre_shape": "the log does not show where the tyres' force ends (on the lower bound a curve "
                               "without a peak bending from the smallest slip, on the upper one a sharp peak); the "
                               "friction fitted with it is then not the tyres' (for C < 1 the force reaches only mu "
                               "sin(C pi / 2)), and a yaw gain that falls with |a_y| (a steering map, understeer) bends "
                               "the same way"}
    threshold = ("the linear range it leaves, |a_y| < mu g F/D at 95 % of the linear force, ends below the log's "
                 "99th percentile of |a_y|: the log drives into the saturation")
    hypothesis = ("the tyres saturate: in hard turns the lateral force falls behind C alpha, and the yaw rate "
                  "with it")
    experiment = ("steady turns at rising speed (a ramp of lateral acceleration to the limit): saturation caps "
                  "a_y near mu g, a stiffness or a steering gain does not")
    imitated_by = ("scale_disagreement",)

    def baseline(self, study):
        p = study.parameters("yaw_plant")
        mu = float(p.get("tyre_friction") or 0.0)
        return {"tyre_friction": mu if mu > 0 else math.inf, "tyre_shape": float(p.get("tyre_shape") or 1.3)}

    def material(self, fitted, base):
        if not math.isfinite(fitted["tyre_friction"]):
            return False
        limit = fitted["tyre_friction"] * GRAVITY * linear_share_limit(fitted["tyre_shape"])
        return limit < base.get(LATERAL_KEY, 0.0)

    def contradicts(self, fitted, base):
        """Tyres that cannot carry the log's turns are not its tyres: their force limit mu g x the
        shape's share of it (force_limit_share) below the log's 99th percentile of |v r| / CARRIED
        is a yaw gain that falls with |a_y| (a steering map, understeer) read as a tyre curve."""
        mu = fitted["tyre_friction"]
        if not math.isfinite(mu):
            return []
        limit, turns = mu * GRAVITY * force_limit_share(fitted["tyre_shape"]), base.get(LATERAL_KEY, 0.0)
        if limit >= turns / CARRIED:
            return []
        return [f"the fitted tyres carry at most {limit:.3g} m/s2 (mu {mu:.3g} x {force_limit_share(fitted['tyre_shape']):.2f} "
                f"of it at shape {fitted['tyre_shape']:.2f}), less than the {turns:.3g} m/s2 the log turns at (99th "
                f"percentile of |v r|): not the tyres' limit but a yaw gain falling with |a_y| (a steering map, understeer)"]

    def options(self, fitted, base, study):
        return [("yaw_plant", "tyre_friction", fitted["tyre_friction"]),
                ("yaw_plant", "tyre_shape", fitted["tyre_shape"])]

    def plausibility(self, values, ctx):
        """The friction the force reaches, mu x the shape's share of it, is within the class's range."""
        mu = values.get("tyre_friction", 0.0) * force_limit_share(values.get("tyre_shape", 1.3))
        hi = ctx.vehicle.friction_range[1]
        if mu > hi:
            return [f"a friction of {mu:.2f} is above what tyres give on this vehicle's ground "
                    f"({hi:g} for a {ctx.vehicle.kind or 'vehicle'}): the lateral acceleration is overstated (a speed or "
                    f"gyro scale factor) or the mass and inertia are not this vehicle's"]
        return []

    def display(self, fitted):
        return {"tyre_friction [-]": fitted["tyre_friction"], "tyre_shape [-]": fitted["tyre_shape"]}
