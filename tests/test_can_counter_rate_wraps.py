"""rate() of a CAN counter: a DBC signal has a width (its bit length), so a wheel-tick counter
that rolls over at 2^bits (times the signal's scale, in its physical unit) is unwrapped as an
integer stored in a file of fixed width is (measurements.signal_expressions.counter_rate)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.measurements.raw_can import series
from agrobot.measurements.signal_expressions import evaluate, parse_signal

DBC = '''VERSION ""
BU_: ECU
BO_ 5 wheel: 8 ECU
 SG_ Ticks : 0|8@1+ (1,0) [0|255] "" ECU
 SG_ Half : 8|16@1+ (0.5,0) [0|32767.5] "" ECU
'''


def _frames(per_second: float, scale: float, bits: int, name: str) -> dict:
    """A 20 Hz wheel message whose counter of ``bits`` (physical step ``scale``) counts
    ``per_second`` physical units a second, rolling over at 2^bits raw steps."""
    t = np.arange(0.0, 30.0, 0.05)
    raw = np.floor(t * per_second / scale).astype(int) % 2 ** bits
    return {"wheel": pd.DataFrame({"t": t, name: raw * scale})}


def test_a_dbc_counter_that_rolls_over_gives_a_steady_rate():
    import cantools

    db = cantools.database.load_string(DBC)
    for name, scale, bits, per_second in (("Ticks", 1.0, 8, 400.0), ("Half", 0.5, 16, 9000.0)):
        frames = _frames(per_second, scale, bits, name)
        counter = series(db, frames, f"wheel.{name}")
        assert np.diff(counter.values).min() < 0          # it rolls over within the log
        spec = parse_signal(f"v=rate(wheel.{name})*0.01[m/s]")
        t, v, how = evaluate(spec, {f"wheel.{name}": counter}, "drive.log")
        assert np.all(np.abs(v - per_second * 0.01) < 2 * scale / 0.05 * 0.01 + 1e-9), (name, v.min(), v.max())
        assert "unwrapped modulo" in how
