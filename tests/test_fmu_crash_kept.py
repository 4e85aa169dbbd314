"""An FMU kept in this process (``isolate_fmus = false``) that crashes with a segmentation fault
ends the process with no Python code run after it; what the run recorded until then is kept all the
same: while a binary is loaded in-process the signal blocks also go, every SPILL_EVERY_S, to an
Arrow IPC stream in the run's staging folder (atomic_files.SignalWriter.spill), and the fatal
signal's dump names that file; the next run into the same ``--out`` moves it to ``OUT.failed``. Truth: the misbehaving FMU's output x equals t until it crashes in
doStep at its fail_time; paced in real time (0.1 s of wall time a step), the stream holds every row
before the crash but those of the last advance (SPILL_EVERY_S, at most two steps here)."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from agrobot.orchestrator.atomic_files import read_partial
from tests.fmu_build import build_test_fmu
from tests.test_fmu_isolation import FAIL_TIME as ISOLATED_FAIL
from tests.test_fmu_isolation import STEP
from tests.test_fmu_isolation import STUDY as ISOLATED

ROOT = Path(__file__).resolve().parent.parent
FAIL_TIME = 1.5
STUDY = ISOLATED.format(mode=1, timeout=60.0).replace("isolate_fmus = true", "isolate_fmus = false\nrealtime = true") \
    .replace('signals_format = "csv"\n', "").replace(f"fail_time = {ISOLATED_FAIL}", f"fail_time = {FAIL_TIME}")

@pytest.mark.slow
def test_a_segfault_in_process_keeps_the_signals_recorded_until_it_and_names_where(tmp_path):
    build_test_fmu("misbehaving", tmp_path)
    study = tmp_path / "crashing.toml"
    study.write_text(STUDY)
    assert "isolate_fmus = false" in STUDY and f"fail_time = {FAIL_TIME}" in STUDY and "parquet" not in STUDY
    done = subprocess.run([sys.executable, "-m", "agrobot", "run", str(study), "--out", str(tmp_path / "out"),
                           "--no-progress", "--engine", "python", "--no-plots"], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)
    assert done.returncode != 0 and "Segmentation fault" in done.stderr, done.stderr
    assert "FMU component 'm' (misbehaving.fmu): doStep" in done.stderr, done.stderr
    named = re.search(r"the signals recorded until the crash: (\S+\.partial\.arrows) \(", done.stderr)
    assert named, done.stderr
    frame = read_partial(Path(named.group(1)))
    rows = round(FAIL_TIME / STEP)                 # the rows t = 0 .. FAIL_TIME - STEP were whole
    assert rows - 3 <= len(frame) <= rows, list(frame["t"])
    assert np.allclose(frame["t"], np.arange(len(frame)) * STEP, atol=1e-12), list(frame["t"])
    assert np.abs(frame["m.x"] - frame["t"]).max() < 1e-12
    assert frame.attrs["units"]["t"] == "s"
    # the next run into the same --out keeps the crashed run's staging folder as OUT.failed
    again = subprocess.run(done.args, capture_output=True, text=True, timeout=120, cwd=ROOT)
    kept = tmp_path / "out.failed" / "signals.partial.arrows"
    assert f"the signals recorded until an earlier run crashed are kept in {kept.parent}" in again.stderr, again.stderr
    assert read_partial(kept).equals(frame)
