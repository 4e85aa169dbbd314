"""A field's coverage route as the trackers' reference: path following, not a clock.

At initialisation the field named by ``path`` is read (fields.read_fields: GeoJSON, WKT, GML,
ISOXML, AgOpenGPS, a polygon CSV in ``crs``) and planned (fields.planner.plan with this
component's parameters); the route is put in the *mission frame*, its start at the origin heading
east, so that the tractor starts there at rest (route_frame). Each step projects the estimated CG
onto the route near where it was (a window of -2 m to +10 m of arc length on the grid s = k ROUTE_STEP,
so a turn that crosses a swath does not capture it) and gives the reference at that arc length s*:

    (x_ref, y_ref) = route(s*),   (xdot_ref, ydot_ref) = v(s*) (cos h, sin h),   gamma_ref = v(s*) kappa(s*)

so the tracker's along-track error is nil and its cross-track error is the distance to the route;
the speed comes from the route's profile (slower in turns). The implement's working point is
projected the same way (its own window): ``implement_cross_track`` is its signed distance to the
route, left positive, and ``working`` says whether it is on a swath or a headland pass. The run ends
(EndRun) when the CG reaches the route's end.

The route is the plan's Path, evaluated lazily: the grid is sampled a window of WINDOW metres at a
time round the vehicle (RouteWindow), so memory stays flat however long the route.

Imported where used: control (start-up: 0.8 s of CPU, measured, that every run following a field's route would
pay; only the linear analyses use it).
"""
from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path

import numpy as np
from shapely import transform

from agrobot.fields import FieldError, read_fields
from agrobot.fields.field import choose_field
from agrobot.fields.planner import HEADLAND, SWATH, Settings, plan as make_plan
from agrobot.fields.planner.sampling import ROUTE_STEP
from agrobot.fields.planner.sections import SectionControl, SectionLayout, check_sections
from agrobot.orchestrator.component import Component, EndRun, inp, out, par
from agrobot.orchestrator.units import FILE_UNIT

WINDOW = 500.0          # m of the route sampled at a time
MAX_LATENCY = 5.0       # s: a section latency beyond this is a unit slip (ms given as s), refused
BEHIND = 20.0           # m of it kept behind the vehicle


@functools.lru_cache(maxsize=8)
def planned(path: str, crs: str, name: str, settings):
    """(field, plan) for the parameters (cached: the run and its analysis plan once)."""
    field = choose_field(read_fields(Path(path), crs or None), name or None, path)
    return field, make_plan(field, settings)


def route_frame(path) -> tuple[np.ndarray, float]:
    """(origin, rotation) of the mission frame: the route's start, its heading."""
    x, y, heading = path.start_pose()
    return np.array([x, y]), heading


def to_mission(xy: np.ndarray, origin: np.ndarray, rotation: float) -> np.ndarray:
    """Field-local (N, 2) -> mission frame."""
    c, s = math.cos(-rotation), math.sin(-rotation)
    d = np.asarray(xy, float) - origin
    return np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]])


def settings_of(p: dict):
    """fields.planner.Settings from the component's parameters of the same names (nan angle: chosen)."""
    values = {}
    for f in dataclasses.fields(Settings):
        if f.name not in p:
            continue
        v, default = p[f.name], f.default
        if f.name == "driving_angle":
            values[f.name] = None if v is None or (isinstance(v, float) and math.isnan(v)) else float(v)
        else:
            values[f.name] = type(default)(v)
    return Settings(**values)


def section_control(p: dict, plan, origin: np.ndarray, rotation: float, require):
    """fields.planner.sections.SectionControl over the field in the mission frame, or None
    (``sections`` 0); the count and the latencies checked (ComponentError naming the value)."""
    for key in ("section_on_delay", "section_off_delay"):
        v = p[key]
        require(isinstance(v, (int, float)) and 0.0 <= v <= MAX_LATENCY,
                f"parameter {key} = {v!r} s: expected a latency from 0 to {MAX_LATENCY:g} s")
    require(p["section_look_ahead"] in (0, 1), f"parameter section_look_ahead = {p['section_look_ahead']!r}: "
            "expected 0 or 1")
    if p["sections"] == 0:
        return None
    try:
        n = check_sections(p["sections"], plan.settings.working_width, "parameter sections")
    except FieldError as exc:
        require(False, str(exc))
    region = transform(plan.field.boundary, lambda xy: to_mission(xy, origin, rotation))
    return SectionControl(region, SectionLayout(plan.settings.working_width, n), float(p["section_on_delay"]),
                          float(p["section_off_delay"]), bool(p["section_look_ahead"]))


