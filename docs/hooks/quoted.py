"""The program outputs the docs quote, made by the program and checked against the pages.

Every block of output a page quotes is marked by the comment ``<!-- quoted: NAME -->`` on the line
before its code fence; ``QUOTES[NAME]`` gives the commands that print it, and their output (stdout
and stderr, progress and wall-clock lines left out) is kept in ``docs/hooks/quoted/NAME.txt``.
``mismatches`` lists every line of a marked block that the kept output does not print (a line
ending in ``...`` is a quoted beginning; a line ``...`` stands for lines left out); a marked
Markdown table of key figures is checked figure by figure, rounded as written
(``table_mismatches``). So a number
changed by hand fails tests/test_docs.py, and a changed program changes the kept output when this
script is run again::

    python3 docs/hooks/quoted.py             # run every command, rewrite docs/hooks/quoted/*.txt
    python3 docs/hooks/quoted.py figure8-run # one of them
    python3 docs/hooks/quoted.py --check     # say which quoted lines the kept outputs do not print
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
KEPT = Path(__file__).resolve().parent / "quoted"
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
F1TENTH = "/tmp/f1tenth"          # the folder the identification page names
_DS5 = ["convert", "tests/data/f1tenth_frictionmaps/DataSets/DS5",
        "--signal", "delta_cmd=commandData.delta[rad]", "--signal", "yaw_rate=imuData.wz[deg/s]",
        "--signal", "v=pfOdomData.vx[m/s]", "--signal", "x=pfOdomData.x[m]", "--signal", "y=pfOdomData.y[m]",
        "--out", f"{F1TENTH}/ds5.csv", "--overwrite"]
# NAME -> the commands (arguments of ``python -m agrobot``) whose output the pages quote; every
# command but the last prepares its input and is not kept. {out}: a fresh folder.
QUOTES: dict[str, list[list[str]]] = {
    "figure8-run": [["run", "studies/figure8.toml", "--out", "{out}/figure8", "--no-plots"]],
    "f1tenth-identify": [_DS5, ["identify", f"{F1TENTH}/ds5.csv", "--study", "studies/f1tenth.toml",
                                "--out", "{out}/identify"]],
    "f1tenth-diagnose": [_DS5, ["diagnose", f"{F1TENTH}/ds5.csv", "--study", "studies/f1tenth.toml",
                                "--out", "{out}/diagnose"]],
}
# lines that change from one run to the next (wall time, progress, where the results went)
VOLATILE = re.compile(r"^(progress:|wall_time_s\b|results written to|\[\s*[\d.]+ s\] |\w+ \.\.\. [\d.]+ s$|\w+: done in [\d.]+ s$|\s*$)")
MARKER = re.compile(r"<!--\s*quoted:\s*([\w-]+)\s*-->\s*\n```[^\n]*\n(.*?)```", re.S)


def produce(name: str, python: str = sys.executable) -> str:
    """Run ``QUOTES[name]`` in the repository; the last command's output without VOLATILE lines."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "COLUMNS": "100"}
    with tempfile.TemporaryDirectory() as out:
        text = ""
        for argv in QUOTES[name]:
            argv = [a.replace("{out}", out) for a in argv]
            if "--out" in argv:
                Path(argv[argv.index("--out") + 1]).parent.mkdir(parents=True, exist_ok=True)
            done = subprocess.run([python, "-m", "agrobot", *argv], cwd=ROOT, env=env, capture_output=True,
                                  text=True, timeout=900)
            if done.returncode != 0:
                raise RuntimeError(f"{name}: python -m agrobot {' '.join(argv)} exited {done.returncode}: "
                                   f"{done.stderr.strip().splitlines()[-1:]}")
            text = (done.stdout + done.stderr).replace(out, "OUT")
    return "".join(line + "\n" for line in text.splitlines() if not VOLATILE.match(line))


def kept(name: str) -> str:
    path = KEPT / f"{name}.txt"
    return path.read_text(encoding="utf-8") if path.is_file() else ""


def mismatches(page: str, text: str, outputs=kept) -> list[str]:
    """Lines of the marked blocks of ``text`` (the page ``page``) that the kept outputs do not print."""
    found = []
    for match in MARKER.finditer(text):
        name, block = match.group(1), match.group(2)
        if name not in QUOTES:
            found.append(f"{page}: quoted: {name}: no such output (known: {', '.join(QUOTES)})")
            continue
        printed = [line.rstrip() for line in outputs(name).splitlines()]
        for line in block.splitlines():
            line = line.rstrip()
            if line.strip() in ("", "...") or VOLATILE.match(line):
                continue
            ok = any(p.startswith(line[:-3].rstrip()) for p in printed) if line.endswith("...") else line in printed
            if not ok:
                found.append(f"{page}: quoted: {name}: the program does not print {line!r}")
    return found


TABLE = re.compile(r"<!--\s*quoted:\s*([\w-]+)\s*-->[ \t]*\n\s*\n?((?:\|[^\n]*\n)+)")


def figures(name: str, outputs=kept) -> dict[str, float]:
    """The key figures of a kept run table: figure -> value."""
    rows = re.findall(r"^(\w+)\s+(-?\d[\d.]*(?:e[-+]\d+)?|nan)\s", outputs(name), flags=re.M)
    return {k: float(v) for k, v in rows}


def table_mismatches(page: str, text: str, outputs=kept) -> list[str]:
    """Rows of the marked Markdown tables (``| `figure` / `_other` | 0.19 / 0.19 m | ...``) whose
    numbers are not the kept figures rounded as the page writes them."""
    found = []
    for match in TABLE.finditer(text):
        name = match.group(1)
        values = figures(name, outputs)
        for row in match.group(2).splitlines():
            cells = [c.strip() for c in row.strip("|").split("|")]
            keys = re.findall(r"`(\w+)`", cells[0])
            if not keys or len(cells) < 2:
                continue
            full = [keys[0]]
            for k in keys[1:]:          # `_curved` after `euclid_mean_straight`: euclid_mean_curved
                full.append(full[-1].rsplit("_", 1)[0] + k if k.startswith("_") else k)
            numbers = [re.match(r"\s*(-?\d[\d.]*)", part) for part in cells[1].split(" / ")]
            for key, number in zip(full, numbers):
                if number is None:
                    continue
                quoted = number.group(1)
                places = len(quoted.split(".")[1]) if "." in quoted else 0
                if key not in values or round(values[key], places) != float(quoted):
                    found.append(f"{page}: quoted: {name}: {key} = {quoted}, the program prints "
                                 f"{values.get(key, 'nothing')}")
    return found


def check() -> list[str]:
    """Every page's mismatches."""
    return [m for page in PAGES for f in (mismatches, table_mismatches)
            for m in f(str(page.relative_to(ROOT)), page.read_text(encoding="utf-8"))]


def main(argv: list[str]) -> int:
    if argv[:1] == ["--check"]:
        problems = check()
        print("\n".join(problems) or "every quoted output is printed by the program")
        return 1 if problems else 0
    KEPT.mkdir(exist_ok=True)
    for name in argv or list(QUOTES):
        (KEPT / f"{name}.txt").write_text(produce(name), encoding="utf-8")
        print(f"written: {KEPT / name}.txt")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
