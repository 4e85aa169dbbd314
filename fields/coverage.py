"""A coverage plan of a field (issue 27): headland passes, swaths, turns, a speed profile.

- **Headland**: ``headland_passes`` rings of the working width w inside the boundary (and around
  each hole); the swaths fill what is left (the boundary buffered in by n w). Auto: as many
  passes as the turns need to stay inside the field (their reach beyond the swath ends, the
  straight run-in of the implement's length and ``settle``, the tractor's half width, w/2), and
  up to 3 more when a turn at a slanted edge or a corner still leaves the field (noted).
- **Swaths**: straight lines w - overlap apart at the driving angle, each as long as its strip
  touches the inner field (a line crossing a hole or a bay gives several swaths). The angle is
  given, or chosen to minimise the number of swaths, hence of turns (ties: the longer mean
  swath); Fields2Cover's default objective is the same count.
- **Order**: boustrophedon when a U-turn fits between adjacent swaths (w >= about 2 R_min);
  otherwise rows are skipped in blocks (_skip_order: every move spans at least s lines, the
  smallest s whose s w fits a U-turn), so no turn loops round (an omega turn needs far more
  headland). Lines that give several swaths split the field into boustrophedon cells
  (_cells), each driven in that order, the nearest cell next.
- **Turns and transits**: continuous-curvature paths (fields.turns) within the curvature and the
  steering-rate limits; each is checked to stay inside the field with the tractor's half width.
  A move to another cell that would leave the field goes round the innermost headland pass.
- **Headland work**: after the swaths, each ring from the innermost out (either way round,
  whichever is nearer), once round and on by the implement's length, joined by
  continuous-curvature shifts. Corners are rounded (a tractor cannot follow a polygon's corner):
  the innermost pass at R, each further out at w more, so that the passes are parallel and leave
  no gap between them at the corners.
- **Speed**: working speed on swaths and headland passes, turn speed in turns and transits,
  changes at ``acceleration``.

Everything is in the field's local metres (fields.field). ``workable`` is what the implement can
reach: the field opened by a disk of radius R_o + w/2 + (R - R_i), R_o = R + (n - 1) w the outer
headland pass's corner radius, R_i the trailed implement's steady radius when the tractor turns
at R (it cuts each corner by R - R_i).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field as dc_field

import numpy as np
from shapely import affinity
from shapely.geometry import LineString, MultiLineString, Point, Polygon

from .field import Field, FieldError, polygons
from .turns import Limits, connect, integrate

SWATH, TURN, HEADLAND, TRANSIT = 0, 1, 2, 3
KINDS = {SWATH: "swath", TURN: "turn", HEADLAND: "headland", TRANSIT: "transit"}


@dataclass(frozen=True)
class Settings:
    working_width: float = 3.0            # m
    headland_passes: int = 0              # 0: as many as the turns need
    driving_angle: float | None = None    # rad, east = 0, counter-clockwise; None: fewest swaths
    guidance_line: str = ""               # else along this guidance line of the field ("*": its first)
    turn_radius: float = 4.0              # m: the tractor's smallest (well above its 45 deg lock)
    wheelbase: float = 1.4                # m
    steer_rate: float = math.radians(30)  # rad/s the turns may ask (the hydraulics do 60)
    work_speed: float = 2.0               # m/s
    turn_speed: float = 1.0               # m/s
    acceleration: float = 0.5             # m/s^2
    overlap: float = 0.05                 # m between adjacent passes
    order: str = "auto"                   # auto, boustrophedon, skip
    half_width: float = 0.8               # m: the tractor's, kept inside the boundary
    hitch_offset: float = 0.6             # m behind the rear axle
    drawbar: float = 2.5                  # m hitch to implement axle (0: a mounted implement)
    headland_work: bool = True            # drive the headland passes after the swaths
    settle: float = 5.0                   # m driven straight before a swath beyond the implement's length
    swath_extension: float = 0.1          # m each swath works on beyond its strip's reach (lift and drop margin)
    max_swaths: int = 0                   # 0: all; else the first N (a section of a field, for tests)

    def check(self, where: str) -> None:
        for name in ("working_width", "turn_radius", "wheelbase", "steer_rate", "work_speed", "turn_speed",
                     "acceleration"):
            if not getattr(self, name) > 0:
                raise FieldError(f"{where}: {name} = {getattr(self, name)}: expected a positive number")
        if self.order not in ("auto", "boustrophedon", "skip"):
            raise FieldError(f"{where}: order = {self.order!r}: expected auto, boustrophedon or skip")
        for name in ("headland_passes", "hitch_offset", "drawbar", "half_width", "settle", "swath_extension",
                     "max_swaths"):
            if not getattr(self, name) >= 0:
                raise FieldError(f"{where}: {name} = {getattr(self, name)}: expected zero or more")
        if not 0 <= self.overlap < 0.5 * self.working_width:
            raise FieldError(f"{where}: overlap = {self.overlap} m: expected 0 to half the working width")

    @property
    def lead(self) -> float:
        """Straight run before and after each swath: the implement (hitch + drawbar behind the
        rear axle) is on the line, and the loop has settled, when the work starts."""
        return self.hitch_offset + self.drawbar + self.settle

    @property
    def implement_radius(self) -> float:
        """R_i: the implement's steady radius when the rear axle runs on R (hitch c behind, drawbar L)."""
        r2 = self.turn_radius ** 2 + self.hitch_offset ** 2 - self.drawbar ** 2
        return math.sqrt(max(r2, 0.25 * self.turn_radius ** 2))


