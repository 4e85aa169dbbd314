"""Small bad inputs of a run: a study file that is not UTF-8, a mistyped ``--set`` key, and SIGTERM
landing while the command's modules load."""
from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from agrobot.orchestrator.study import Study, StudyError

ROOT = Path(__file__).resolve().parent.parent
CMD = [sys.executable, "-m", "agrobot"]
FIGURE8 = ROOT / "studies" / "figure8.toml"


def test_a_study_file_that_is_not_utf8_is_refused_with_its_line_column_and_byte(tmp_path, cli):
    text = FIGURE8.read_text()
    latin = tmp_path / "latin.toml"
    latin.write_bytes(text.encode() + "# réglage du tracteur\n".encode("latin-1"))
    line = text.count("\n") + 1
    proc = cli("run", latin, "--out", tmp_path / "o")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    offset = len(text.encode()) + len("# r")
    for words in (str(latin), f"line {line}, column 4 (byte offset {offset})", "0xe9", "not UTF-8", "'# r'"):
        assert words in proc.stderr, proc.stderr
    assert not (tmp_path / "o").exists()
    extended = tmp_path / "child.toml"                # the file it extends is named when that one is the culprit
    extended.write_text('extends = "latin.toml"\n[study]\nname = "child"\n')
    with pytest.raises(StudyError, match=r"latin\.toml: line"):
        Study.load(extended)


@pytest.mark.parametrize("item, words", [
    ("tracker.lookahed=1", ["--set tracker.lookahed=1", "did you mean 'lookahead'?", "Known: k_c"]),
    ("trackr.lookahead=1", ["--set trackr.lookahead=1", "no component 'trackr'", "did you mean 'tracker'"]),
    ("study.stop_tme=10", ["--set study.stop_tme=10", "no field 'stop_tme'", "did you mean 'stop_time'"]),
    ("tracker.inputs.x_rf=1", ["--set tracker.inputs.x_rf=1", "unknown input", "did you mean 'x_ref'?"]),
    ("study.stop_time=-1", ["--set study.stop_time=-1", "greater than 0"]),
    ("tractor.psi0=abc", ["--set tractor.psi0=abc", "expected a number"]),
])
def test_a_mistyped_set_key_is_blamed_on_the_set_item_with_the_nearest_names(item, words):
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.resolver import resolve

    with pytest.raises(StudyError) as err:
        build_system(resolve(Study.load(FIGURE8, [item])))
    message = str(err.value)
    for w in words:
        assert w in message, message
    assert "invalid study file" not in message and not message.startswith(str(FIGURE8))


def test_the_same_typo_in_the_file_is_blamed_on_the_file(tmp_path):
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.resolver import resolve

    path = tmp_path / "typo.toml"
    path.write_text(FIGURE8.read_text().replace("lookahead", "lookahed", 1) if "lookahead" in FIGURE8.read_text()
                    else f'extends = "{FIGURE8}"\n[components.tracker.parameters]\nlookahed = 1.0\n')
    with pytest.raises(StudyError) as err:
        build_system(resolve(Study.load(path, ["study.stop_time=10"])))
    assert str(err.value).startswith(f"{path}: components.tracker.parameters.lookahed: unknown parameter")


def test_a_signal_landing_in_an_import_is_raised_when_the_import_is_over(tmp_path, monkeypatch):
    """Raised inside an import, the interrupt could leave a C extension half initialised or be
    swallowed by a library's guarded import (the run then went on, exit 0): it waits for the
    import to end, then ends the work as Terminated (exit 143)."""
    from agrobot.orchestrator import cli, errors

    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGALRM)}
    (tmp_path / "slow_plugin.py").write_text(
        "import os, signal\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "try:\n    x = sum(range(10_000))\nexcept BaseException:\n    pass   # a library's guarded import\n"
        "loaded = True\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        errors.install_signal_handlers()
        with pytest.raises(errors.Terminated):
            import slow_plugin                                   # noqa: F401
            assert slow_plugin.loaded
            for _ in range(200):
                time.sleep(0.05)
        assert sys.modules["slow_plugin"].loaded
        # the command line turns it into 143, wherever it lands before the command runs
        monkeypatch.setattr(cli, "build_parser", lambda: (_ for _ in ()).throw(errors.Terminated()))
        assert cli.main(["run", "x.toml", "--out", "o"]) == 143
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        for s, handler in saved.items():
            signal.signal(s, handler)
        sys.modules.pop("slow_plugin", None)


@pytest.mark.parametrize("delay", [0.5, 1.5, 3.0])
def test_sigterm_ends_the_hardware_layout_run_as_terminated_wherever_it_lands(tmp_path, delay):
    """While the modules load, while the study is built, while the composite tractor steps: 143,
    no traceback (before Python has installed its handlers the kernel's default ends it: -15)."""
    proc = subprocess.Popen(CMD + ["run", "studies/figure8_hardware_layout.toml", "--set", "study.realtime=true",
                                   "--out", str(tmp_path / "hw"), "--no-plots"], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode in (143, -signal.SIGTERM), err
    assert "Traceback" not in err and "ImportError" not in err, err
