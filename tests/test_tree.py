"""The tree as static tools read it: the import root ``agrobot`` is the folder ``src/agrobot`` (the design's
top-level folders linked into it), so mypy, an editor's go-to-definition and an import-graph builder find
every module from the installed package without running it; one name per thing."""
from __future__ import annotations

import ast
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from tests.package_tree import PACKAGE, ROOT, module_name, package_files

DESIGN_FOLDERS = ("components", "orchestrator", "studies")     # the design card's top-level folders
# module names that are a convention of every tool package (its command layer, its staged pipeline)
CONVENTIONS = {"__init__", "__main__", "cli", "pipeline"}


def test_the_design_folders_stay_at_the_top_and_are_the_import_names():
    for name in DESIGN_FOLDERS:
        assert (ROOT / name).is_dir() and not (ROOT / name).is_symlink(), name
        link = PACKAGE / name
        assert link.is_symlink() and link.resolve() == (ROOT / name).resolve(), name
    assert not (ROOT / "setup.py").exists(), "no import hook: the package folder is the import root"


@pytest.mark.slow
def test_mypy_finds_every_agrobot_module(tmp_path):
    """mypy, run outside the checkout on the installed package, parses every module and misses none."""
    pytest.importorskip("mypy")
    proc = subprocess.run([sys.executable, "-m", "mypy", "-p", "agrobot", "--follow-imports=silent", "-v",
                           "--cache-dir", str(tmp_path / "cache"), "--hide-error-context"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=600)
    out = proc.stdout + proc.stderr
    assert "INTERNAL ERROR" not in out, out[-2000:]
    missing = [line for line in out.splitlines() if re.search(r'module named "agrobot', line)]
    assert missing == [], missing[:10]
    parsed = set(re.findall(r"Parsing \S+ \((agrobot[\w.]*)\)", out))
    on_disk = {module_name(p) for p in package_files()}
    assert on_disk - parsed == set(), sorted(on_disk - parsed)[:10]


@pytest.mark.parametrize("source, line, column, expected", [
    ("from agrobot.components.steering_hydraulics import SteeringHydraulics\n", 1, 55,
     "components/steering_hydraulics.py"),
    ("import agrobot.api\nagrobot.api.diagnose\n", 2, 14, "src/agrobot/api.py"),
    ("from agrobot.orchestrator.study import Study\n", 1, 40, "orchestrator/study.py"),
    ("from agrobot.diagnosis.pipeline import diagnose\n", 1, 42, "src/agrobot/diagnosis/pipeline.py"),
])
def test_go_to_definition_lands_on_the_file_in_the_checkout(tmp_path, source, line, column, expected):
    """An editor's static go-to-definition (jedi, as the Python language servers use it), from outside
    the checkout, lands on the file of this tree that defines the name."""
    jedi = pytest.importorskip("jedi")
    names = jedi.Script(source, path=tmp_path / "user.py").goto(line, column, follow_imports=True)
    assert names, f"no definition found for {source!r}"
    assert names[0].module_path is not None
    assert Path(names[0].module_path).resolve() == (ROOT / expected).resolve()


def test_an_import_graph_is_drawn_from_the_tree():
    """grimp (import-linter's graph) reads the installed package statically: every module on disk is in
    the graph, and the layers' imports are there (the API imports the orchestrator)."""
    grimp = pytest.importorskip("grimp")
    graph = grimp.build_graph("agrobot")
    on_disk = {module_name(p) for p in package_files()}
    assert on_disk <= set(graph.modules), sorted(on_disk - set(graph.modules))[:10]
    assert graph.direct_import_exists(importer="agrobot.components.steering_hydraulics",
                                      imported="agrobot.orchestrator.component")
    assert graph.find_shortest_chain(importer="agrobot.diagnosis.pipeline", imported="agrobot.orchestrator.study")


def test_one_name_per_thing():
    """No two modules of one name (apart from each package's command layer and pipeline) and no two
    public classes of one name in the package."""
    files = package_files()
    modules = Counter(p.stem for p in files if p.stem not in CONVENTIONS)
    assert [m for m, n in modules.items() if n > 1] == []
    classes: Counter[str] = Counter()
    for path in files:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        classes.update(node.name for node in tree.body if isinstance(node, ast.ClassDef) and not node.name.startswith("_"))
    assert [c for c, n in classes.items() if n > 1] == []
