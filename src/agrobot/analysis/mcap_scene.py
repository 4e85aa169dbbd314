"""The vehicle's scene in a run's MCAP and live view (orchestrator.mcap_out), in Foxglove's well-known
schemas, found from the study's components by their roles:

- ``/tf`` (foxglove.FrameTransforms): ``world`` -> ``base_link`` (the yaw plant's centre of gravity
  and heading), ``base_link`` -> ``antenna`` (its GNSS antenna, where the plant gives it), ``world`` ->
  ``implement`` (the implement's working point and heading);
- ``/vehicle/pose``, ``/implement/pose``, ``/estimate/pose`` (foxglove.PoseInFrame, frame ``world``): the
  true vehicle, the implement and the pose estimator's estimate;
- ``/gnss/fix`` (foxglove.LocationFix): the GNSS sensor's measured position on the map (a second receiver,
  such as an implement's: ``/gnss/<component>/fix``), from the
  geodetic origin (the field's for a field mission; else the study's ``[output] origin``; else a
  nominal origin, said in the message's frame and the MCAP's metadata);
- ``/reference/pose`` (foxglove.PoseInFrame): the reference point; ``/reference/path``
  (foxglove.SceneUpdate, once): the reference path driven, as a line strip (live, where the run's signals
  are not known in advance: the path driven so far, gathered at every scene instant of simulated time
  (20 Hz) and sent again twice a
  second of wall time while it grows, at most LIVE_PATH_POINTS points);
- ``/field`` (foxglove.GeoJson, once): the field boundary, its swaths and the route, longitude/latitude.

``world`` is the simulation's east/north frame (the mission frame of a field mission), z up.

Imported where used: agrobot.analysis.field_tracks (start-up: it loads the field planner, about 1.2 s here,
which every run of a study would pay, a figure-8's and each of its sweep workers included, as the study's
analysis module imports this one; a field mission alone needs it), agrobot.components.field_route (start-up: the
same), foxglove (the mcap extra), pymap3d (the hardware extra).
"""
from __future__ import annotations

import json
import math

import numpy as np
from shapely import transform
from shapely.geometry import LineString, mapping

from agrobot.orchestrator.resolver import resolve

# A nominal geodetic origin where a study gives none (the paper's tractor was driven near Leuven, Belgium)
NOMINAL_ORIGIN = (50.8632, 4.6858)
SCENE_STEP = 0.05          # s between two scene instants (20 Hz)
PATH_SPACING = 0.05        # m between two points of the reference path's line
LIVE_PATH_POINTS = 1000    # points of the live path at most (past it, every other point is dropped: 1.3 ms to send)
LIVE_PATH_EVERY = 10       # scene instants between two sendings of a grown live path (0.5 s at 20 Hz of wall time)


def _yaw_quaternion(heading: float):
    from foxglove.messages import Quaternion

    return Quaternion(x=0.0, y=0.0, z=math.sin(heading / 2.0), w=math.cos(heading / 2.0))


