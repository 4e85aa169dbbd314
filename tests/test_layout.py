"""The layout rules a reader relies on, checked on every module of the package (src/agrobot, the linked
folders followed):

- no function longer than 80 lines (its ``def`` to its last line);
- imports at the top of the module; a function-level import only for an optional extra or a measured
  start-up cost, and then named in the module docstring, in a paragraph that starts ``Imported where
  used:`` and lists the modules (``Imported where used: matplotlib (start-up), ortools (the fields
  extra).``). A module of the package may be named from below its root (``orchestrator.ssp``: the
  orchestrator names no project). An import inside ``if TYPE_CHECKING:`` is not a run-time import
  and is not counted.
"""
from __future__ import annotations

import ast
import re

import pytest

from tests.package_tree import PACKAGE, module_name, package_files

MAX_LINES = 80
DEFERRED = re.compile(r"Imported where used:(.*?)(?:\n\s*\n|\Z)", re.S)


def declared_deferred(docstring: str | None) -> list[str]:
    """The module names a docstring's ``Imported where used:`` paragraph lists (the words before
    each parenthesis or comma)."""
    match = DEFERRED.search(docstring or "")
    if not match:
        return []
    text = re.sub(r"\([^)]*\)", "", match.group(1))
    return [w.strip(" .`") for w in re.split(r"[,;]|\band\b", text) if w.strip(" .`\n")]


def _target(node: ast.Import | ast.ImportFrom, module: str, is_package: bool) -> list[str]:
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level:
        base = module.split(".") if is_package else module.split(".")[:-1]
        base = base[:len(base) - node.level + 1]
        return [".".join(base + ([node.module] if node.module else []))]
    return [node.module or ""]


def function_imports(tree: ast.AST, module: str, is_package: bool) -> list[tuple[int, str]]:
    """(line, imported module) of every import inside a function (not under ``if TYPE_CHECKING``)."""
    found = []
    for fn in ast.walk(tree):
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for node in ast.walk(fn):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                found += [(node.lineno, t) for t in _target(node, module, is_package)]
    return sorted(set(found))


def long_functions(tree: ast.AST) -> list[tuple[str, int]]:
    return [(fn.name, fn.end_lineno - fn.lineno + 1) for fn in ast.walk(tree)
            if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)) and fn.end_lineno - fn.lineno + 1 > MAX_LINES]


def _covered(target: str, declared: list[str]) -> bool:
    names = [target] + ([target.split(".", 1)[1]] if target.startswith(PACKAGE.name + ".") else [])
    return any(n == d or n.startswith(d + ".") for n in names for d in declared)


@pytest.mark.parametrize("path", package_files(), ids=module_name)
def test_functions_are_short_and_imports_at_the_top(path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    assert long_functions(tree) == [], f"{path}: functions over {MAX_LINES} lines"
    declared = declared_deferred(ast.get_docstring(tree))
    stray = [f"line {line}: {target}" for line, target in function_imports(tree, module_name(path), path.name == "__init__.py")
             if not _covered(target, declared)]
    assert stray == [], (f"{path}: imports inside functions that the module docstring does not name in an "
                         f"'Imported where used:' paragraph (an optional extra or a measured start-up cost): {stray}")


def test_the_rule_finds_what_it_forbids():
    """The checks on a planted module: a long function, an undeclared and a declared deferred import."""
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_LINES))
    source = (f'"""A module.\n\nImported where used: matplotlib (start-up).\n"""\n\n\ndef long():\n{body}\n\n\n'
              f"def plot():\n    import matplotlib.pyplot\n    from .sibling import thing\n    return thing\n")
    tree = ast.parse(source)
    assert long_functions(tree) == [("long", MAX_LINES + 1)]
    declared = declared_deferred(ast.get_docstring(tree))
    assert declared == ["matplotlib"]
    imports = function_imports(tree, "agrobot.pkg.mod", False)
    assert [t for _, t in imports if not _covered(t, declared)] == ["agrobot.pkg.sibling"]
    assert _covered("agrobot.pkg.sibling", ["pkg.sibling"]) and not _covered("numpy.pkg", ["pkg"])
