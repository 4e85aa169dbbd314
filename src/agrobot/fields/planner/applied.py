"""What a plan works, as applied: the implement's working point on the path (as the planner lays
it; the simulation measures the real one, analysis.field_coverage), its strips on swaths and
headland passes, with or without section control (fields.planner.sections); the covered and
overlapping area against the whole field and the workable part.

With N sections each section's runs (where it is on) are strips of width w/N about the path offset
by the section's centre; without, the whole width is on along every swath and headland pass. The
areas are exact (shapely on the strips); the sections' decisions use the raster of
fields.planner.sections. Latency is left out here: the commands look ahead by v t (compensated),
so on the planned path the sections switch where the ground changes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from shapely import contains_xy
from shapely.geometry import LineString, Polygon
from shapely.ops import unary_union

from .leftovers import leftovers
from .sections import CoverageMap, SectionLayout, open_sections, paint_strip
from .types import WORKING

CHUNK = 10.0            # m of path decided at a time (against the ground worked before it)


@dataclass(frozen=True)
class AsApplied:
    """Areas [m^2] of what was worked: ``covered`` (at least once), ``overlap`` (worked more than
    once, counted once per extra time), of the whole ``field`` and of its ``workable`` part."""

    field: float
    covered: float
    overlap: float
    workable: float
    covered_workable: float
    strips: tuple                      # the applied strips (shapely polygons)
    shape: object = None               # what was covered (their union within the field)

    @property
    def field_coverage_share(self) -> float:
        return self.covered / self.field

    @property
    def coverage_share(self) -> float:
        return self.covered_workable / self.workable

    @property
    def overlap_share(self) -> float:
        """Overlap over the whole field's area."""
        return self.overlap / self.field

    @property
    def skipped(self) -> float:
        return self.field - self.covered


def areas(strips: list, field: Polygon, workable: Polygon) -> AsApplied:
    """Covered and overlapping areas of strips within the field (and the workable part)."""
    union = unary_union(strips).intersection(field) if strips else Polygon()     # union first: exactly adjacent
    swept = sum(s.intersection(field).area for s in strips)                       # strips stay seamless
    return AsApplied(field.area, union.area, max(swept - union.area, 0.0), workable.area,
                     union.intersection(workable).area, tuple(strips), union)


def working_strips(plan) -> list:
    """The whole working width about every swath and headland pass (no section control): about the
    implement's line (a curved swath's own, the rear axle running outside it), else the path's."""
    w = plan.settings.working_width
    return [LineString(seg.points[:, :2] if seg.work is None else seg.work).buffer(0.5 * w, cap_style="flat")
            for seg in plan.path.segments if seg.kind in WORKING]


def as_applied(plan, sections: int = 0) -> AsApplied:
    """The plan worked without section control (``sections`` 0) or with N sections."""
    if not sections:
        return areas(working_strips(plan), plan.field.boundary, plan.workable)
    return areas(section_strips(plan, SectionLayout(plan.settings.working_width, sections)), plan.field.boundary,
                 plan.workable)


def section_strips(plan, layout: SectionLayout) -> list:
    """Each section's strips where it is on, the path replayed in order a CHUNK at a time."""
    cmap = CoverageMap(plan.field.boundary, min(0.1, layout.section_width / 2))
    look, look_owner = layout.across(cmap.cell)
    brush, brush_owner = layout.across(0.5 * cmap.cell)
    step = min(0.25, 0.5 * layout.section_width, cmap.cell)
    path, strips = plan.path, []
    for k in np.flatnonzero(np.isin(path.kinds, WORKING)):
        a = path.starts[k]
        b = path.starts[k + 1] if k + 1 < len(path) else path.length
        s = np.append(np.arange(a, b, step), b)
        r = path.evaluate(s)
        x, y, h = r["x"], r["y"], r["heading"]
        on = np.zeros((len(s), layout.count), bool)
        for i0 in range(0, len(s) - 1, max(1, int(CHUNK / step))):
            i1 = min(len(s), i0 + max(1, int(CHUNK / step)) + 1)
            want = open_sections(cmap, x[i0:i1], y[i0:i1], h[i0:i1], s[i0:i1], look, look_owner, layout)
            on[i0:i1] = want
            paint_strip(cmap, x[i0:i1], y[i0:i1], h[i0:i1], s[i0:i1], brush, brush_owner, want)
        strips += block_strips(x, y, h, on, layout)
    return strips


def block_strips(x: np.ndarray, y: np.ndarray, h: np.ndarray, on: np.ndarray, layout: SectionLayout) -> list:
    """Strips of the sections on (``on[i]`` from pose i to i + 1): one per run of poses with the same
    sections on and per block of adjacent sections on in it (few strips: their union stays quick)."""
    out = []
    code = on[:-1] @ (1 << np.arange(layout.count, dtype=np.int64)) if len(on) > 1 else np.zeros(0, np.int64)
    breaks = np.flatnonzero(np.diff(code)) + 1
    w = layout.section_width
    for i0, i1 in zip(np.concatenate([[0], breaks]), np.concatenate([breaks, [len(code)]])):
        state = on[i0]
        edges = np.diff(np.concatenate([[0], state.astype(int), [0]]))
        for j0, j1 in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
            offset = -0.5 * layout.width + 0.5 * (j0 + j1) * w
            sx = x[i0:i1 + 1] - offset * np.sin(h[i0:i1 + 1])
            sy = y[i0:i1 + 1] + offset * np.cos(h[i0:i1 + 1])
            if math.hypot(sx[-1] - sx[0], sy[-1] - sy[0]) > 1e-6:
                out.append(LineString(np.column_stack([sx, sy])).buffer(0.5 * (j1 - j0) * w, cap_style="flat"))
    return out


def crossings(plan, step: float = 0.25) -> int:
    """Times the tractor's side (the path's centre line kept ``half_width`` inside) leaves the
    field or enters a hole or an obstacle: runs of path points, every ``step`` m, outside the field
    shrunk by the half width (1 cm tolerance)."""
    inside = plan.field.boundary.buffer(-plan.settings.half_width + 0.01)
    count, was_in = 0, True
    for s in plan.path.knots(step, uniform=True):
        r = plan.path.evaluate(s)
        ok = contains_xy(inside, r["x"], r["y"])
        flags = np.concatenate([[was_in], ok])
        count += int(np.sum(flags[:-1] & ~flags[1:]))
        was_in = bool(ok[-1])
    return count


def applied_outside(applied: AsApplied, field: Polygon) -> float:
    """Area [m^2] the implement applied outside the field (beyond the boundary, in holes, on obstacles)."""
    return float(unary_union(applied.strips).difference(field).area) if applied.strips else 0.0


def summary(plan, applied: AsApplied, sections: int) -> dict:
    """The as-applied figures for plan.json."""
    return {"sections": sections, "field_coverage_share": round(applied.field_coverage_share, 5),
            "coverage_share": round(applied.coverage_share, 5), "overlap_share": round(applied.overlap_share, 5),
            "covered_ha": round(applied.covered / 1e4, 4), "overlap_ha": round(applied.overlap / 1e4, 4),
            "skipped_ha": round(applied.skipped / 1e4, 4),
            "applied_outside_m2": round(applied_outside(applied, plan.field.boundary), 2),
            "boundary_crossings": crossings(plan), **leftover_summary(plan, applied)}


def leftover_summary(plan, applied: AsApplied) -> dict:
    """The field left unworked, piece by piece with its area and why (fields.planner.leftovers)."""
    named, slivers = leftovers(plan, applied.shape)
    return {"leftovers": [x.summary() for x in named], "leftover_slivers_m2": round(slivers, 2)}
