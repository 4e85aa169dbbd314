"""A coverage plan of a field, in stages (after Fields2Cover):

    headland -> decomposition -> swaths (an angle objective) -> route order -> turns -> speed profile
             -> passes of their own for what is left (fields.planner.leftover_passes)

Before any of it the settings and the field are checked (finite values in range, coordinates on
the Earth, a number of swaths that fits memory, a turn radius the field can hold), so that a plan
that cannot be made is refused at once, naming the value. The auto headland widens by a pass (up
to 3) when a turn at a slanted edge or a corner leaves the field.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field as dc_field, replace

from shapely.geometry import MultiPolygon, Polygon
from shapely.ops import unary_union

from ..field import Field, FieldError
from . import decomposition, headland, leftover_passes, route_order, swaths
from .applied import as_applied
from .path import Path
from .settings import Settings
from .speed import speed_profile
from .turns import Joiner, TurnOutside, length_of
from .types import HEADLAND, SWATH, TRANSIT, TURN, Cell, Route, Swath

MAX_SWATHS = 20_000     # across a field at the fewest: about 1 GB of path (a 60 km wide field of a 3 m implement)
MORE_PASSES = 3         # the auto headland widens by at most this many passes


@dataclass(frozen=True, eq=False)
class Plan:
    field: Field
    settings: Settings
    angle: float                # rad, east = 0, counter-clockwise
    angle_how: str
    headland_passes: int
    inner: Polygon | MultiPolygon   # what the swaths fill: every piece of the inner field
    workable: Polygon           # what the implement can reach
    cells: tuple[Cell, ...]
    route: Route
    path: Path
    notes: tuple[str, ...] = dc_field(default_factory=tuple)
    pieces: tuple[Polygon, ...] = ()        # the inner field's pieces, the largest first
    angles: tuple[float, ...] = ()          # the driving angle [rad] of each piece
    leftover_passes: tuple[Swath, ...] = ()  # driven after the route's passes, as driven (fields.planner.leftover_passes)

    @property
    def order_how(self) -> str:
        return self.route.how

    @property
    def swaths(self) -> list[Swath]:
        """The field's swaths as driven (oriented, extended), in driving order (the leftovers' own
        passes, driven after them, are ``leftover_passes``)."""
        return self.route.swaths

    def summary(self) -> dict:
        dist = self.path.distances()
        return {"field": self.field.name, "area_ha": round(self.field.area_ha, 4),
                "workable_ha": round(self.workable.area / 1e4, 4), "driving_angle_deg": round(math.degrees(self.angle), 2),
                "pieces": len(self.pieces), "piece_angles_deg": [round(math.degrees(a), 2) for a in self.angles],
                "driving_angle_how": self.angle_how, "order": self.order_how, "headland_passes": self.headland_passes,
                "swaths": len(self.swaths), "leftover_passes": len(self.leftover_passes),
                "turns": max(len(self.swaths) + len(self.leftover_passes) - 1, 0),
                "distance_m": round(self.path.length, 1), "working_distance_m": round(dist[SWATH] + dist[HEADLAND], 1),
                "turn_distance_m": round(dist[TURN], 1), "transit_distance_m": round(dist[TRANSIT], 1),
                "estimated_time_s": round(self.path.time(), 1), "working_width_m": self.settings.working_width,
                "turn_radius_m": self.settings.turn_radius, "notes": list(self.notes)}


def check_field(field: Field, settings: Settings, where: str) -> None:
    """What can be known before planning: a simple polygon on the Earth (Field.problems), not too
    many swaths across, wide enough for the turns (a U-turn reaches at least R beyond the swath ends: its
    heading passes pi/2 with |kappa| <= 1/R, so x >= R int_0^{pi/2} cos = R)."""
    problems = field.problems()
    if problems:
        raise FieldError(f"{where}: {problems[0]}")
    across = decomposition.min_width(field.boundary)
    fewest = across / settings.spacing
    if fewest > MAX_SWATHS:
        raise FieldError(f"{where}: the field is {across / 1e3:.1f} km across at its narrowest: about "
                         f"{fewest:,.0f} swaths of {settings.spacing:g} m, more than the {MAX_SWATHS:,} planned at once; "
                         f"plan it in parts or with a wider working width")
    lowest = headland.width_needed(settings.turn_radius, settings)
    if across <= 2 * lowest:
        w = settings.working_width
        raise FieldError(f"{where}: the field is narrower than two working widths ({2 * w:g} m) inside the headland its "
                         f"turns need: with turn radius {settings.turn_radius:g} m a turn needs at least {lowest:.1f} m "
                         f"on each side (the radius, a straight run of {settings.lead:.1f} m, the tractor's half width "
                         f"and half the working width), but the field is {across:.1f} m across at its narrowest; use a "
                         f"smaller turn radius or a shorter run")


def plan(field: Field, settings: Settings = Settings()) -> Plan:
    where = f"{field.source}: field {field.name!r}"
    settings.check(where)
    check_field(field, settings, where)
    order, skip, reach = route_order.pattern(settings)
    needed = headland.width_needed(reach, settings)
    n = first = headland.passes(needed, settings, reach, where)
    refused = None
    while True:
        try:
            return _layout(field, settings, n, order, skip, where, [] if n == first else
                           [f"headland widened from {first} to {n} passes: a turn at a slanted edge or a corner needed "
                            f"the room"])
        except TurnOutside as exc:
            # auto headland: a turn at a slanted edge or a corner needs more room than the straight
            # U-turn's reach; widen by a pass rather than refuse the field
            if settings.headland_passes or n >= first + MORE_PASSES:
                raise FieldError(str(exc)) from None
            n, refused = n + 1, exc
        except FieldError:
            if refused is None:
                raise
            raise FieldError(str(refused)) from None          # widening left too little: the turn is the cause


def _layout(field: Field, settings: Settings, n: int, order: str, skip: int, where: str, widened: list[str]) -> Plan:
    """Every stage for n headland passes: each piece of the inner field its own swaths and cells."""
    notes: list[str] = []
    w = settings.working_width
    pieces = decomposition.worked_regions(headland.inner_parts(field, n, w), w, n, where, notes)
    cells: list[Cell] = []
    angles, hows, count = [], [], 0
    for k, piece in enumerate(pieces):
        first = sum(len(c.swaths) for c in cells)
        lines, along, angle, how = swaths.generate(field, piece, settings, where, first, count)
        count += len(lines) + 1                 # a line number left out between pieces: not neighbours
        cells += decomposition.cells(lines, along, len(cells), k)
        angles.append(angle)
        hows.append(how)
    if settings.max_swaths:
        notes.append(f"a section of the field: the first {min(settings.max_swaths, count)} swath(s) of the route")
    rings = headland.headland_passes(field, settings, n) if settings.headland_work and not settings.max_swaths else []
    route = route_order.route(cells, skip, order, settings, rings)
    segments = Joiner(field, settings, n, where, notes, pieces).join(route)
    if order == "optimised":
        route, segments = _least_idle(field, route, segments, cells, skip, settings, rings, n, where, notes, pieces)
    inner = pieces[0] if len(pieces) == 1 else unary_union(pieces)
    draft = Plan(field, settings, angles[0], hows[0], n, inner, headland.workable(field, settings, n), tuple(cells), route,
                 _path(segments, settings), tuple(notes + widened), tuple(pieces), tuple(angles))
    first = max([count] + [sw.index + 1 for c in cells for sw in c.swaths])    # numbers no swath has
    return _with_leftover_passes(draft, first, where, pieces)


def _path(segments, settings: Settings) -> Path:
    return Path(segments, lambda starts, ends, kinds: speed_profile(starts, ends, kinds, settings))


def _with_leftover_passes(draft: Plan, first: int, where: str, pieces) -> Plan:
    """The plan with passes of its own for what it leaves (fields.planner.leftover_passes) driven
    after the rest, when ``leftover_passes`` is on and the route works the whole field; the choice in
    the notes either way."""
    s = draft.settings
    if s.max_swaths or not s.headland_work:
        return draft
    if not s.leftover_passes:
        return replace(draft, notes=draft.notes + ("leftover passes off: what the route leaves is named in plan.json, "
                                                   "not worked (--leftover-passes on works it)",))
    extra, what = leftover_passes.passes(draft, as_applied(draft).shape, first)
    if not extra:
        return replace(draft, notes=draft.notes + (f"leftover passes: {what}",))
    notes: list[str] = []
    try:
        segments, joined = Joiner(draft.field, s, draft.headland_passes, where, notes, pieces).more(
            list(draft.path.segments), extra)
    except FieldError:                    # no way from the last of them to the user's end point: the route as it was
        return replace(draft, notes=draft.notes + (f"leftover passes: {what}; left out: no way from them to the "
                                                   "end point inside the field",))
    route = Route(draft.route.passes, draft.route.cell_starts, draft.route.how + f"; then {len(joined)} leftover "
                  "pass(es)")
    return replace(draft, route=route, leftover_passes=tuple(joined), path=_path(segments, s), notes=draft.notes + (
        f"leftover passes (--leftover-passes off to leave them): {what}; {len(joined)} of the {len(extra)} joined into "
        "the route",) + tuple(notes))


def idle_distance(segments) -> float:
    """Metres driven without working: turns and transits."""
    return sum(float(length_of(seg.points)) for seg in segments if seg.kind in (TURN, TRANSIT))


def _least_idle(field, route, segments, cells, skip, settings, rings, n, where, notes, pieces):
    """The solver's order, or a pattern's (boustrophedon; skip where the U-turn needs it) where that,
    joined by the real turns, drives less without working: the solver's costs are closed-form
    estimates without the headland transits the joiner may add."""
    mine = best = idle_distance(segments)
    chosen = (route, segments, [])
    for pattern, s in (("boustrophedon", 1),) + ((("skip", skip),) if skip > 1 else ()):
        other_notes: list[str] = []
        other = route_order.route(cells, s, pattern, settings, rings)
        try:
            other_segments = Joiner(field, settings, n, where, other_notes, pieces).join(other)
        except FieldError:
            continue
        idle = idle_distance(other_segments)
        notes.append(f"the {pattern} order drives {idle:.0f} m without working, the solver's {mine:.0f} m")
        if idle < best:
            best, chosen = idle, (Route(other.passes, other.cell_starts, other.how + " (kept: less idle than the "
                                        "solver's)"), other_segments, other_notes)
    notes += [x for x in chosen[2] if x not in notes]
    return chosen[0], chosen[1]
