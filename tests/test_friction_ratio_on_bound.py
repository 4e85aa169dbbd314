"""A rear / front friction ratio that ends on its bound is not kept, however much it lowers the BIC:
a value on a bound is never concluded; one inside its bounds that lowers the BIC as much is kept.
The rule is exercised through identification.axle_friction.axle_friction_fit with fits built here
(their RSS set so that dBIC = n_eff ln(RSS_b / RSS_s) + ln n_eff is about -60)."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.estimation import FitResult, Parameter
from agrobot.identification.axle_friction import RATIO_BOUNDS, axle_friction_fit

FRICTION = Parameter("friction", "1", 0.1, 0.3, 1.5, meaning="tyre friction")


def _result(free, values, rss):
    return FitResult(values=values, free=tuple(free), cov=np.eye(len(free)) * 1e-4, rss={"yaw_rate": rss},
                     n={"yaw_rate": 2000}, n_eff={"yaw_rate": 400.0})


@pytest.mark.parametrize("rho, kept", [(RATIO_BOUNDS[0], False), (0.8, True), (RATIO_BOUNDS[1], False)])
def test_a_ratio_on_its_bound_is_not_kept(rho, kept):
    single = _result([FRICTION], {"friction": 1.0, "c_f": 8.0, "c_r": 9.0}, rss=1.0)
    fit = lambda free, start, n: _result(free, {**start, "friction_ratio": rho}, rss=0.85)     # noqa: E731
    gain = lambda free, start, added: (1.0, 0.2)                                                # noqa: E731
    notes: list[str] = []
    chosen, free = axle_friction_fit(fit, gain, single, [FRICTION], notes)
    dbic = chosen.bic_at(400.0) - single.bic
    assert (("friction_ratio" in chosen.values) == kept) and (len(free) == (2 if kept else 1))
    assert kept or (dbic == 0.0 and "ran to its bound" in notes[-1])
