"""A log that cannot be identified lists its columns as logged: a yaw rate the project derived from
the positions' course is named as derived, not as a gyro the log has."""
import numpy as np
import pandas as pd
import pytest

from agrobot.identification.ordinary_driving import identify_driving
from agrobot.measurements.log import LogError


def circle_positions(speed=2.0, radius=20.0, rate=10.0, seconds=60.0, seed=3):
    """Positions of a machine driving a circle, with 5 mm of white noise: no steering, no speed."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / rate)
    a = speed * t / radius
    return pd.DataFrame({"t": t, "x": radius * np.sin(a) + rng.normal(0, 0.005, t.size),
                         "y": radius * (1 - np.cos(a)) + rng.normal(0, 0.005, t.size)})


def test_a_positions_only_log_names_its_yaw_rate_as_derived():
    with pytest.raises(LogError) as err:
        identify_driving(circle_positions(), "circle.csv")
    text = str(err.value)
    assert "no delta or delta_cmd" in text and "no v" in text
    assert "yaw_rate (derived from the GNSS course, not logged)" in text, text


def test_a_logged_gyro_is_listed_as_it_is():
    frame = circle_positions()
    frame["yaw_rate"] = 0.1
    with pytest.raises(LogError) as err:
        identify_driving(frame, "circle.csv")
    assert "derived" not in str(err.value) and "yaw_rate" in str(err.value)
