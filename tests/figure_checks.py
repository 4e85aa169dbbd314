"""Checks a figure must pass to be read at a glance: every quantity's axis carries its unit in brackets, and what
a reader tells apart (legend entries, the classes of a colour map) stays apart when the figure is printed in grey.

Greyscale is the luminance Y = 0.299 R + 0.587 G + 0.114 B (ITU-R BT.601, the weights of PIL's "L" conversion);
two entries merge in grey when their look (line style, marker, width within a factor of 2, hatch) is the same
and their luminances are closer than ``MIN_CONTRAST``."""
from __future__ import annotations

import re

import numpy as np

MIN_CONTRAST = 0.15           # luminance steps closer than this merge when printed in grey
UNIT = re.compile(r"\[[^\]]+\]")


def luminance(color) -> float:
    from matplotlib.colors import to_rgb

    r, g, b = to_rgb(color)
    return 0.299 * r + 0.587 * g + 0.114 * b


def has_unit(label: str) -> bool:
    """An axis label that names its unit in brackets ("east [m]", "ratio [-]")."""
    return bool(UNIT.search(label))


def _look(handle) -> tuple[tuple, float]:
    """(what tells a legend entry apart besides its colour, its colour's luminance)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if isinstance(handle, Line2D):
        marker = handle.get_marker() if handle.get_marker() not in (None, "None", "none", "") else None
        style = handle.get_linestyle() if handle.get_linestyle() not in ("None", "none", "", " ") else None
        width = round(float(np.log2(max(handle.get_linewidth(), 1e-3)))) if style else None
        return ("line", style, marker, width), luminance(handle.get_color())
    if isinstance(handle, Patch):
        face = handle.get_facecolor()
        return ("patch", handle.get_hatch() or None), luminance(face[:3] if face[3] > 0 else "white")
    return (type(handle).__name__,), luminance(handle.get_facecolor()[0][:3]) if hasattr(handle, "get_facecolor") else 0.0


def _entries(ax) -> list[tuple[str, object]]:
    """(label, handle) of what the reader matches: the legend's entries (the handles drawn in it, whatever the
    artist: line, bar, line collection), or the labelled lines when there is no legend."""
    legend = ax.get_legend()
    if legend is not None:
        return [(t.get_text(), h) for t, h in zip(legend.get_texts(), legend.legend_handles) if h is not None]
    return [(ln.get_label(), ln) for ln in ax.get_lines() if not ln.get_label().startswith("_")]


def apart_in_greyscale(ax) -> list[str]:
    """What of ``ax`` only its hue tells apart: pairs of legend entries of the same look whose luminances are
    closer than MIN_CONTRAST, and classes of a colour map with a few colours (a categorical map) as close;
    a continuous colour map must run monotonically in luminance (it reads as a grey scale)."""
    from matplotlib.colors import ListedColormap

    clashes = []
    entries = _entries(ax)
    looks = [(label, *_look(h)) for label, h in entries]
    for i, (la, look_a, ya) in enumerate(looks):
        for lb, look_b, yb in looks[i + 1:]:
            if look_a == look_b and abs(ya - yb) < MIN_CONTRAST:
                clashes.append(f"{la} / {lb} (luminance {ya:.2f} and {yb:.2f})")
    for mappable in ax.collections + ax.images:
        cmap = getattr(mappable, "cmap", None)
        if cmap is None or mappable.get_array() is None:
            continue
        if isinstance(cmap, ListedColormap) and cmap.N <= 12:
            ys = sorted(luminance(c) for c in cmap.colors)
            close = [f"{a:.2f}/{b:.2f}" for a, b in zip(ys, ys[1:]) if b - a < MIN_CONTRAST]
            if close:
                clashes.append(f"colour map {cmap.name}: classes of luminance {', '.join(close)}")
        else:
            ys = np.array([luminance(cmap(v)[:3]) for v in np.linspace(0, 1, 64)])
            steps = np.diff(ys)
            if not (np.all(steps >= -1e-3) or np.all(steps <= 1e-3)):
                clashes.append(f"colour map {cmap.name}: not monotonic in luminance")
    return clashes
