"""A tractor plant and a steering hydraulics that have stepped (holding arrays written through
memoryviews, and substep loops generated for their step) pickle and copy, and the copy steps on as
the original does, to the bit, without touching the original's state."""
from __future__ import annotations

import copy
import math
import pickle

from threadpoolctl import threadpool_limits

from agrobot.components.steering_hydraulics import SteeringHydraulics
from agrobot.components.tractor_yaw_plant import TractorYawPlant


def _drive(component, inputs, steps: int, k0: int = 0) -> list[dict]:
    rows = []
    for k in range(k0, k0 + steps):
        component.u.update(inputs(k))
        component.step(k * 0.01, 0.01)
        rows.append(dict(component.y))
    return rows


def _check(make, inputs):
    with threadpool_limits(limits=1, user_api="blas"):
        original = make()
        original.initialize(0.0, 0.01)
        _drive(original, inputs, 30)
        pickled = pickle.loads(pickle.dumps(original))
        copied = copy.deepcopy(original)
        shallow = copy.copy(original)
        shallow.u, shallow.y = dict(original.u), dict(original.y)
        later = [_drive(c, inputs, 40, 30) for c in (pickled, copied, shallow)]
        want = _drive(original, inputs, 40, 30)          # after the copies stepped: its own state kept
    for rows in later:
        assert rows == want


def test_a_stepped_tractor_plant_pickles_and_copies():
    _check(lambda: TractorYawPlant("tractor", {"model": "rlf", "antenna_forward": 0.5}),
           lambda k: {"speed": 2.0, "steer_angle": 0.2 * math.sin(0.05 * k)})


def test_a_stepped_steering_pickles_and_copies():
    # a shallow copy shares the PI object with its original: pickled and deep copies only
    s = SteeringHydraulics("steering", {"quantization_guard": 1})
    s.initialize(0.0, 0.01)
    inputs = lambda k: {"steer_angle_cmd": 0.3 * math.sin(0.05 * k)}       # noqa: E731
    _drive(s, inputs, 30)
    later = [_drive(c, inputs, 40, 30) for c in (pickle.loads(pickle.dumps(s)), copy.deepcopy(s))]
    want = _drive(s, inputs, 40, 30)
    for rows in later:
        assert rows == want
