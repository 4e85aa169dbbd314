"""FMUs that misbehave (built here from tests/fmu_sources/misbehaving: a segmentation fault, exit(3)
or an endless loop in doStep from fail_time on) run in a child process with study.isolate_fmus:
each becomes a named error with the signals up to then kept, Ctrl-C ends a hung run within
seconds; unpacked FMUs and SSPs hold only the entries a run uses, under a cap, and are removed."""
from __future__ import annotations

import gc
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import pandas as pd
import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import RunError, Simulation
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import load_study
from tests.fmu_build import build_test_fmu

ROOT = Path(__file__).resolve().parent.parent
FAIL_TIME, STEP = 0.5, 0.1
STUDY = f"""[study]
name = "bad"
stop_time = 2.0
base_step = {STEP}
seed = 1
signals_format = "csv"
isolate_fmus = true
fmu_timeout = {{timeout}}

[components.m]
type = "misbehaving.fmu"
parameters = {{{{ fail_time = {FAIL_TIME}, fail_mode = {{mode}} }}}}
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    where = tmp_path_factory.mktemp("misbehaving")
    build_test_fmu("misbehaving", where)
    return where


def _study(folder: Path, mode: int, timeout: float = 60.0, name: str = "s.toml") -> Path:
    path = folder / name
    path.write_text(STUDY.format(mode=mode, timeout=timeout))
    return path


def _unpacked() -> set[str]:
    return {p.name for p in Path(tempfile.gettempdir()).glob("fmu-*")} | \
        {p.name for p in Path(tempfile.gettempdir()).glob("ssp-*")}


@pytest.mark.parametrize("mode, words", [(1, "crashed (signal SIGSEGV) in doStep at t = 0.5 s"),
                                         (2, "ended its process (exit code 3) in doStep at t = 0.5 s"),
                                         (3, "doStep at t = 0.5 s did not return within 1 s")])
def test_a_crash_an_exit_and_a_hang_are_named_errors_and_the_signals_are_kept(folder, tmp_path, mode, words,
                                                                            monkeypatch):
    own = tmp_path / "tmp"              # the run's own temporary folder: other processes' FMUs are not counted
    own.mkdir()
    monkeypatch.setenv("TMPDIR", str(own))
    monkeypatch.setattr(tempfile, "tempdir", str(own))
    before = _unpacked()
    out = tmp_path / "out"
    with pytest.raises(RunError) as err:
        run_study(load_study(_study(folder, mode, timeout=1.0, name=f"s{mode}.toml")), out, plots=False)
    message, where = str(err.value), err.value.where
    del err                                 # the traceback holds the run's components
    gc.collect()
    assert words in message, message
    frame = pd.read_csv(where / "signals.csv")
    # x is the time the FMU reached: every instant before the failing doStep, as the FMU computed it
    assert list(frame["t"].round(9)) == [round(k * STEP, 9) for k in range(round(FAIL_TIME / STEP))]
    assert (frame["m.x"] - frame["t"]).abs().max() < 1e-12
    assert _unpacked() <= before            # the unpacked FMU is gone


@pytest.mark.slow               # a whole command in a subprocess, and its FMU's: about 15 s here
def test_ctrl_c_ends_a_hung_isolated_run_within_seconds_and_keeps_the_signals(folder, tmp_path):
    study = _study(folder, 3, name="hang.toml")
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "agrobot", "run", str(study), "--out", str(out), "--no-plots"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    children = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
    end = time.time() + 120
    while time.time() < end and not children.read_text().split():      # the FMU's process has started
        time.sleep(0.2)
    time.sleep(4.0)                                                     # ... and hangs in doStep at 0.5 s
    proc.send_signal(signal.SIGINT)
    sent = time.monotonic()
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and time.monotonic() - sent < 5.0, err
    assert "Traceback" not in err
    frame = pd.read_csv(out / "signals.csv")
    assert len(frame) == round(FAIL_TIME / STEP) and (frame["m.x"] - frame["t"]).abs().max() < 1e-12


def _padded(fmu: Path, extra: dict[str, bytes], out: Path) -> Path:
    """The FMU with more entries (sources, other platforms' binaries, resources)."""
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            dst.writestr(info, src.read(info))
        for name, data in extra.items():
            dst.writestr(name, data)
    return out


def test_only_the_entries_a_run_uses_are_unpacked_and_removed_after(folder, tmp_path, monkeypatch):
    import fmpy

    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))     # other workers unpack FMUs too

    _padded(folder / "misbehaving.fmu", {"sources/misbehaving.c": b"int x;\n" * 1000,
                                         "binaries/win64/misbehaving.dll": b"\0" * 100_000,
                                         "resources/table.csv": b"1,2\n"}, tmp_path / "misbehaving.fmu")
    path = tmp_path / "s.toml"
    path.write_text(STUDY.format(mode=0, timeout=60).replace("isolate_fmus = true", "isolate_fmus = false"))
    before = _unpacked()
    system = build_system(resolve(load_study(path)))
    sim = Simulation(system)
    sim.start()
    where = system.nodes["m"].component._unpacked
    files = sorted(p.relative_to(where).as_posix() for p in where.rglob("*") if p.is_file())
    assert files == ["binaries/" + fmpy.platform + "/misbehaving.so", "modelDescription.xml", "resources/table.csv"]
    sim.terminate()
    del sim, system
    gc.collect()
    assert not where.exists() and _unpacked() <= before


