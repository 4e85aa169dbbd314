"""Direction (measurements.direction): a small Ackermann machine (harness.held_channels) backs up
for 9-10 s while its speed stays positive. The audit must name the stretch with its times (the
truth's), refuse the unsigned speed with the remedy, sign it with --sign-speed, and pass a signed
speed or a declared direction channel."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal
from harness.held_channels import BACKWARD, L, signals, truth, write_machine_log

REVERSE = (40.0, 50.0)
SECONDS = 75.0
ROW0 = 0.5          # the first row's time in the drive (harness.held_channels)


def options(signal_list, **kw) -> ImportOptions:
    return ImportOptions(signals=[parse_signal(s) for s in signal_list], wheelbase=L, **kw)


def backing_up() -> tuple[float, float]:
    """The truth's stretch moving backwards faster than 0.2 m/s, s from the first row."""
    drive = truth(SECONDS, 3, REVERSE)
    back = drive["t"][drive["v"] < -0.2]
    return float(back.min()) - ROW0, float(back.max()) - ROW0


@pytest.fixture(scope="module")
def unsigned(tmp_path_factory):
    return write_machine_log(tmp_path_factory.mktemp("rev") / "rec", seconds=SECONDS, reverse=REVERSE)


def test_an_unsigned_speed_while_reversing_is_refused_with_the_stretch_and_the_remedy(unsigned):
    a, b = backing_up()
    with pytest.raises(LogError) as err:
        import_recording(unsigned, options(signals()))
    text = str(err.value)
    assert "reverses at" in text and "--sign-speed" in text and "v stays positive" in text
    start, end = (float(x) for x in text.split("reverses at ")[1].split(" s")[0].split("-"))
    assert abs(start - a) < 0.5 and abs(end - b) < 0.5, (start, end, a, b)


@pytest.mark.parametrize("evidence", ["heading", "steering"])
def test_sign_speed_makes_it_negative_where_the_truth_reverses(unsigned, evidence):
    chosen = [s for s in signals() if evidence == "heading" or not s.startswith("heading")]
    frame, report = import_recording(unsigned, options(chosen, sign_speed=True))
    rev = [f for f in frame.attrs["audit"] if f["kind"] == "reversing"]
    assert len(rev) == 1 and rev[0]["resolved"] and "--sign-speed" in rev[0]["meaning"]
    drive = truth(SECONDS, 3, REVERSE)
    t = frame["t"].to_numpy() + report["used"]["start"] + ROW0
    true = np.interp(t, drive["t"], drive["v"])
    moving = np.abs(true) > 0.15
    assert np.mean(np.sign(frame["v"].to_numpy()[moving]) == np.sign(true[moving])) > 0.98
    backwards = true < -0.5 * BACKWARD
    assert np.all(frame["v"].to_numpy()[backwards] < 0)


@pytest.mark.parametrize("how", ["signed", "gear"])
def test_a_signed_speed_or_a_direction_channel_passes(tmp_path, how):
    rec = write_machine_log(tmp_path / "rec", seconds=SECONDS, reverse=REVERSE, signed=how == "signed",
                            gear=how == "gear")
    frame, _ = import_recording(rec, options(signals(gear=how == "gear"), sign_speed=how == "gear"))
    rev = [f for f in frame.attrs["audit"] if f["kind"] == "reversing"]
    assert len(rev) == 1 and rev[0]["resolved"]
    assert ("declared direction channel" in rev[0]["meaning"]) == (how == "gear")
    assert frame["v"].min() < -0.5 * BACKWARD


def test_a_forward_drive_names_no_reversing(tmp_path):
    rec = write_machine_log(tmp_path / "rec", seconds=50.0)
    frame, _ = import_recording(rec, options(signals()))
    assert not [f for f in frame.attrs["audit"] if f["kind"] == "reversing"] and frame["v"].min() > 0