def _timestamp(t_ns: int):
    from foxglove.messages import Timestamp

    return Timestamp(sec=int(t_ns // 1_000_000_000), nsec=int(t_ns % 1_000_000_000))


class VehicleScene:
    """The scene of one study; ``frame`` (the run's signals, when known in advance) gives the path."""

    def __init__(self, study, frame=None, base_step: float | None = None) -> None:
        model = resolve(study)
        self.study = study
        h = base_step or float(study.study.base_step)
        self.every = max(1, int(round(SCENE_STEP / h)))

        def one(role: str) -> str | None:
            names = model.find(role=role)
            return names[0] if len(names) == 1 else None
        self.plant, self.implement = one("yaw_plant"), one("implement")
        receivers = sorted(model.find(role="gps"), key=lambda n: (n != "gps", n))   # 'gps' first, then by name
        self.gnss = {name: "/gnss/fix" if k == 0 else f"/gnss/{name}/fix" for k, name in enumerate(receivers)}
        self.estimate, self.reference = one("pose_estimator"), one("reference")
        self.origin, self.origin_how, self.to_world_local, self.field_geojson = self._geodesy(model, study)
        self.path = None
        if frame is not None and self.reference and f"{self.reference}.x_ref" in frame:
            xy = np.column_stack([frame[f"{self.reference}.x_ref"].to_numpy(float),
                                  frame[f"{self.reference}.y_ref"].to_numpy(float)])
            s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])   # arc length
            keep = np.r_[True, np.diff(np.floor(s / PATH_SPACING)) > 0]
            keep[-1] = True
            self.path = xy[keep]
        self.growing = GrowingPath(PATH_SPACING, LIVE_PATH_POINTS) if frame is None and self.reference else None
        self._since_path = 0
        self._ch = {}

    @property
    def note(self) -> str:
        """What the scene chose that changes what a viewer shows: the map's origin."""
        return f"map origin {self.origin[0]:.6f} N, {self.origin[1]:.6f} E: {self.origin_how}"

    # --- geodesy --------------------------------------------------------------------------------------
    def _geodesy(self, model, study):
        """(origin lat/lon deg, how it was chosen, world -> field-local map, the field's GeoJSON or None)."""
        routes = model.find(role="route")
        if len(routes) == 1:
            from .field_tracks import mission

            field, plan, _, _ = mission(study)
            origin_xy, rotation = _route_frame(plan)
            if field.origin is not None:          # the mission frame: the route's start, turned by its heading
                c, s = math.cos(rotation), math.sin(rotation)

                def to_local(xy):
                    xy = np.atleast_2d(np.asarray(xy, float))
                    return np.column_stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]]) + origin_xy
                return field.origin, f"the field's origin ({field.name})", to_local, _field_geojson(field, plan)
        section = study.section("output") if hasattr(study, "section") else None
        if section and section.get("origin"):
            lat, lon = (float(v) for v in section["origin"])
            return (lat, lon), "the study's [output] origin", None, None
        return NOMINAL_ORIGIN, (f"a nominal origin ({NOMINAL_ORIGIN[0]} N, {NOMINAL_ORIGIN[1]} E): the study gives "
                                f"none; set [output] origin = [lat, lon] in degrees"), None, None

    def to_geodetic(self, x: float, y: float) -> tuple[float, float]:
        """World east/north [m] -> (lat, lon) degrees."""
        import pymap3d

        if self.to_world_local is not None:
            x, y = self.to_world_local([[x, y]])[0]
        lat, lon, _ = pymap3d.enu2geodetic(x, y, 0.0, self.origin[0], self.origin[1], 0.0, deg=True)
        return float(lat), float(lon)

    # --- channels and messages ---------------------------------------------------------------------
    def channels(self, context) -> None:
        from foxglove.channels import (FrameTransformsChannel, GeoJsonChannel, LocationFixChannel, PoseInFrameChannel,
                                       SceneUpdateChannel)

        self._ch = {"/tf": FrameTransformsChannel("/tf", context=context)}
        for topic, present in (("/vehicle/pose", self.plant), ("/implement/pose", self.implement),
                               ("/estimate/pose", self.estimate), ("/reference/pose", self.reference)):
            if present:
                self._ch[topic] = PoseInFrameChannel(topic, context=context)
        for topic in self.gnss.values():
            self._ch[topic] = LocationFixChannel(topic, context=context)
        if self.path is not None or self.growing is not None:
            self._ch["/reference/path"] = SceneUpdateChannel("/reference/path", context=context)
        if self.field_geojson is not None:
            self._ch["/field"] = GeoJsonChannel("/field", context=context)

    def static(self, t_ns: int) -> None:
        from foxglove.messages import GeoJson

        self._log_path(t_ns)
        if "/field" in self._ch:
            self._ch["/field"].log(GeoJson(geojson=json.dumps(self.field_geojson)), log_time=t_ns)

    def _log_path(self, t_ns: int) -> None:
        from foxglove.messages import Color, LinePrimitive, LinePrimitiveLineType, Point3, SceneEntity, SceneUpdate

        if "/reference/path" not in self._ch:
            return
        path = self.path if self.growing is None else self.growing.points()
        if not len(path):
            return
        line = LinePrimitive(type=LinePrimitiveLineType.LineStrip, thickness=0.05, scale_invariant=False,
                             points=[Point3(x=float(x), y=float(y), z=0.0) for x, y in path],
                             color=Color(r=0.4, g=0.4, b=0.4, a=1.0))
        self._ch["/reference/path"].log(SceneUpdate(entities=[SceneEntity(
            timestamp=_timestamp(t_ns), frame_id="world", id="reference_path", lines=[line])]), log_time=t_ns)
        if self.growing is not None:
            self.growing.sent()

    def track(self, value) -> None:
        """Live, at every scene instant of simulated time: the reference point joins the path driven so far."""
        if self.growing is not None:
            self.growing.add(value(f"{self.reference}.x_ref"), value(f"{self.reference}.y_ref"))

    def step(self, t_ns: int, value) -> None:
        from foxglove.messages import (FrameTransform, FrameTransforms, LocationFix, Pose, PoseInFrame, Quaternion,
                                       Vector3)
        if self.growing is not None:
            self._since_path += 1
            if self.growing.grown and (self._since_path >= LIVE_PATH_EVERY or self.growing.never_sent):
                self._since_path = 0
                self._log_path(t_ns)

        stamp = _timestamp(t_ns)
        transforms = []

        def pose(x, y, heading):
            return Pose(position=Vector3(x=x, y=y, z=0.0), orientation=_yaw_quaternion(heading))

        def finite(*v):
            return all(math.isfinite(a) for a in v)
        if self.plant:
            x, y, psi = value(f"{self.plant}.x_cg"), value(f"{self.plant}.y_cg"), value(f"{self.plant}.heading")
            if finite(x, y, psi):
                transforms.append(FrameTransform(timestamp=stamp, parent_frame_id="world", child_frame_id="base_link",
                                                 translation=Vector3(x=x, y=y, z=0.0), rotation=_yaw_quaternion(psi)))
                self._ch["/vehicle/pose"].log(PoseInFrame(timestamp=stamp, frame_id="world", pose=pose(x, y, psi)),
                                              log_time=t_ns)
                ax, ay = value(f"{self.plant}.x_antenna"), value(f"{self.plant}.y_antenna")
                if finite(ax, ay):
                    c, s = math.cos(psi), math.sin(psi)
                    dx, dy = ax - x, ay - y
                    transforms.append(FrameTransform(
                        timestamp=stamp, parent_frame_id="base_link", child_frame_id="antenna",
                        translation=Vector3(x=c * dx + s * dy, y=-s * dx + c * dy, z=0.0),
                        rotation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)))
        if self.implement:
            x, y, psi = (value(f"{self.implement}.{p}") for p in ("x", "y", "heading"))
            if finite(x, y, psi):
                transforms.append(FrameTransform(timestamp=stamp, parent_frame_id="world", child_frame_id="implement",
                                                 translation=Vector3(x=x, y=y, z=0.0), rotation=_yaw_quaternion(psi)))
                self._ch["/implement/pose"].log(PoseInFrame(timestamp=stamp, frame_id="world", pose=pose(x, y, psi)),
                                                log_time=t_ns)
        if self.estimate:
            x, y, psi = (value(f"{self.estimate}.{p}") for p in ("x_cg", "y_cg", "heading"))
            if finite(x, y, psi):
                self._ch["/estimate/pose"].log(PoseInFrame(timestamp=stamp, frame_id="world", pose=pose(x, y, psi)),
                                               log_time=t_ns)
        if self.reference:
            x, y = value(f"{self.reference}.x_ref"), value(f"{self.reference}.y_ref")
            psi = value(f"{self.reference}.heading_ref")
            if finite(x, y):
                self._ch["/reference/pose"].log(PoseInFrame(timestamp=stamp, frame_id="world",
                                                            pose=pose(x, y, psi if math.isfinite(psi) else 0.0)),
                                                log_time=t_ns)
        for name, topic in self.gnss.items():
            x, y = value(f"{name}.x"), value(f"{name}.y")
            if finite(x, y):
                lat, lon = self.to_geodetic(x, y)
                self._ch[topic].log(LocationFix(timestamp=stamp, frame_id=name, latitude=lat, longitude=lon,
                                                altitude=0.0), log_time=t_ns)
        if transforms:
            self._ch["/tf"].log(FrameTransforms(transforms=transforms), log_time=t_ns)


