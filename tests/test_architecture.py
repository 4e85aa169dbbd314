"""The layers hold: no import circle, no import from a lower layer to a higher one (checked
statically by benchmarks/import_graph.py, which must find circles and upward imports planted in a
small tree), and a study is a description that parses with no plugin installed."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from pydantic import BaseModel, ConfigDict

from agrobot.orchestrator.registry import registry
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study, StudyError

ROOT = Path(__file__).resolve().parent.parent
CHECKER = ROOT / "benchmarks" / "import_graph.py"


def _check(root: Path, *options: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(CHECKER), str(root), *options], capture_output=True, text=True,
                          timeout=120)


def _listed(output: str, heading: str) -> list[str]:
    """The lines listed under ``heading: N`` in the checker's output."""
    lines = output.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(heading))
    items = []
    for line in lines[start + 1:]:
        if not line.startswith("  "):
            break
        items.append(line.strip())
    return items


def test_the_packages_have_no_import_circle_and_no_upward_import():
    proc = _check(ROOT / "src" / "agrobot", "--allow-pending")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    circles = [c for c in _listed(proc.stdout, "import circles") if not c.endswith("(pending)")]
    upward = [u for u in _listed(proc.stdout, "upward imports") if not u.endswith("(pending)")]
    assert circles == [] and upward == []
    # what other work is still removing stays inside its two packages
    for item in _listed(proc.stdout, "import circles") + _listed(proc.stdout, "upward imports"):
        assert "measurements." in item or "fields" in item, item


def _write(root: Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_the_checker_finds_a_planted_circle_and_upward_imports(tmp_path):
    _write(tmp_path, {
        "orchestrator/__init__.py": "",
        "orchestrator/a.py": "from .b import thing\n",
        "orchestrator/b.py": "def thing():\n    from orchestrator import a   # a function-level import counts\n",
        "orchestrator/c.py": "import orchestrator.errors\n",
        "orchestrator/errors.py": "",
        "orchestrator/study.py": "from .engine import run\n",     # the description importing the engine
        "orchestrator/engine.py": "def run(): pass\n",
        "components/__init__.py": "",
        "components/plan.py": "from measurements.truth import plan\n",
        "measurements/__init__.py": "",
        "measurements/truth.py": "from components import plan\n",
    })
    proc = _check(tmp_path)
    assert proc.returncode == 1
    assert _listed(proc.stdout, "import circles") == ["components.plan <-> measurements.truth",
                                                      "orchestrator.a <-> orchestrator.b"]
    assert _listed(proc.stdout, "upward imports") == ["components.plan -> measurements.truth",
                                                      "orchestrator.study -> orchestrator.engine"]
    _write(tmp_path, {"orchestrator/b.py": "def thing(): pass\n", "orchestrator/study.py": "from . import errors\n",
                      "components/plan.py": "import numpy\n"})
    clean = _check(tmp_path)
    assert clean.returncode == 0, clean.stdout
    assert "import circles: 0" in clean.stdout and "upward imports: 0" in clean.stdout


BLOCKED = ("components", "measurements", "fields", "analysis", "identification", "diagnosis", "fmu_export")
NO_PLUGINS = f"""
import json, sys
from importlib.abc import MetaPathFinder

class Absent(MetaPathFinder):          # the project's plugin packages are not installed
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {BLOCKED!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None

sys.meta_path.insert(0, Absent())
import agrobot.orchestrator.registry
agrobot.orchestrator.registry.entry_points = lambda group: []      # no entry point either
from agrobot.orchestrator.study import Study, StudyError

parsed = {{}}
for path in sorted(__import__("pathlib").Path("studies").glob("*.toml")):
    study = Study.load(path)
    parsed[path.name] = sorted(study.sections)
loaded = sorted(m for m in sys.modules if m.startswith("agrobot"))
from agrobot.orchestrator.resolver import resolve
try:
    resolve(Study.load("studies/figure8.toml"))
    refused = ""
except StudyError as exc:
    refused = str(exc)
print(json.dumps({{"parsed": parsed, "loaded": loaded, "refused": refused}}))
"""


def test_every_study_parses_with_no_plugin_installed_and_keeps_its_tool_tables():
    proc = subprocess.run([sys.executable, "-c", NO_PLUGINS], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert len(out["parsed"]) == len(list((ROOT / "studies").glob("*.toml")))
    assert out["parsed"]["passenger_car.toml"] == ["vehicle"]            # kept as written, its tool absent
    assert out["parsed"]["identification.toml"] == ["identification", "vehicle"]
    # parsing loaded the description and nothing above it
    assert set(out["loaded"]) <= {"agrobot", "agrobot.orchestrator", *(f"agrobot.orchestrator.{m}" for m in (
                                  "component", "errors", "registry", "study", "study_files", "study_schema"))}
    # resolving needs the component types: a message, not a traceback
    assert "figure8.toml" in out["refused"] and "no component package is registered" in out["refused"]


class _Checked(BaseModel):
    model_config = ConfigDict(extra="forbid")
    period: float


@pytest.fixture
def checked_table(monkeypatch):
    """A tool table ``[checked]`` whose tool registered a schema."""
    reg = registry()
    monkeypatch.setitem(reg.sections, "checked", "a test tool")
    monkeypatch.setitem(reg.section_schemas, "checked", _Checked)


def test_a_tool_table_is_validated_by_its_tool_when_the_study_is_resolved(checked_table):
    base = Study.load(ROOT / "studies" / "figure8.toml")
    good = base.derive({**base.to_data(), "checked": {"period": 0.5}})
    assert good.section("checked") == {"period": 0.5} and resolve(good).find(role="yaw_plant") == ["tractor"]
    bad = good.with_values({"checked.period": "soon"})
    with pytest.raises(StudyError, match=r"figure8.toml: checked\.period: Input should be a valid number"):
        resolve(bad)
    unknown = good.derive({**good.to_data(), "chekced": {"period": 0.5}})
    with pytest.raises(StudyError, match=r"unknown table 'chekced'; .* or a tool's table \(.*checked"):
        resolve(unknown)


def test_a_type_whose_module_does_not_exist_is_refused_by_name():
    study = Study.load(ROOT / "studies" / "figure8.toml").with_component("extra", type="nosuch.module:Thing")
    with pytest.raises(StudyError, match=r"components\.extra: type 'nosuch\.module:Thing': no such component type: "
                                         r"cannot import 'nosuch\.module'"):
        resolve(study)
