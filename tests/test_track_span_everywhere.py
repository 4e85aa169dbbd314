"""One rule for the speed and the course of the GPS track (measurements.log.track_chords): chords that
span the positions' updates wherever the track is read, not only in the unit check. A receiver that
updates every 4 s, held on a 10 Hz grid, read on 1 s chords stands still three rows in four and
jumps at 4.8 m/s on the fourth."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.log import speed_estimate, yaw_rate_in_radians
from tests.test_track_span import held_log


@pytest.mark.parametrize("update_s", [0.1, 4.0, 8.0])
def test_the_speed_from_the_track_is_the_vehicles_with_slow_updates(update_s):
    """Truth: 1.2 m/s all along (held_log); the log has no wheel speed and no receiver speed."""
    frame = held_log(update_s).drop(columns=["v"])
    speed, source = speed_estimate(frame)
    assert source == "track"
    inside = speed[200:-200]                          # away from the ends the chords do not reach
    assert np.median(inside) == pytest.approx(1.2, rel=0.05)
    assert np.percentile(inside, 90) < 1.5, np.percentile(inside, [10, 50, 90])


def test_a_yaw_rate_in_radians_turns_with_a_track_of_slow_updates():
    """Truth: the yaw rate is r = v / 40 rad/s, the track's course turns at that rate."""
    why = yaw_rate_in_radians(held_log(4.0))
    assert why is not None and why.startswith("integrated, it turns"), why