@dataclass
class Segment:
    kind: int
    index: int                  # swath number, ring number, or -1
    path: np.ndarray            # (N, 4) x, y, heading, curvature


@dataclass
class Plan:
    field: Field
    settings: Settings
    angle: float
    angle_how: str
    headland_passes: int
    inner: Polygon
    workable: Polygon
    segments: list[Segment]
    order_how: str
    notes: list[str] = dc_field(default_factory=list)
    route: dict | None = None

    @property
    def swaths(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(start, end) of each swath in driving order."""
        return [(seg.path[0, :2], seg.path[-1, :2]) for seg in self.segments if seg.kind == SWATH]

    def summary(self) -> dict:
        r = self.route
        ds = np.diff(r["s"], append=r["s"][-1])
        dist = {k: float(np.sum(ds[r["kind"] == k])) for k in KINDS}
        time = float(np.sum(ds / np.maximum(r["speed"], 0.1)))
        turns = max(len(self.swaths) - 1, 0)
        return {"field": self.field.name, "area_ha": round(self.field.area_ha, 4),
                "workable_ha": round(self.workable.area / 1e4, 4), "driving_angle_deg": round(math.degrees(self.angle), 2),
                "driving_angle_how": self.angle_how, "order": self.order_how, "headland_passes": self.headland_passes,
                "swaths": len(self.swaths), "turns": turns, "distance_m": round(float(r["s"][-1]), 1),
                "working_distance_m": round(dist[SWATH] + dist[HEADLAND], 1), "turn_distance_m": round(dist[TURN], 1),
                "transit_distance_m": round(dist[TRANSIT], 1), "estimated_time_s": round(time, 1),
                "working_width_m": self.settings.working_width, "turn_radius_m": self.settings.turn_radius,
                "notes": self.notes}


def plan(field: Field, settings: Settings = Settings()) -> Plan:
    where = f"{field.source}: field {field.name!r}"
    settings.check(where)
    problems = field.problems()
    if problems:
        raise FieldError(f"{where}: {problems[0]}")
    w = settings.working_width
    limits = Limits.of(settings.turn_radius, settings.wheelbase, settings.steer_rate, settings.turn_speed)
    spacing = w - settings.overlap
    order, skip, reach = _order_and_reach(spacing, limits, settings)
    # the turn's reach, the straight run-in and out, the tractor's half width from the boundary, a margin
    needed = reach + settings.lead + settings.half_width + 0.5 * w + 0.2       # + w/2: _swath_lines
    n_h = settings.headland_passes or max(1, math.ceil(needed / w))
    notes = []
    if settings.headland_passes and n_h * w < needed:
        raise FieldError(f"{where}: the turns do not fit the headland: a turn reaches {reach:.1f} m beyond the swath "
                         f"ends after a straight run of {settings.lead:.1f} m (the implement's length and settling), "
                         f"{needed:.1f} m in all, but {n_h} headland pass(es) of {w:g} m give {n_h * w:.1f} m (turn "
                         f"radius {settings.turn_radius:g} m); use {math.ceil(needed / w)} passes or a smaller turn radius")
    first, refused = n_h, None
    while True:
        try:
            plan_ = _layout(field, settings, n_h, order, skip, limits, where, list(notes))
            break
        except TurnOutside as exc:
            # auto headland: a turn at a slanted edge or a corner needs more room than the straight
            # U-turn's reach; widen by a pass (up to 3) rather than refuse the field
            if settings.headland_passes or n_h >= first + 3:
                raise FieldError(str(exc)) from None
            n_h, refused = n_h + 1, exc
        except FieldError:
            if refused is None:
                raise
            raise FieldError(str(refused)) from None          # widening left too little: the turn is the cause
    if n_h > first:
        plan_.notes.append(f"headland widened from {first} to {n_h} passes: a turn at a slanted edge or a corner needed "
                           f"the room")
    plan_.route = _route(plan_)
    return plan_


class TurnOutside(FieldError):
    """A turn between swaths leaves the field (plan() may widen the headland)."""


def _layout(field: Field, settings: Settings, n_h: int, order: str, skip: int, limits: Limits, where: str,
            notes: list[str]) -> Plan:
    """Inner field, driving angle, swaths, turns and headland passes for n_h headland passes."""
    w, spacing = settings.working_width, settings.working_width - settings.overlap
    inner = field.boundary.buffer(-n_h * w, join_style="mitre", mitre_limit=3.0)
    parts = [p for p in polygons(inner) if p.area > w * w]
    if not parts or _min_width(max(parts, key=lambda p: p.area)) < 2 * w:
        raise FieldError(f"{where}: the field is narrower than two working widths ({2 * w:g} m) inside its "
                         f"{n_h} headland pass(es) of {w:g} m (its narrowest width there: "
                         f"{_min_width(max(parts, key=lambda p: p.area)) if parts else 0.0:.1f} m)")
    inner = max(parts, key=lambda p: p.area)
    if len(parts) > 1:
        notes.append(f"the inner field falls apart into {len(parts)} pieces; the largest ({inner.area / 1e4:.2f} ha) "
                     f"is worked")
    if settings.driving_angle is None and settings.guidance_line:
        angle, angle_how = _along_line(field, settings.guidance_line, where)
    else:
        angle, angle_how = _angle(inner, spacing, settings.driving_angle)
    lines = _swath_lines(inner, angle, spacing, w)
    if settings.max_swaths:
        notes.append(f"a section of the field: the first {min(settings.max_swaths, len(lines))} swath(s) of the route")
    plan_ = Plan(field, settings, angle, angle_how, n_h, inner, _workable(field, settings, n_h), [],
                 f"{order}" + (f" (skip {skip})" if order == "skip" else ""), notes)
    _swaths_and_turns(plan_, lines, skip, limits, where)
    if settings.headland_work and not settings.max_swaths:
        _headland(plan_, limits, where)
    return plan_


# --- geometry -----------------------------------------------------------------------------------------
def _min_width(poly: Polygon) -> float:
    rect = poly.minimum_rotated_rectangle
    xy = np.asarray(rect.exterior.coords)
    sides = np.hypot(*np.diff(xy, axis=0).T)
    return float(min(sides[:2])) if len(sides) >= 2 else 0.0


def _along_line(field: Field, name: str, where: str) -> tuple[float, str]:
    """The driving angle of the field's guidance line (an AB line's heading, a curve's ends)."""
    found = field.lines[:1] if name == "*" else [g for g in field.lines if g.name == name]
    if not found:
        have = ", ".join(repr(g.name) for g in field.lines) or "none"
        raise FieldError(f"{where}: guidance_line = {name!r}: the field has no such guidance line (it has {have})")
    line = found[0]
    return line.heading % math.pi, f"along the field's {line.kind} {line.name!r}"


def _angle(inner: Polygon, spacing: float, given: float | None) -> tuple[float, str]:
    if given is not None:
        return float(given) % math.pi, "given"
    best = None
    for deg in np.arange(0.0, 180.0, 1.0):
        a = math.radians(deg)
        rot = affinity.rotate(inner, -deg, origin=(0, 0))
        minx, miny, maxx, maxy = rot.bounds
        count = math.ceil((maxy - miny) / spacing)
        mean_length = inner.area / max(count, 1)
        key = (count, -mean_length)
        if best is None or key < best[0]:
            best = (key, a)
    return best[1], f"chosen: the fewest swaths ({best[0][0]}), hence the fewest turns; ties by the longer swath"


def _swath_lines(inner: Polygon, angle: float, spacing: float, width: float) -> list[list[tuple[np.ndarray, np.ndarray]]]:
    """Per line across the field, its swaths (start, end) along the driving direction. The
    ceil(H / spacing) lines across the inner field's height H leave some slack; where they sit
    in it is chosen (9 shifts) to leave the least of the inner field unworked: an inner edge at
    a small angle to the swaths leaves a wedge beside the outermost swath, and the shift puts
    the slack on the other side. Each swath runs as far as its strip (width w) touches the inner
    field, on the line within w/2 of it: the strip covers the corners where an edge crosses the
    swaths at a slant, and a line just outside a near-parallel edge still works the wedge
    beside it. Its ends are thus at most w/2 outside the inner field (plan() counts that in the
    headland)."""
    from shapely.ops import unary_union

    deg = math.degrees(angle)
    rot = affinity.rotate(inner, -deg, origin=(0, 0))
    minx, miny, maxx, maxy = rot.bounds
    count = math.ceil((maxy - miny) / spacing)
    best = None
    for share in np.linspace(0.0, 1.0, 9):
        first = miny + share * ((maxy - miny) - (count - 1) * spacing)
        strips = unary_union([LineString([(minx - 1, first + k * spacing), (maxx + 1, first + k * spacing)])
                              .buffer(0.5 * width, cap_style="flat") for k in range(count)])
        missed = rot.difference(strips).area
        if best is None or missed < best[0] - 1e-6 or (abs(missed - best[0]) <= 1e-6 and abs(share - 0.5) < abs(best[2] - 0.5)):
            best = (missed, first, share)
    offset = best[1]
    c, s = math.cos(angle), math.sin(angle)
    w_pad = width + 1.0
    near = rot.buffer(0.5 * width, join_style="mitre", mitre_limit=3.0)
    out = []
    for k in range(count):
        yk = offset + k * spacing
        band = rot.intersection(LineString([(minx - 1, yk), (maxx + 1, yk)]).buffer(0.5 * width, cap_style="flat"))
        cut = near.intersection(LineString([(minx - w_pad, yk), (maxx + w_pad, yk)]))
        pieces = [g for g in (cut.geoms if isinstance(cut, MultiLineString) else [cut]) if isinstance(g, LineString)]
        segs = []
        for g in sorted(pieces, key=lambda g: min(g.coords[0][0], g.coords[-1][0])):
            x0, x1 = sorted((g.coords[0][0], g.coords[-1][0]))
            # the part of the line whose strip touches the inner field
            part = band.intersection(LineString([(x0, yk), (x1, yk)]).buffer(0.5 * width, cap_style="flat"))
            if part.is_empty:
                continue
            x0, x1 = max(x0, part.bounds[0]), min(x1, part.bounds[2])
            if x1 - x0 < 1.0:
                continue
            a = np.array([c * x0 - s * yk, s * x0 + c * yk])
            b = np.array([c * x1 - s * yk, s * x1 + c * yk])
            segs.append((a, b))
        if segs:
            out.append(segs)
    return out


def _workable(field: Field, settings: Settings, passes: int) -> Polygon:
    outer = settings.turn_radius + (passes - 1) * settings.working_width
    rho = outer + 0.5 * settings.working_width + (settings.turn_radius - settings.implement_radius)
    opened = field.boundary.buffer(-rho).buffer(rho)
    return max(polygons(opened), key=lambda p: p.area) if polygons(opened) else field.boundary


# --- order and turns ---------------------------------------------------------------------------------------
def _u_turn(D: float, limits: Limits) -> np.ndarray | None:
    """The CC turn between two swaths D apart (the second to the left), or None."""
    return connect((0.0, 0.0, 0.0), (0.0, D, math.pi), limits)


def _reach(path: np.ndarray) -> float:
    return float(np.max(path[:, 0]))


def _order_and_reach(spacing: float, limits: Limits, settings: Settings) -> tuple[str, int, float]:
    """(order, skip, how far its turns reach beyond the swath ends)."""
    def csc(D):          # a U-turn of turn-straight-turn turning through pi once: no loop
        p = connect((0.0, 0.0, 0.0), (0.0, D, math.pi), limits, families=("LSL",))
        return p is not None and np.all(np.diff(p[:, 2]) >= -1e-9) and np.ptp(p[:, 2]) <= math.pi + 1e-6
    fits = csc(spacing)
    if settings.order == "boustrophedon" or (settings.order == "auto" and fits):
        return "boustrophedon", 1, _reach(_u_turn(spacing, limits))
    u_min = spacing
    while not fits and u_min < 10 * settings.turn_radius + 10 * spacing:
        u_min += 0.25 * spacing
        fits = csc(u_min)
    s = max(2, math.ceil(u_min / spacing))
    reach = max(_reach(_u_turn(s * spacing, limits)), _reach(_u_turn((s + 1) * spacing, limits)))
    return "skip", s, reach


def _skip_order(n: int, s: int) -> list[int]:
    """An order of n parallel swaths in which every move spans at least s lines (a U-turn each),
    in blocks of 2s (the last takes the rest): an even block b..b+2h-1 goes b+h, b, b+h+1, b+1,
    ..., b+2h-1, b+h-1; an odd one b+h-1, b, b+h, b+1, ..., b+h-2, b+2h-2. Moves within a block
    span h and h - 1 lines, between blocks more. Fewer than 2s swaths: some moves are shorter
    (omega turns)."""
    sizes = [2 * s] * max(1, n // (2 * s))
    sizes[-1] += n - sum(sizes)
    out, b = [], 0
    for k in sizes:
        if k % 2 == 0:
            h = k // 2
            for i in range(h):
                out += [b + h + i, b + i]
        else:
            h = (k + 1) // 2
            for i in range(h - 1):
                out += [b + h - 1 + i, b + i]
            out.append(b + 2 * h - 2)
        b += k
    return out


def _swaths_and_turns(plan_: Plan, lines, skip: int, limits: Limits, where: str) -> None:
    settings = plan_.settings
    inside = plan_.field.boundary.buffer(-settings.half_width)
    cells = _cells(lines, plan_.angle)
    chosen, ids, firsts = _cell_order(cells, skip)
    if len(cells) > 1:
        plan_.order_how += f" in {len(cells)} cells (lines that cross holes or bays give several swaths)"
    if settings.max_swaths:
        chosen, ids = chosen[:settings.max_swaths], ids[:settings.max_swaths]
    previous = None
    for k, ((a, b), idx) in enumerate(zip(chosen, ids)):
        start, end = _entered(a, b, None if previous is None else previous[:2])
        heading = math.atan2(end[1] - start[1], end[0] - start[0])
        direction = np.array([math.cos(heading), math.sin(heading)])
        start, end = start - settings.swath_extension * direction, end + settings.swath_extension * direction
        run_in = start - settings.lead * direction
        if previous is not None:
            turn = connect(previous, (run_in[0], run_in[1], heading), limits)
            if turn is None:
                raise FieldError(f"{where}: no turn within the limits from swath {ids[k - 1]} to swath {idx}")
            path = np.vstack([turn, _straight(run_in, start)[1:]])
            outside = _outside(path, inside)
            if outside is not None and k in firsts:           # to another cell: round by the headland
                via = _via_headland(plan_, previous, (run_in[0], run_in[1], heading), limits, inside)
                if via is not None:
                    plan_.segments.append(Segment(TRANSIT, -1, via))
                    path, outside = _straight(run_in, start), None
            if outside is not None:
                raise TurnOutside(f"{where}: the turn from swath {ids[k - 1]} to swath {idx} leaves the field near "
                                 f"({outside[0]:.1f}, {outside[1]:.1f}) m: the headland ({plan_.headland_passes} x "
                                 f"{settings.working_width:g} m) cannot hold a turn of radius {settings.turn_radius:g} m")
        else:
            path = _straight(run_in, start)
        plan_.segments.append(Segment(TURN, -1, path))
        plan_.segments.append(Segment(SWATH, idx, _straight(start, end)))
        run_out = end + settings.lead * direction
        plan_.segments.append(Segment(TURN, -1, _straight(end, run_out)))
        previous = (run_out[0], run_out[1], heading)


def _entered(a: np.ndarray, b: np.ndarray, pos) -> tuple[np.ndarray, np.ndarray]:
    """(start, end) of a swath entered from its end nearer pos (a first when pos is None): after
    a U-turn that is the alternate direction."""
    return (a, b) if pos is None or np.hypot(*(a - pos)) <= np.hypot(*(b - pos)) else (b, a)


def _cells(lines, angle: float) -> list[list[tuple[int, tuple]]]:
    """Boustrophedon cells: runs of consecutive lines whose swaths continue one another (a swath
    continues the one before if each overlaps only the other along the driving direction). A
    convex field is one cell; a hole or a bay splits the lines there into several."""
    d = np.array([math.cos(angle), math.sin(angle)])
    cells: list[list[tuple[int, tuple]]] = []
    previous: list[tuple[float, float, int]] = []
    for i, segs in enumerate(lines):
        spans = [tuple(sorted((float(a @ d), float(b @ d)))) for a, b in segs]
        current = []
        for seg, (x0, x1) in zip(segs, spans):
            touching = [p for p in previous if p[0] < x1 and x0 < p[1]]
            cell = None
            if len(touching) == 1:
                p = touching[0]
                if sum(1 for y0, y1 in spans if y0 < p[1] and p[0] < y1) == 1:
                    cell = p[2]
            if cell is None:
                cells.append([])
                cell = len(cells) - 1
            cells[cell].append((i, seg))
            current.append((x0, x1, cell))
        previous = current
    return cells


def _walk(items, pos) -> np.ndarray:
    """Where a sequence of swaths ends, each entered from its nearer end."""
    for _, (a, b) in items:
        pos = _entered(a, b, pos)[1]
    return pos


def _cell_order(cells, skip: int) -> tuple[list, list]:
    """The swaths in driving order: each cell in the skip order (boustrophedon when skip is 1),
    forwards or backwards; from the first cell on, the nearest unvisited cell next (by the
    straight distance to its first swath's nearer end)."""
    def sequence(cell):
        n = len(cell)
        return [cell[k] for k in (range(n) if skip == 1 else _skip_order(n, skip))]

    left = list(range(len(cells)))
    out, pos, firsts = [], None, set()
    while left:
        options = [(c, seq) for c in left for seq in (sequence(cells[c]), sequence(cells[c])[::-1])]
        if pos is None:
            c, seq = options[0]
        else:
            c, seq = min(options, key=lambda o: min(np.hypot(*(o[1][0][1][0] - pos)), np.hypot(*(o[1][0][1][1] - pos))))
        left.remove(c)
        firsts.add(len(out))
        out += seq
        pos = _walk(seq, pos)
    return [seg for _, seg in out], [i for i, _ in out], firsts


def _via_headland(plan_: Plan, a, b, limits: Limits, inside) -> np.ndarray | None:
    """A transit from pose a to pose b along the innermost headland pass (either way round, the
    field's outer ring or a hole's), joined by continuous-curvature turns; the shortest inside
    the field, or None."""
    settings = plan_.settings
    w = settings.working_width
    rings = ring_path(plan_.field, (plan_.headland_passes - 0.5) * w, settings.turn_radius)
    best = None
    for ring in rings:
        for way in (ring, _reversed_ring(ring)):
            n = len(way)
            i0 = int(np.argmin(np.hypot(way[:, 0] - a[0], way[:, 1] - a[1])))
            j0 = int(np.argmin(np.hypot(way[:, 0] - b[0], way[:, 1] - b[1])))
            for lead in (10.0, 20.0, 30.0):
                i, j = (i0 + int(lead / 0.5)) % n, (j0 - int(lead / 0.5)) % n
                along = way[i:j + 1] if j >= i else np.vstack([way[i:], way[:j + 1]])
                if len(along) < 2:
                    continue
                onto, off = connect(a, way[i, :3], limits), connect(way[j, :3], b, limits)
                if onto is None or off is None:
                    continue
                path = np.vstack([onto, along[1:-1], off])
                length = _length_of(path)
                if (best is None or length < best[0]) and _outside(path, inside) is None:
                    best = (length, path)
                    break
    return None if best is None else best[1]


def _outside(path: np.ndarray, inside: Polygon):
    from shapely import contains_xy

    ok = contains_xy(inside, path[:, 0], path[:, 1])
    return None if ok.all() else path[int(np.argmin(ok)), :2]


def _straight(a: np.ndarray, b: np.ndarray, step: float = 0.5) -> np.ndarray:
    n = max(2, int(math.ceil(np.hypot(*(b - a)) / step)) + 1)
    s = np.linspace(0.0, 1.0, n)[:, None]
    xy = a + s * (b - a)
    heading = math.atan2(b[1] - a[1], b[0] - a[0])
    return np.column_stack([xy, np.full(n, heading), np.zeros(n)])


# --- headland passes ---------------------------------------------------------------------------------------
def ring_path(field: Field, offset: float, radius: float) -> list[np.ndarray]:
    """The closed paths at ``offset`` inside the boundary (and around each hole), corners rounded
    to ``radius``: (N, 4) x, y, heading, curvature, counter-clockwise around the field. Passes
    whose offset + radius is the same are parallel (no gap between them at the corners): the
    innermost turns at R, each further out at w more."""
    shape = field.boundary.buffer(-(offset + radius)).buffer(radius, quad_segs=16)
    out = []
    for poly in polygons(shape):
        for ring, ccw in [(poly.exterior, True)] + [(r, False) for r in poly.interiors]:
            xy = np.asarray(LineString(ring.coords).segmentize(0.5).coords)[:-1]
            out.append(_closed_path(xy[::-1] if ring.is_ccw != ccw else xy))
    return out


def _closed_path(xy: np.ndarray) -> np.ndarray:
    """(N, 4) x, y, heading (towards the next point, unwrapped), curvature of a closed polyline."""
    d = np.diff(np.vstack([xy, xy[:1]]), axis=0)
    heading = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    ds = np.hypot(d[:, 0], d[:, 1])
    curvature = np.gradient(heading) / np.maximum(ds, 1e-6)
    return np.column_stack([xy, heading, curvature])


def _headland(plan_: Plan, limits: Limits, where: str) -> None:
    settings = plan_.settings
    w, R = settings.working_width, settings.turn_radius
    last = plan_.segments[-1].path[-1, :3]
    inside = plan_.field.boundary.buffer(-settings.half_width)
    for k in range(plan_.headland_passes - 1, -1, -1):
        rings = ring_path(plan_.field, (k + 0.5) * w, R + (plan_.headland_passes - 1 - k) * w)
        for j, ring in enumerate(rings):
            best = None
            for way in (ring, _reversed_ring(ring)):          # either way round: the shorter way on
                found = _onto_ring(last, way, limits, inside)
                if found is not None and (best is None or _length_of(found[0]) < _length_of(best[0])):
                    best = (*found, way)
            if best is None:
                plan_.notes.append(f"headland pass {k + 1}{'' if j == 0 else f' (hole {j})'}: no turn onto it "
                                   f"within the field; left out")
                continue
            path, i, ring = best
            plan_.segments.append(Segment(TRANSIT, k, path))
            # once round and on by the implement's length, so that it closes the loop where it came in
            more = int(math.ceil((settings.hitch_offset + settings.drawbar + 1.0) / 0.5))
            loop = np.vstack([ring[i:], ring[:i + 1], ring[i + 1:][:more], ring[:max(0, more - (len(ring) - i - 1))]])
            plan_.segments.append(Segment(HEADLAND, k, loop))
            last = loop[-1, :3].copy()
            last[2] = math.atan2(*(loop[-1, 1::-1] - loop[-2, 1::-1]))


def _reversed_ring(ring: np.ndarray) -> np.ndarray:
    """A ring path driven the other way round."""
    return _closed_path(ring[::-1, :2])


def _length_of(path: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(path[:, :2], axis=0).T)))


