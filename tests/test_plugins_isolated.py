"""A broken third-party plugin never takes the commands down: one that cannot be imported, or
whose ``register`` raises, is named in one warning line (distribution, entry point, error) and
left out whole; every command that does not need it works; a study naming a type only it would
have brought gets the plugin's error in its message."""
from __future__ import annotations

import pytest

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _broken_distribution(folder: Path) -> dict:
    """A distribution ``brokenplug`` with two plugins: one whose module is missing, one whose
    register adds a component package and then raises."""
    info = folder / "brokenplug-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: brokenplug\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[agrobot.plugins]\nbroken = brokenplug_missing:register\n"
                                           "raiser = brokenplug:register\n")
    (folder / "brokenplug.py").write_text("def register(reg):\n    reg.add_component_package('brokenplug_parts')\n"
                                          "    raise RuntimeError('boom in register')\n")
    path = os.pathsep.join([str(folder), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path}


def _agrobot(env: dict, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "agrobot", *args], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=300)


@pytest.mark.slow
def test_a_broken_plugin_is_named_once_and_every_command_still_works(tmp_path):
    env = _broken_distribution(tmp_path / "site")
    for args in (["--version"], ["run", "--help"], ["plan", "--help"]):
        done = _agrobot(env, *args)
        assert done.returncode == 0 and "Traceback" not in done.stderr, (args, done.stderr)
        warnings = [line for line in done.stderr.splitlines() if line.startswith("warning: plugin")]
        assert len(warnings) == 2, done.stderr
        assert "'broken' of brokenplug (agrobot.plugins: brokenplug_missing:register) cannot be imported" in warnings[0]
        assert "'raiser' of brokenplug (agrobot.plugins: brokenplug:register) failed to register: RuntimeError: " \
               "boom in register" in warnings[1]
    out = tmp_path / "run"
    done = _agrobot(env, "run", "studies/figure8.toml", "--set", "study.stop_time=15", "--out", str(out), "--no-plots")
    assert done.returncode == 0, done.stderr
    assert (out / "run.json").is_file()


def test_a_study_naming_a_type_of_a_broken_plugin_gets_its_error(tmp_path):
    env = _broken_distribution(tmp_path / "site")
    study = tmp_path / "s.toml"
    study.write_text('[study]\nname = "s"\nstop_time = 1.0\nbase_step = 0.1\nseed = 1\n\n'
                     '[components.part]\ntype = "brokenplug_part"\nstep = 0.1\n')
    done = _agrobot(env, "run", str(study), "--out", str(tmp_path / "out"))
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "no such component type" in done.stderr and "boom in register" in done.stderr.split("no such component")[1]
    # what the failing register added before it raised is left out with it
    assert "brokenplug_parts" not in done.stderr