class GrowingPath:
    """A path gathered point by point: a point joins when it lies ``spacing`` or more from the last one; past
    ``most`` points every other one is dropped and the spacing doubles (memory and message size bounded)."""

    def __init__(self, spacing: float, most: int) -> None:
        self.spacing, self.most = float(spacing), int(most)
        self.xy: list[tuple[float, float]] = []
        self.grown, self.never_sent = False, True

    def add(self, x: float, y: float) -> None:
        if not (math.isfinite(x) and math.isfinite(y)):
            return
        if self.xy:
            last = self.xy[-1]
            if math.hypot(x - last[0], y - last[1]) < self.spacing:
                return
        self.xy.append((x, y))
        self.grown = True
        if len(self.xy) > self.most:
            self.xy = self.xy[::2] + ([self.xy[-1]] if len(self.xy) % 2 == 0 else [])
            self.spacing *= 2.0

    def points(self) -> list[tuple[float, float]]:
        return list(self.xy)

    def sent(self) -> None:
        self.grown = self.never_sent = False


def _route_frame(plan):
    from agrobot.components.field_route import route_frame

    return route_frame(plan.path)


def _field_geojson(field, plan) -> dict:
    """The boundary, the swaths and the route as a GeoJSON FeatureCollection in longitude/latitude."""
    def geo(geom):
        return mapping(transform(geom, lambda xy: field.to_geodetic(xy)))
    features = [{"type": "Feature", "properties": {"kind": "boundary", "name": field.name}, "geometry": geo(field.boundary)}]
    for k, swath in enumerate(plan.swaths):
        features.append({"type": "Feature", "properties": {"kind": "swath", "index": k},
                         "geometry": geo(LineString(np.asarray(swath.points, float)))})
    return {"type": "FeatureCollection", "features": features}


def mcap_scene(study, frame=None):
    """The scene of a study's run (orchestrator.mcap_out), or None when it has no vehicle to show: a simulated
    plant, an implement or a GNSS receiver, or, where the tractor is hardware (its truth unknown), the pose
    estimator's estimate and the reference."""
    scene = VehicleScene(study, frame)
    return scene if (scene.plant or scene.implement or scene.gnss or scene.estimate or scene.reference) else None