def section_mask(low: np.ndarray, high: np.ndarray, count: int) -> np.ndarray:
    """(samples, count) of the sections on, from the route's ``section_mask_0`` and ``_1``."""
    lo, hi = np.asarray(low).astype(np.int64), np.asarray(high).astype(np.int64)
    bits = np.arange(count)
    word = np.where(bits < 32, lo[:, None], hi[:, None])
    return ((word >> (bits % 32)) & 1).astype(bool)


class RouteWindow:
    """The route on the grid s = i ROUTE_STEP, i < size, in the mission frame, sampled a window at
    a time: ``take(a, b)`` makes sure points a..b-1 are at hand (resampling WINDOW metres from
    BEHIND before a when they are not); ``x``, ``y``, ... are then indexed by i - ``first``."""

    def __init__(self, path, origin: np.ndarray, rotation: float) -> None:
        self.path, self.origin, self.rotation = path, origin, rotation
        self.size = path.grid_size(ROUTE_STEP)
        self.first = self.stop = 0

    def take(self, a: int, b: int) -> None:
        if self.first <= a and b <= self.stop:
            return
        self.first = max(0, a - int(BEHIND / ROUTE_STEP))
        self.stop = min(self.size, max(b, self.first + int(WINDOW / ROUTE_STEP)))
        r = self.path.grid(self.first, self.stop, ROUTE_STEP)
        xy = to_mission(np.column_stack([r["x"], r["y"]]), self.origin, self.rotation)
        self.x, self.y = xy[:, 0], xy[:, 1]
        self.h = r["heading"] - self.rotation
        self.kappa, self.speed, self.kind, self.index, self.s = r["curvature"], r["speed"], r["kind"], r["index"], r["s"]

    def at(self, i: int, name: str) -> float:
        self.take(i, i + 1)
        return float(getattr(self, name)[i - self.first])