def test_an_fmu_past_the_unpack_cap_is_refused_naming_the_cap(folder, tmp_path, monkeypatch):
    from agrobot.orchestrator import fmu_unpack

    _padded(folder / "misbehaving.fmu", {"resources/zeros.bin": b"\0" * (8 * 1024 ** 2)}, tmp_path / "misbehaving.fmu")
    assert (tmp_path / "misbehaving.fmu").stat().st_size < 100_000          # 8 MB of zeros, deflated
    monkeypatch.setattr(fmu_unpack, "UNPACK_LIMIT", 1024 ** 2)
    path = tmp_path / "s.toml"
    path.write_text(STUDY.format(mode=0, timeout=60).replace("isolate_fmus = true", "isolate_fmus = false"))
    before = _unpacked()
    with pytest.raises(InputError) as err:
        Simulation(build_system(resolve(load_study(path)))).run()
    assert "more than 1 MB" in str(err.value) and "FMU_UNPACK_LIMIT_MB" in str(err.value), str(err.value)
    assert _unpacked() <= before


SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  version="1.0" name="two">
  <ssd:System name="two">
    <ssd:Elements>
      <ssd:Component name="m" source="{source}" type="application/x-fmu-sharedlibrary"/>
    </ssd:Elements>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0" stopTime="1"/>
</ssd:SystemStructureDescription>
"""


def test_an_ssp_unpacks_the_fmus_it_uses_and_names_none_outside_unless_allowed(folder, tmp_path, monkeypatch):
    from agrobot.orchestrator import ssp

    archive = tmp_path / "two.ssp"
    with zipfile.ZipFile(archive, "w") as zf:
        zf.writestr("SystemStructure.ssd", SSD.format(source="resources/m.fmu"))
        zf.write(folder / "misbehaving.fmu", "resources/m.fmu")
        zf.writestr("resources/unused.fmu", b"\0" * 100_000)
    study = load_study(archive)
    where = ssp._EXTRACTED[archive.resolve()]
    assert sorted(p.relative_to(where).as_posix() for p in where.rglob("*") if p.is_file()) == \
        ["SystemStructure.ssd", "resources/m.fmu"]
    assert Path(study.components["m"].type).parent.parent == where
    outside = tmp_path / "outside.ssp"
    with zipfile.ZipFile(outside, "w") as zf:
        zf.writestr("SystemStructure.ssd", SSD.format(source=str(folder / "misbehaving.fmu")))
    monkeypatch.delenv(ssp.ALLOW_OUTSIDE, raising=False)
    with pytest.raises(InputError, match="lies outside the archive"):
        load_study(outside)
    monkeypatch.setenv(ssp.ALLOW_OUTSIDE, "1")
    assert Path(load_study(outside).components["m"].type) == folder / "misbehaving.fmu"
