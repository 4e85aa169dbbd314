"""The documentation: the site builds strictly (a broken link or anchor, a page left out of the
nav fails), the README stays short, its links resolve and its test command is CI's, and the
generated reference pages cover every command, study-file field and component type."""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest


ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
sys.path.insert(0, str(ROOT / "docs" / "hooks"))
import reference  # noqa: E402  (docs/hooks/reference.py: the generator the site build runs)


@pytest.mark.slow
def test_site_builds_strictly(tmp_path):
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    warnings = [line for line in done.stderr.splitlines() if line.startswith(("WARNING", "ERROR"))]
    assert done.returncode == 0 and not warnings, done.stderr[-3000:]
    for page in ("index.html", "getting-started/index.html", "reference/commands/index.html",
                 "reference/study-file/index.html", "reference/components/index.html"):
        assert (tmp_path / "site" / page).is_file(), page


def _links(markdown: str) -> list[str]:
    return re.findall(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", markdown)


def test_readme_is_short_and_its_links_resolve():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    links = [link for link in _links(text) if not re.match(r"[a-z]+:", link) and not link.startswith("#")]
    assert links, "the README links to the docs"
    missing = [link for link in links if not (ROOT / link.split("#")[0]).exists()]
    assert not missing, f"README links to files that do not exist: {missing}"
    assert any(link.startswith("docs/img/") for link in links), "the tour shows pictures"


def test_readme_test_command_is_the_one_ci_runs():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    ci_command = next(line for line in ci.splitlines() if "pytest" in line and not line.startswith("#"))
    readme = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```\w*\n(.*?)```", readme, flags=re.S)
    commands = [line.strip() for block in blocks for line in block.splitlines() if "pytest" in line]
    assert commands, "the README gives the test command"
    assert shlex.split(commands[0]) == shlex.split(ci_command)


def test_commands_page_covers_every_registered_command():
    from agrobot.orchestrator.registry import registry

    page = reference.commands_markdown()
    expected = {"run", "sweep", *registry().commands}
    documented = set(re.findall(r"^## (\S+)$", page, flags=re.M))
    assert documented == expected
    assert "usage: python -m agrobot identify" in page


def test_study_file_page_covers_every_field():
    from agrobot.orchestrator import study_schema

    page = reference.study_file_markdown()
    for model in (study_schema.StudySettings, study_schema.ComponentSpec, study_schema.Sweep,
                  study_schema.Exports, study_schema.SubsystemSpec, study_schema.SweepRange):
        for field in model.model_fields:
            assert f"| `{field}` |" in page, (model.__name__, field)
    assert "| `stop_time` | float | **required** | > 0, finite |" in page


def test_components_page_covers_every_component_module():
    page = reference.components_markdown()
    modules = sorted(p.stem for p in (ROOT / "components").glob("*.py") if p.stem != "__init__")
    documented = set(re.findall(r"^## (\w+)$", page, flags=re.M))
    assert set(modules) <= documented
    # declared parameters as the modules write them (the paper's N_p = 8; the 2 m/s reference)
    mpc = page.split("## yaw_rate_mpc")[1].split("\n## ")[0]
    assert "| `prediction_horizon` | 1 | 8 | N_p |" in mpc
    assert "| `speed` | m/s | 2 | reference speed along the path |" in page.split("## figure8_reference")[1]


def test_readme_lists_every_registered_command():
    from agrobot.orchestrator.registry import registry

    table = README.read_text(encoding="utf-8").split("## Commands", 1)[1].split("\n## ", 1)[0]
    listed = set(re.findall(r"^\| `([\w-]+)", table, flags=re.M))
    assert listed == {"run", "sweep", *registry().commands}


# --- quoted outputs and section references ------------------------------------------------------

import quoted  # noqa: E402  (docs/hooks/quoted.py: the outputs the pages quote)


def test_every_quoted_output_is_what_the_program_printed():
    assert quoted.check() == []
    marked = {m.group(1) for page in quoted.PAGES for m in quoted.MARKER.finditer(page.read_text(encoding="utf-8"))}
    assert marked == set(quoted.QUOTES)
    assert all((quoted.KEPT / f"{name}.txt").is_file() for name in marked)


def test_a_quoted_number_changed_by_hand_fails():
    page = ROOT / "docs" / "runs-and-results.md"
    text = page.read_text(encoding="utf-8")
    line = next(l for l in quoted.kept("figure8-run").splitlines() if l.startswith("euclid_max_straight "))
    value = line.split()[1]
    assert f"\n{line}\n" in text
    edited = text.replace(line, line.replace(value, f"{float(value) + 0.0001:.4f}"))
    assert quoted.mismatches("runs-and-results.md", edited) == [
        f"runs-and-results.md: quoted: figure8-run: the program does not print "
        f"{line.replace(value, f'{float(value) + 0.0001:.4f}')!r}"]
    # a line the program prints but the kept output has lost fails too
    assert quoted.mismatches("p", text, outputs=lambda name: "")
    # a table of key figures, rounded as the page writes them
    table = (ROOT / "docs" / "guidance-loop.md").read_text(encoding="utf-8")
    value = quoted.figures("figure8-run")["euclid_max_curved"]
    assert f"| `euclid_max_curved` | {value:.2f} m |" in table
    assert quoted.table_mismatches("g", table) == []
    wrong = table.replace(f"| `euclid_max_curved` | {value:.2f} m |", f"| `euclid_max_curved` | {value + 0.01:.2f} m |")
    assert quoted.table_mismatches("g", wrong) == [f"g: quoted: figure8-run: euclid_max_curved = {value + 0.01:.2f}, "
                                                   f"the program prints {value}"]


@pytest.mark.slow
def test_the_kept_figure8_output_is_what_the_program_prints_now():
    assert quoted.produce("figure8-run") == quoted.kept("figure8-run")


def _slug(heading: str) -> str:
    """Python-Markdown's toc slug (MkDocs' anchors)."""
    text = re.sub(r"[^\w\s-]", "", heading).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def _anchors(path: Path) -> set[str]:
    return {_slug(h) for h in re.findall(r"^#+\s+(.*?)\s*$", path.read_text(encoding="utf-8"), flags=re.M)}


def test_links_and_references_to_readme_and_docs_sections_resolve():
    readme_headings = set(re.findall(r"^#+\s+(.*?)\s*$", README.read_text(encoding="utf-8"), flags=re.M))
    texts = [README, *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "studies").glob("*.toml")),
             *sorted((ROOT / "tests" / "data").glob("*.md"))]
    broken = []
    for path in texts:
        text = path.read_text(encoding="utf-8")
        # 'README, "Section"' or 'README: "Section"' in prose and comments
        for section in re.findall(r"README[,:]\s+\"([^\"]+)\"", text):
            if section not in readme_headings:
                broken.append(f"{path.name}: README section {section!r}")
        # links with an anchor: [..](README.md#x), [..](#x), docs/page.md#x in comments
        for target, anchor in re.findall(r"(?<![\w/.-])((?:docs/)?[\w./-]*\.md|)#([\w-]+)", text):
            if (not target and path.suffix != ".md") or target in reference.PAGES:   # generated: the site build checks them
                continue
            base = path if not target else (ROOT / target if target.startswith("docs/") or target == "README.md"
                                            else path.parent / target)
            if not base.is_file() or anchor not in _anchors(base):
                broken.append(f"{path.name}: {target or path.name}#{anchor}")
    assert not broken, broken