class FieldRoute(Component):
    sampled = True
    roles = ("reference", "route")
    variables = (
        inp("x", "m", 0.0, "estimated CG east position (mission frame)"),
        inp("y", "m", 0.0, "estimated CG north position"),
        inp("implement_x", "m", 0.0, "implement working point east"),
        inp("implement_y", "m", 0.0, "implement working point north"),
        inp("implement_pose_x", "m", 0.0, "the implement's own working point east (sections switch from it)"),
        inp("implement_pose_y", "m", 0.0, "its north"),
        inp("implement_heading", "rad", 0.0, "its heading (a trailed implement's own)"),
        par("path", FILE_UNIT, "", "the field: a file or folder fields.read_fields reads (relative: to the study "
            "file, the files it extends, or the working folder)"),
        par("crs", "", "", "its CRS when the file does not name it (EPSG:6677 ...)"),
        par("name", "", "", "the field when the file holds several (default: the largest)"),
        par("working_width", "m", 3.0, "implement working width"),
        par("headland_passes", "1", 0, "0: as many as the turns need"),
        par("driving_angle", "rad", float("nan"), "swath direction, east = 0, counter-clockwise (nan: by angle_objective)"),
        par("guidance_line", "", "", "drive along this guidance line of the field (an AB line; '*': its first)"),
        par("swath_pattern", "", "straight", "straight; curved: swaths offset from the guidance line (a curve) at "
            "the working width"),
        par("angle_objective", "", "fewest_swaths", "how the driving angle is chosen: fewest_swaths or longest_edge"),
        par("turn_radius", "m", 4.0, "the tractor's smallest turning radius"),
        par("wheelbase", "m", 1.4, "for the steering-rate limit of the turns"),
        par("steer_rate", "rad/s", math.radians(30.0), "steering rate the turns may ask"),
        par("work_speed", "m/s", 2.0, "speed on swaths and headland passes"),
        par("turn_speed", "m/s", 1.0, "speed in turns"),
        par("acceleration", "m/s2", 0.5, "speed changes"),
        par("overlap", "m", 0.05, "between adjacent passes"),
        par("order", "", "auto", "auto, boustrophedon, skip or optimised (least non-working distance, OR-tools)"),
        par("half_width", "m", 0.8, "the tractor's half width, kept inside the field"),
        par("hitch_offset", "m", 0.6, "the implement's hitch behind the rear axle"),
        par("drawbar", "m", 2.5, "hitch to implement axle (0: mounted)"),
        par("headland_work", "1", 1, "1: drive and work the headland passes"),
        par("headland_order", "", "last", "last: the headland passes after the swaths; first: before them"),
        par("max_swaths", "1", 0, "0: every swath; N: the first N (a section of the field)"),
        par("leftover_passes", "1", 1, "1: what the route leaves (corners, necks, strips) is worked by passes of its "
            "own after it (fields.planner.leftover_passes); 0: named in the plan only"),
        par("settle", "m", 5.0, "straight run before a swath beyond the implement's length"),
        par("swath_extension", "m", 0.1, "each swath worked on beyond its strip's reach (lift and drop margin)"),
        par("sections", "1", 0, "0: the whole width works along every swath and headland pass; N: N sections "
            "switched by section control"),
        par("section_on_delay", "s", 0.3, "a section's latency from its on command to working (0 to "
            f"{MAX_LATENCY:g} s)"),
        par("section_off_delay", "s", 0.2, f"from its off command to stopping (0 to {MAX_LATENCY:g} s)"),
        par("section_look_ahead", "1", 1, "1: commands go out v t ahead, so that sections switch at the edge; "
            "0: they switch v t late"),
        out("x_ref", "m", 0.0, "route point at the CG's projection, east"),
        out("y_ref", "m", 0.0, "north"),
        out("xdot_ref", "m/s", 0.0, "route speed along its tangent, east"),
        out("ydot_ref", "m/s", 0.0, "north"),
        out("heading_ref", "rad", 0.0, "route tangent"),
        out("yaw_rate_ref", "rad/s", 0.0, "v kappa at the projection"),
        out("speed_ref", "m/s", 0.0, "route speed profile at the projection"),
        out("path_length", "m", 0.0, "s*: arc length of the CG's projection"),
        out("segment", "1", 0.0, "what the CG is on: 0 swath, 1 turn, 2 headland pass, 3 transit"),
        out("swath", "1", -1.0, "swath (or headland ring) index, -1 in turns"),
        out("cross_track", "m", 0.0, "CG to route, left positive"),
        out("implement_cross_track", "m", 0.0, "implement working point to route, left positive"),
        out("implement_segment", "1", 0.0, "what the implement is on (as segment)"),
        out("working", "1", 0.0, "1 while the implement is on a swath or a headland pass"),
        out("implement_on_straight", "1", 0.0, "1 while the route is straight where the implement is (a swath and "
            "its run-in: the side-shift may act)"),
        out("progress", "1", 0.0, "share of the route done"),
        out("sections_on", "1", 0.0, "sections working (all of the width: 1 without section control)"),
        out("section_mask_0", "1", 0.0, "bit i: section i (0-31) on"),
        out("section_mask_1", "1", 0.0, "bit i: section 32 + i on"),
    )
    feedthrough = {o: ("x", "y") for o in ("x_ref", "y_ref", "xdot_ref", "ydot_ref", "heading_ref", "yaw_rate_ref",
                                           "speed_ref", "path_length", "segment", "swath", "cross_track", "progress")}
    feedthrough |= {o: ("implement_x", "implement_y") for o in ("implement_cross_track", "implement_segment", "working",
                                                                "implement_on_straight")}
    feedthrough |= {o: ("implement_x", "implement_y", "implement_pose_x", "implement_pose_y", "implement_heading")
                    for o in ("sections_on", "section_mask_0", "section_mask_1")}

    def initialize(self, t0: float, dt: float) -> None:
        self.require(bool(self.p["path"]), "parameter path: expected the field's file or folder")
        self.require(self.p["leftover_passes"] in (0, 1), f"parameter leftover_passes = {self.p['leftover_passes']!r}: "
                     f"expected 1 (work what the route leaves) or 0 (name it only)")
        try:
            _, plan = planned(str(self.p["path"]), str(self.p["crs"]), str(self.p["name"]), settings_of(self.p))
        except (FieldError, ValueError, OSError) as exc:
            self.require(False, str(exc))             # names the file, the field and the value
        self.path = plan.path
        origin, rotation = route_frame(self.path)
        self.route = RouteWindow(self.path, origin, rotation)
        self.end = (self.route.size - 1) * ROUTE_STEP          # s of the last grid point
        self.i_cg = self.i_impl = 0
        self.sections = section_control(self.p, plan, origin, rotation, self.require)
        n = len(plan.leftover_passes)
        if self.p["leftover_passes"]:
            self.event(t0, f"{n} leftover pass(es) of their own after the route (parameter leftover_passes = 0 "
                           f"leaves what the route leaves unworked, named in the plan)")
        else:
            self.event(t0, "leftover passes off: what the route leaves is named, not worked (parameter "
                           "leftover_passes = 1 works it)")
        self.travelled, self.last_pose = 0.0, None
        self.step(t0, dt)

    def run_progress(self) -> tuple[float, float, str] | None:
        """(metres of the route done, the route's length, "m"): the run's progress line
        (orchestrator.observers.Progress)."""
        end = getattr(self, "end", None)
        return None if end is None else (float(self.y["path_length"]), float(end), "m")

    def _project(self, px: float, py: float, i: int, back: float = 2.0, ahead: float = 10.0) -> tuple[int, float]:
        """(index, signed lateral distance) of the route point nearest (px, py) within the window."""
        r = self.route
        a, b = max(0, i - int(back / ROUTE_STEP)), min(r.size, i + int(ahead / ROUTE_STEP) + 1)
        r.take(a, b)
        d2 = (r.x[a - r.first:b - r.first] - px) ** 2 + (r.y[a - r.first:b - r.first] - py) ** 2
        j = a + int(np.argmin(d2))
        k = j - r.first
        lateral = -math.sin(r.h[k]) * (px - r.x[k]) + math.cos(r.h[k]) * (py - r.y[k])
        return j, lateral

    def step(self, t: float, dt: float) -> None:
        u, y, r = self.u, self.y, self.route
        self.i_cg, lateral = self._project(u["x"], u["y"], self.i_cg)
        j = self.i_cg
        v, h = r.at(j, "speed"), r.at(j, "h")
        y["x_ref"], y["y_ref"] = r.at(j, "x"), r.at(j, "y")
        y["heading_ref"] = h
        y["xdot_ref"], y["ydot_ref"] = v * math.cos(h), v * math.sin(h)
        y["yaw_rate_ref"], y["speed_ref"] = v * r.at(j, "kappa"), v
        y["path_length"], y["segment"], y["swath"] = r.at(j, "s"), r.at(j, "kind"), r.at(j, "index")
        y["cross_track"], y["progress"] = lateral, r.at(j, "s") / self.end if self.end > 0 else 1.0
        self.i_impl, lat_i = self._project(u["implement_x"], u["implement_y"], min(self.i_impl, j), back=2.0,
                                           ahead=max(12.0, (j - self.i_impl) * ROUTE_STEP + 2.0))
        y["implement_cross_track"] = lat_i
        kind = r.at(self.i_impl, "kind")
        y["implement_segment"] = kind
        y["working"] = float(kind in (SWATH, HEADLAND))
        y["implement_on_straight"] = float(abs(r.at(self.i_impl, "kappa")) < 1e-3)
        self._switch_sections(t, dt)
        if j >= r.size - 3:
            raise EndRun(self.name, f"the route is complete ({self.end:.0f} m)")

    def _switch_sections(self, t: float, dt: float) -> None:
        """The sections' states from the implement's own pose and speed (its travel over the step)."""
        u, y = self.u, self.y
        if self.sections is None:
            y["sections_on"] = y["working"]
            return
        pose = (float(u["implement_pose_x"]), float(u["implement_pose_y"]))
        moved = math.dist(pose, self.last_pose) if self.last_pose is not None else 0.0
        self.travelled += moved
        self.last_pose = pose
        state = self.sections.step(t, self.travelled, *pose, float(u["implement_heading"]), moved / dt if dt > 0 else 0.0,
                                   y["working"] > 0.5)
        y["sections_on"] = float(state.sum())
        bits = np.flatnonzero(state)
        y["section_mask_0"] = float(sum(1 << int(i) for i in bits if i < 32))
        y["section_mask_1"] = float(sum(1 << int(i - 32) for i in bits if i >= 32))

    def operating_points(self) -> dict[str, dict[str, float]]:
        """Where the guidance loop is linearised: a straight at ``work_speed`` (swaths, headland
        passes) and at ``turn_speed`` (the turns, of radius down to ``turn_radius``); the route point
        is the CG's projection, so the tracker's along-track error is nil."""
        return {"work": {"speed": float(self.p["work_speed"]), "along_track_error": 0.0},
                "turn": {"speed": float(self.p["turn_speed"]), "along_track_error": 0.0,
                         "turn_radius": float(self.p["turn_radius"])}}

    def lateral_linearisation(self, speed: float, dt: float, along_track_error: float = 0.0):
        """Small deviations of the CG from a straight leg heading east: the route point is the
        CG's projection, so the reference the tracker reads (y_ref, ydot_ref, heading_ref,
        yaw_rate_ref) does not move with the CG and the along-track error stays nil (the argument
        is there for the common signature);
        cross_track = d y. A static gain (python-control StateSpace, ports as names)."""
        import control

        outputs = ["y_ref", "ydot_ref", "heading_ref", "yaw_rate_ref", "cross_track"]
        return control.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((len(outputs), 0)),
                          np.array([[0.0], [0.0], [0.0], [0.0], [1.0]]), dt, inputs=["y"], outputs=outputs)


COMPONENT = FieldRoute
