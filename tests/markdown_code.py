"""The code of a docs page, run as it stands: fenced blocks with ``title="PATH"`` are written to PATH
(files the page asks the reader to create), the other ``python`` blocks are executed in order in
one namespace, in a given folder."""
from __future__ import annotations

import os
import re
from pathlib import Path

FENCE = re.compile(r"^```(\w+)([^\n]*)\n(.*?)^```", re.S | re.M)


def blocks(page: Path) -> list[tuple[str, str | None, str]]:
    """(language, title or None, code) of every fenced block of ``page``, in order."""
    out = []
    for lang, info, code in FENCE.findall(page.read_text(encoding="utf-8")):
        title = re.search(r'title="([^"]+)"', info)
        out.append((lang, title.group(1) if title else None, code))
    return out


def run_page(page: Path, folder: Path) -> dict:
    """Write the page's titled blocks into ``folder`` and execute its python blocks there; returns
    the namespace. Matplotlib draws off screen."""
    import matplotlib

    matplotlib.use("Agg")
    namespace: dict = {"__name__": "__docs__"}
    here = os.getcwd()
    os.chdir(folder)
    try:
        for lang, title, code in blocks(page):
            if title is not None:
                Path(title).parent.mkdir(parents=True, exist_ok=True)
                Path(title).write_text(code)
            elif lang == "python":
                exec(compile(code, f"{page.name} block", "exec"), namespace)
    finally:
        os.chdir(here)
    return namespace