def _onto_ring(pose, ring: np.ndarray, limits: Limits, inside) -> tuple[np.ndarray, int] | None:
    """(path, index): a turn from pose onto the ring a little along it from its nearest points,
    inside the field, or None."""
    candidates = np.argsort(np.hypot(ring[:, 0] - pose[0], ring[:, 1] - pose[1]))
    for lead in (8.0, 14.0, 20.0, 30.0):        # join the ring this far along it (metres)
        for i0 in candidates[:5]:
            i = (i0 + int(lead / 0.5)) % len(ring)
            path = connect(pose, ring[i, :3], limits)
            if path is not None and _outside(path, inside) is None:
                return path, int(i)
    return None


# --- the route ---------------------------------------------------------------------------------------------
def _route(plan_: Plan, step: float = 0.1) -> dict:
    """The segments joined and resampled every ``step`` m: s, x, y, heading, curvature, speed,
    kind, index (swath or ring)."""
    settings = plan_.settings
    xs, ys, kinds, idx, kappa = [], [], [], [], []
    for seg in plan_.segments:
        p = seg.path
        xs.append(p[:, 0]), ys.append(p[:, 1])
        kinds.append(np.full(len(p), seg.kind)), idx.append(np.full(len(p), seg.index)), kappa.append(p[:, 3])
    x, y = np.concatenate(xs), np.concatenate(ys)
    keep = np.concatenate([[True], np.hypot(np.diff(x), np.diff(y)) > 1e-6])
    x, y, kind, index, curv = x[keep], y[keep], np.concatenate(kinds)[keep], np.concatenate(idx)[keep], np.concatenate(kappa)[keep]
    s_raw = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    s = np.arange(0.0, s_raw[-1], step)
    X, Y = np.interp(s, s_raw, x), np.interp(s, s_raw, y)
    j = np.clip(np.searchsorted(s_raw, s, side="right") - 1, 0, len(s_raw) - 1)
    K, I, C = kind[j], index[j], np.interp(s, s_raw, curv)
    heading = np.unwrap(np.arctan2(np.gradient(Y), np.gradient(X)))
    target = np.where((K == SWATH) | (K == HEADLAND), settings.work_speed, settings.turn_speed)
    speed = _speed_profile(target, step, settings.acceleration)
    return {"s": s, "x": X, "y": Y, "heading": heading, "curvature": C, "speed": speed, "kind": K, "index": I}


def _speed_profile(target: np.ndarray, step: float, accel: float) -> np.ndarray:
    """The highest speed under ``target`` that changes at most at ``accel`` (forward and backward
    passes of v^2 <= v0^2 + 2 a ds), from a crawl (0.3 m/s: a reference that moves off) at the
    start to one at the end."""
    v = target.astype(float).copy()
    v[0] = v[-1] = min(0.3, float(target.min()))
    for i in range(1, len(v)):
        v[i] = min(v[i], math.sqrt(v[i - 1] ** 2 + 2 * accel * step))
    for i in range(len(v) - 2, -1, -1):
        v[i] = min(v[i], math.sqrt(v[i + 1] ** 2 + 2 * accel * step))
    return v
