"""A CSV written in a European locale: fields separated by ';', numbers with a decimal comma. Its
values are read as the numbers they are, and the note counts the columns that hold one; a ';' table
with decimal points is read as before, with no such note."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.api import convert

START = 1.7e9


def _table(folder, comma: bool) -> dict:
    """A 20 Hz log (t, v, yaw_rate, delta, delta_cmd, and an integer fix count); truth per column."""
    folder.mkdir()
    t = np.arange(0.0, 30.0, 0.05)
    truth = {"v": 1.5 + 0.2 * np.sin(0.3 * t), "yaw_rate": 0.1 * np.sin(0.5 * t), "delta": 0.05 * np.sin(0.5 * t),
             "delta_cmd": 0.05 * np.sin(0.5 * t + 0.1)}
    lines = ["t;" + ";".join(truth) + ";satellites"]
    for i, x in enumerate(t):
        cells = [f"{START + x:.3f}"] + [f"{truth[c][i]:.6f}" for c in truth]
        if comma:
            cells = [c.replace(".", ",") for c in cells]
        lines.append(";".join(cells) + ";14")
    (folder / "log.csv").write_text("\n".join(lines) + "\n")
    return {"t": t, **truth}


@pytest.mark.parametrize("comma", [True, False])
def test_decimal_commas_are_read_as_the_numbers_they_are(tmp_path, comma):
    truth = _table(tmp_path / "rec", comma)
    rec = convert(tmp_path / "rec")
    log = rec.log
    for c in ("v", "yaw_rate", "delta", "delta_cmd"):
        assert np.max(np.abs(log[c].to_numpy(float) - np.interp(log["t"].to_numpy(float), truth["t"], truth[c]))) < 1e-4
    said = [n for n in rec.report["notes"] if "decimal comma" in n]
    assert len(said) == int(comma)
    if comma:
        assert "in 5 columns" in said[0]          # t and the four signals; the satellites' integers hold none
