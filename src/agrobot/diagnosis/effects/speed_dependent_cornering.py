"""The tyres' cornering stiffness changes with speed: one model does not fit every speed."""
from ..effect import Effect, Parameter


class SpeedDependentCornering(Effect):
    id = "speed_dependent_cornering"
    subsystem = "yaw (tyre cornering stiffness)"
    stages = ("yaw",)
    parameters = (Parameter("cornering_speed_slope", "s/m", 0.1, -0.35, 0.8, "1/(m/s)", 1.0, (-1.0, 2.0)),)
    starts = ((0.0,), (-0.2,), (0.3,))
    enters = {"yaw.speed_slope": "cornering_speed_slope",
              "yaw.reference_speed": "cornering_reference_speed"}
    threshold = "|k| >= 0.08 per m/s at a 2 m/s reference speed (0.16 / v_ref in general: the same relative change)"
    hypothesis = "the tyres' cornering stiffness changes with speed: one model does not fit every speed"
    experiment = ("the same steering multisine at 1, 2 and 3 m/s: only a speed-dependent "
                  "stiffness changes the yaw gain's shape with speed")
    imitated_by = ("scale_disagreement",)

    def baseline(self, study):
        p = study.parameters("yaw_plant")
        return {"cornering_speed_slope": p["cornering_speed_slope"],
                "cornering_reference_speed": p["cornering_reference_speed"]}

    def material(self, fitted, base):
        """8 % of stiffness per 1 m/s at the tractor's 2 m/s; at a car's 20 m/s, per 10 m/s."""
        k = 0.08 * 2.0 / max(base["cornering_reference_speed"], 0.5)
        return abs(fitted["cornering_speed_slope"] - base["cornering_speed_slope"]) >= k

    def options(self, fitted, base, study):
        return [("yaw_plant", "cornering_speed_slope", fitted["cornering_speed_slope"]),
                ("yaw_plant", "cornering_reference_speed", base["cornering_reference_speed"])]
