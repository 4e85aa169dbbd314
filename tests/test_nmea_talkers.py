"""A receiver writing each epoch's GGA from two talkers (GN, its combined solution, and GP, a
GPS-only one 0.5 m off): one solution per epoch, the combined one whichever comes first, and a
note naming both talkers and the count of epochs."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.api import convert
from harness.quirk_recordings import compose


@pytest.mark.parametrize("seed", [3, 4])          # GP first, GN first
def test_the_combined_solution_is_kept_and_the_talkers_named(tmp_path, seed):
    truth = compose(seed, tmp_path, classes=["two_talkers"], layout="nmea", machine="utility")
    planted = truth["planted"]["two_talkers"]
    rec = convert(tmp_path)
    said = [n for n in rec.report["notes"] if "two talkers" in n]
    assert len(said) == 1 and f"on {planted['readable']} epochs" in said[0] and "GN's" in said[0]
    assert f"({planted['talkers'][0]} first" in said[0]
    xy = rec.log[["x", "y"]].to_numpy(float)
    noise = float(np.median(np.hypot(*np.diff(xy, 2, axis=0).T)))
    assert noise < 0.05 < planted["gp_noise_m"]          # GN's centimetres, not GP's decimetres
    assert not [n for n in rec.report["notes"] if "repeat the time" in n]    # not an epoch written twice
