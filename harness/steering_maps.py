"""Steering-map effects: the potentiometer's map from its reading to the road-wheel angle is wrong
and the steering loop closes on the reading, so a log's angles are the reading f(wheels) of the
wheels the vehicle turned (wheels = f^-1(reading)). Drawn magnitudes:

- ``steering_map_gain``: wheels = g x reading, g in 1 +- (0.05-0.30);
- ``steering_map_asymmetry``: wheels = (1 + a) x reading to the left (reading > 0), (1 - a) x reading
  to the right, a in 0.10-0.25 (a 1.13 m against a 1.90 m radius at full lock is a = 0.25);
- ``steering_map_offset``: wheels = reading + o, o = +-(0.03-0.045) rad x the vehicle's steering scale;
- ``steering_map_curve``: wheels = reading (1 + c reading^2), c in 1.5-3 1/rad2.
"""
from __future__ import annotations

import numpy as np

# the catalogue's id of each map effect (an asymmetry has none yet: the name a right diagnosis would give it)
MAP_IDS = {"steering_map_gain": "steering_gain", "steering_map_asymmetry": "steering_asymmetry",
           "steering_map_offset": "steering_offset", "steering_map_curve": "steering_ratio_curve"}


MAP_EFFECTS = ("steering_map_gain", "steering_map_asymmetry", "steering_map_offset", "steering_map_curve")


def draw_map(effect: str, rng: np.random.Generator, steer_scale: float) -> dict:
    sign = 1.0 if rng.random() < 0.5 else -1.0
    u = rng.uniform
    return {"steering_map_gain": {"map_gain": 1.0 + sign * u(0.05, 0.30)},
            "steering_map_asymmetry": {"map_asymmetry": u(0.10, 0.25)},
            "steering_map_offset": {"map_offset": sign * u(0.03, 0.045) * steer_scale},
            "steering_map_curve": {"map_curvature": u(1.5, 3.0)}}[effect]


def reading(wheels: np.ndarray, p: dict) -> np.ndarray:
    """The reading f(wheels) of the wheel angles under the map ``p`` (the inverse of wheels = f^-1)."""
    w = np.asarray(wheels, float)
    if "map_gain" in p:
        return w / p["map_gain"]
    if "map_asymmetry" in p:
        return np.where(w > 0, w / (1 + p["map_asymmetry"]), w / (1 - p["map_asymmetry"]))
    if "map_offset" in p:
        return w - p["map_offset"]
    if "map_curvature" in p:                   # d + c d^3 = w by Newton's method (monotonic: one root)
        c, d = p["map_curvature"], w.copy()
        for _ in range(30):
            d = d - (d + c * d ** 3 - w) / (1.0 + 3.0 * c * d * d)
        return d
    return w


