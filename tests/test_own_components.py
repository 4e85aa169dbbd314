"""A component of one's own: the "Your own component" page runs as it stands (its filter checked
against the first-order equation, its study run, its linear model in the margins); a type provided
by an installed package's entry point; a components_path that is not a folder is refused by name;
the agrobot script and python -m agrobot find a module beside the command alike."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.commands import cli
from tests.markdown_code import run_page

ROOT = Path(__file__).resolve().parent.parent
MODULE = '''
from agrobot.orchestrator.component import Component, inp, out, par

class Doubler(Component):
    variables = (inp("u", "1", 0.0, "in"), par("gain", "1", 2.0, "gain"), out("y", "1", 0.0, "gain * u"))
    feedthrough = {"y": ("u",)}

    def initialize(self, t0, dt):
        pass

    def step(self, t, dt):
        self.y["y"] = self.p["gain"] * self.u["u"]
'''
STUDY = '''
connections = ["source.y -> twice.u"]

[study]
name = "own"
stop_time = 1.0
base_step = 0.1
seed = 1
{extra}

[components.source]
type = "{source}"
parameters = {{ gain = 1.0 }}
inputs = {{ u = 1.5 }}

[components.twice]
type = "{twice}"
'''


@pytest.mark.slow
def test_the_own_component_page_runs(tmp_path):
    ns = run_page(ROOT / "docs" / "your-own-component.md", tmp_path)
    # the filter is in the loop: its output is the first-order response of the plant's yaw rate
    s = ns["filtered"].signals
    u, y = s["tractor.yaw_rate"].to_numpy()[::5], s["lowpass.yaw_rate_filtered"].to_numpy()[::5]
    import math

    a = 1 - math.exp(-0.05 / 0.1)
    assert all(abs(y[k] - (y[k - 1] + a * (u[k] - y[k - 1]))) < 1e-12 for k in range(1, len(y)))
    assert ns["lagged"].delay_limit < ns["plain"].delay_limit


def _run(study: Path, cwd: Path, *launcher: str) -> subprocess.CompletedProcess:
    return subprocess.run([*launcher, "run", str(study), "--out", str(cwd / "out"), "--no-plots", "--overwrite"], cwd=cwd,
                          capture_output=True, text=True, timeout=300)


def test_components_path_and_an_entry_point_provide_types(tmp_path, monkeypatch):
    """``components_path`` (relative to the study) and an entry point of ``agrobot.components``
    (a distribution on sys.path that declares it) both resolve; y = gain * u is computed."""
    from agrobot.orchestrator.resolver import resolve
    from agrobot.orchestrator.runner import run_study
    from agrobot.orchestrator.study import Study

    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "doubler_mod.py").write_text(MODULE)
    site = tmp_path / "site"
    (site / "shared_pkg").mkdir(parents=True)
    (site / "shared_pkg" / "__init__.py").write_text(MODULE)
    info = site / "shared_pkg-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: shared-pkg\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[agrobot.components]\ndoubler = shared_pkg:Doubler\n")
    monkeypatch.syspath_prepend(str(site))
    (tmp_path / "studies").mkdir()
    study = tmp_path / "studies" / "own.toml"
    study.write_text(STUDY.format(extra='components_path = "../mine"', source="doubler", twice="doubler_mod:Doubler"))
    loaded = Study.load(study)
    classes = resolve(loaded).classes
    assert classes["source"].__module__ == "shared_pkg" and classes["twice"].__module__ == "doubler_mod"
    result = run_study(loaded, None, plots=False)
    assert result.frame["source.y"].iloc[-1] == pytest.approx(1.0 * 1.5)
    assert result.frame["twice.y"].iloc[-1] == pytest.approx(2.0 * 1.5)


def test_a_components_path_that_is_no_folder_is_refused_by_name(tmp_path):
    study = tmp_path / "own.toml"
    study.write_text(STUDY.format(extra='components_path = "nowhere"', source="gyro_sensor", twice="gyro_sensor"))
    done = cli("run", study, "--out", tmp_path / "o")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"{study}: study.components_path: 'nowhere': no such folder" in done.stderr


def test_the_script_and_python_m_find_a_module_beside_the_command_alike(tmp_path):
    (tmp_path / "beside.py").write_text(MODULE)
    study = tmp_path / "own.toml"
    study.write_text(STUDY.format(extra="", source="beside:Doubler", twice="beside:Doubler"))
    script = Path(sys.executable).parent / "agrobot"
    for launcher in ([sys.executable, "-m", "agrobot"], [str(script)]):
        done = _run(study, tmp_path, *launcher)
        assert done.returncode == 0, (launcher, done.stderr[-1500:])


def test_what_a_component_declares_is_what_the_tools_find():
    """The C core is the class's own (a subclass with other equations has none until it says so);
    the linear model is inherited; a LINEAR_MODEL that cannot be loaded is refused by name; one that
    can is called with the component first."""
    from agrobot.analysis.loop_models import linear_model_of
    from agrobot.components.gps_sensor import GPSSensor
    from agrobot.orchestrator.compiled.cores import description_of
    from agrobot.orchestrator.component import Component
    from agrobot.orchestrator.errors import InputError

    class NoisierGPS(GPSSensor):
        pass

    class Broken(Component):
        LINEAR_MODEL = "agrobot.analysis.loop_models:no_such_model"
        variables = ()

    class Named(Component):
        LINEAR_MODEL = "agrobot.analysis.loop_models:off_the_lateral_loop"
        variables = ()

    assert description_of(GPSSensor("gps", {})).source.name == "gps_sensor.c"
    assert description_of(NoisierGPS("gps", {})) is None
    noisier = NoisierGPS("gps", {})
    assert linear_model_of(noisier).__func__ is GPSSensor.linear_model
    named = Named("n", {})
    assert linear_model_of(named)() is False                    # off_the_lateral_loop(named)
    with pytest.raises(InputError, match="'gps' .*Broken.: LINEAR_MODEL = 'agrobot.analysis.loop_models:no_such_model' "
                                         "cannot be loaded"):
        linear_model_of(Broken("gps", {}))
