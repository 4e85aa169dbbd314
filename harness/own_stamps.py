"""A generated log's channels as a recording gives them: each on its own stamps (a lower rate, jittered),
with white noise on its samples, interpolated linearly onto the log's rows as the import does and
kept in frame.attrs["own_samples"] (measurements.runs.OwnSamples)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.measurements.runs import OwnSamples


def own_stamps(t: np.ndarray, hz: float, rng: np.random.Generator, jitter: float = 0.3) -> np.ndarray:
    """Stamps at ``hz`` over the rows ``t``, each moved uniformly by up to ``jitter`` of its interval."""
    n = int((t[-1] - t[0]) * hz) + 1
    return np.clip(t[0] + (np.arange(n) + rng.uniform(-jitter, jitter, n)) / hz, t[0], t[-1])


def on_own_stamps(frame: pd.DataFrame, groups: dict[tuple[str, ...], tuple[float, float]], seed: int = 0
                  ) -> tuple[pd.DataFrame, dict[str, np.ndarray]]:
    """(the log with each group of columns -- (hz, sigma): columns sharing stamps at ``hz`` -- read at its
    stamps (linear between rows) plus white noise of ``sigma`` on each sample, interpolated back onto
    the rows; the noise each column's rows carry)."""
    rng = np.random.default_rng(seed)
    t = frame["t"].to_numpy(float)
    out, own, on_rows = frame.copy(), {}, {}
    for columns, (hz, sigma) in groups.items():
        stamps = own_stamps(t, hz, rng)
        for c in columns:
            noise = sigma * rng.standard_normal(len(stamps))
            values = np.interp(stamps, t, frame[c].to_numpy(float)) + noise
            out[c] = np.interp(t, stamps, values)
            own[c] = (stamps.tolist(), values.tolist())
            on_rows[c] = np.interp(t, stamps, noise)
    out.attrs["own_samples"] = OwnSamples(own)
    return out, on_rows
