"""The base install runs a study without the optional extras, and a command that needs one names it.
The extras' modules are made unimportable in a child process (a meta-path finder that refuses them)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXTRA_MODULES = ("ortools", "isoxml", "serial", "pynmeagps", "can", "cantools", "msgpack", "pymap3d", "rosbags",
                 "dask", "distributed", "lxml")
BLOCK = f"""
import importlib.abc, sys
class Refuse(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in {EXTRA_MODULES!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
sys.meta_path.insert(0, Refuse())
"""


def _without_extras(code: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", BLOCK + code], cwd=cwd, capture_output=True, text=True, timeout=300)


def test_the_base_install_runs_the_figure8_without_any_extra(tmp_path):
    done = _without_extras("import agrobot\nr = agrobot.run('figure8', set={'study.stop_time': 14})\n"
                           "print(r.status, round(r.values['sim_time_s']))\n"
                           "print(sorted(m for m in sys.modules if m.split('.')[0] in " + repr(EXTRA_MODULES) + "))",
                           tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split("\n")[:2] == ["completed 14", "[]"]


def test_a_command_whose_extra_is_missing_names_the_extra(tmp_path):
    bag = tmp_path / "drive.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n")
    done = _without_extras(f"sys.argv = ['agrobot', 'convert', {str(bag)!r}, '--out', 'log.csv']\n"
                           "from agrobot.__main__ import main\nsys.exit(main())", tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr[-2000:]
    assert "pip install 'agrobot-guidance[bags]'" in done.stderr and "'rosbags'" in done.stderr
    assert not (tmp_path / "log.csv").exists()
