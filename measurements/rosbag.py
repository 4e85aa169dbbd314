"""ROS bags as a recording (issue 26): ROS 1 ``.bag``, ROS 2 ``.db3`` or ``.mcap`` files, or a
rosbag2 folder, read with rosbags (no ROS install).

Standard messages are mapped by their type, without options (TYPE_MAP):

- ``sensor_msgs/NavSatFix``: latitude, longitude, altitude -> x, y about the first fix; status ->
  ``fix_quality`` (NO_FIX -1 -> 0, FIX 0 -> 1, SBAS 1 -> 2 (differential), GBAS 2 -> 4 (ground-based
  augmentation, RTK's class)); the covariance's horizontal part -> ``position_std``;
- ``sensor_msgs/Imu``: ``yaw_rate`` from angular_velocity.z;
- ``nav_msgs/Odometry``: ``v`` from twist.twist.linear.x, ``yaw_rate`` from twist.twist.angular.z
  (an IMU's wins);
- ``geometry_msgs/TwistStamped``: ``v`` and ``yaw_rate`` likewise;
- ``ackermann_msgs/AckermannDriveStamped``: ``delta_cmd`` from drive.steering_angle, ``speed_cmd``
  from drive.speed.

Any numeric field of any topic: ``--signal COLUMN=/topic[.field.path]`` (``a.b[2].c``; a message
with one numeric field needs no path); ``lat``/``lon`` columns in degrees become x/y. Times are
the messages' header stamps where they have a header with a stamp, else the bag's receive times;
every topic is on that one clock, and the report says which each topic used.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .log import LogError, resolution

# ackermann_msgs is not in the rosbags type stores; its layout (ROS 1 and 2 alike)
ACKERMANN = {
    "ackermann_msgs/msg/AckermannDrive": "float32 steering_angle\nfloat32 steering_angle_velocity\nfloat32 speed\n"
                                         "float32 acceleration\nfloat32 jerk\n",
    "ackermann_msgs/msg/AckermannDriveStamped": "std_msgs/Header header\nackermann_msgs/AckermannDrive drive\n",
}
NAVSAT_QUALITY = {-1: 0, 0: 1, 1: 2, 2: 4}

# type -> [(column, field path)], in the order a column is taken from (the first type that has it wins)
TYPE_MAP: dict[str, list[tuple[str, str]]] = {
    "sensor_msgs/msg/NavSatFix": [("lat", "latitude"), ("lon", "longitude"), ("height", "altitude"),
                                  ("fix_quality", "status.status"), ("position_std", "position_covariance")],
    "sensor_msgs/msg/Imu": [("yaw_rate", "angular_velocity.z")],
    "ackermann_msgs/msg/AckermannDriveStamped": [("delta_cmd", "drive.steering_angle"), ("speed_cmd", "drive.speed")],
    "nav_msgs/msg/Odometry": [("v", "twist.twist.linear.x"), ("yaw_rate", "twist.twist.angular.z")],
    "geometry_msgs/msg/TwistStamped": [("v", "twist.linear.x"), ("yaw_rate", "twist.angular.z")],
}
_PATH = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\[\d+\])?(\.[A-Za-z_][A-Za-z0-9_]*(\[\d+\])?)*$")


@dataclass(frozen=True)
class TopicSource:
    """``COLUMN=[-]/topic[.field.path]``: a log column from a field of a ROS topic."""

    column: str
    topic: str
    path: str = ""
    sign: float = 1.0

    def __str__(self) -> str:
        return f"{self.column}={'-' if self.sign < 0 else ''}{self.topic}{'.' + self.path if self.path else ''}"


def parse_topic_source(text: str, topics: list[str] | None = None) -> TopicSource:
    """``COLUMN=[-]/topic[.field.path]``; the topic is the longest known prefix when ``topics``
    are given (a topic name may hold dots only where the bag says so), else up to the first dot."""
    column, _, rest = text.partition("=")
    rest = rest.strip()
    sign = -1.0 if rest.startswith("-") else 1.0
    rest = rest.lstrip("-")
    column = column.strip()
    if not rest.startswith("/") or not re.match(r"^[a-z_][a-z0-9_]*$", column) or column in ("t", "x", "y"):
        raise LogError(f"--signal {text!r}: expected COLUMN=[-]/topic[.field.path] with COLUMN a log column "
                       f"(delta_cmd, delta, v, yaw_rate, lat, lon) or another lower-case name")
    topic, path = rest, ""
    known = [t for t in topics or () if rest == t or rest.startswith(t + ".")]
    if known:                                  # a topic of the bag (its name may hold a dot)
        topic = max(known, key=len)
        path = rest[len(topic) + 1:]
    elif "." in rest.rsplit("/", 1)[-1]:       # /topic.field: the field after the last name
        head, tail = rest.rsplit("/", 1)
        name, path = tail.split(".", 1)
        topic = f"{head}/{name}"
    if path and not _PATH.match(path):
        raise LogError(f"--signal {text!r}: the field path {path!r} is not a.b[2].c")
    return TopicSource(column, topic, path, sign)


def typestore():
    """The ROS 2 type store with the ackermann messages added (bags that carry their own
    definitions, every ROS 1 bag, use those)."""
    from rosbags.typesys import Stores, get_typestore, get_types_from_msg

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for name, text in ACKERMANN.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def field(msg, path: str):
    """The value at ``a.b[2].c`` of a deserialised message; a LookupError names the missing part."""
    value = msg
    for part in path.split(".") if path else ():
        name, _, index = part.partition("[")
        if not hasattr(value, name):
            have = [k for k in getattr(value, "__dataclass_fields__", {}) if not k.startswith("__")]
            raise LookupError(f"no field {name!r} (fields: {', '.join(have)})")
        value = getattr(value, name)
        if index:
            value = value[int(index.rstrip("]"))]
    return value


def _numeric_field(msg) -> str | None:
    """The one numeric field of a message (std_msgs/Float64.data), or None."""
    fields = [k for k in getattr(msg, "__dataclass_fields__", {}) if not k.startswith("__")]
    numeric = [k for k in fields if isinstance(getattr(msg, k), (int, float, np.number)) and not isinstance(getattr(msg, k), bool)]
    return numeric[0] if len(numeric) == 1 else None


def _stamp(msg, receive_ns: int) -> tuple[float, bool]:
    header = getattr(msg, "header", None)
    stamp = getattr(header, "stamp", None)
    if stamp is not None:
        sec, nsec = getattr(stamp, "sec", getattr(stamp, "secs", 0)), getattr(stamp, "nanosec", getattr(stamp, "nsecs", 0))
        if sec or nsec:
            return sec + 1e-9 * nsec, True
    return receive_ns * 1e-9, False


def _value(column: str, path: str, raw):
    if column == "position_std":                       # a 3x3 covariance, row-major: east, north variances
        cov = np.asarray(raw, float)
        return math.sqrt(max(cov[0] + cov[4], 0.0)) if cov.size >= 5 and cov[0] + cov[4] > 0 else math.nan
    if column == "fix_quality":
        return float(NAVSAT_QUALITY.get(int(raw), 0))
    return float(raw)


def read_bags(paths: list[Path], given: list[TopicSource], source: Path) -> tuple[dict, dict]:
    """(column -> (times, values), report) of the bags: the standard types by TYPE_MAP, the
    ``given`` topics by their paths. A LogError names the bag, the topic or the field."""
    from rosbags.highlevel import AnyReader

    try:
        reader = AnyReader([Path(p) for p in paths], default_typestore=typestore())
        reader.open()
    except Exception as exc:                         # noqa: BLE001 - rosbags raises many kinds
        raise LogError(f"{', '.join(map(str, paths))}: cannot read as a ROS bag: {type(exc).__name__}: {exc}") from None
    try:
        return _read(reader, given, source)
    finally:
        reader.close()


def _read(reader, given: list[TopicSource], source: Path) -> tuple[dict, dict]:
    topics = {c.topic: c.msgtype for c in reader.connections}
    given = [parse_topic_source(str(g), list(topics)) for g in given]
    wanted: dict[str, list[tuple[str, str, float]]] = {}            # topic -> [(column, path, sign)]
    for g in given:
        if g.topic not in topics:
            raise LogError(f"{source}: --signal {g}: no topic {g.topic!r} in the bag; topics: "
                           + ", ".join(f"{t} ({m})" for t, m in sorted(topics.items())))
        wanted.setdefault(g.topic, []).append((g.column, g.path, g.sign))
    taken = {g.column for g in given}
    for msgtype, fields in TYPE_MAP.items():
        for topic in sorted(t for t, m in topics.items() if m == msgtype):
            for column, path in fields:
                if column not in taken:
                    wanted.setdefault(topic, []).append((column, path, 1.0))
                    taken.add(column)
    rows: dict[str, list] = {t: [] for t in wanted}
    header_used: dict[str, bool] = {}
    connections = [c for c in reader.connections if c.topic in wanted]
    for conn, receive_ns, raw in reader.messages(connections=connections):
        try:
            msg = reader.deserialize(raw, conn.msgtype)
        except Exception as exc:                     # noqa: BLE001 - an unknown type or a broken message
            raise LogError(f"{source}: topic {conn.topic}: cannot decode its messages of type {conn.msgtype} "
                           f"({type(exc).__name__}: {exc}); the bag carries no definition for it and the standard "
                           f"type stores do not know it") from None
        t, from_header = _stamp(msg, receive_ns)
        header_used.setdefault(conn.topic, from_header)
        values = []
        for column, path, sign in wanted[conn.topic]:
            try:
                p = path or _numeric_field(msg)
                if p is None:
                    raise LookupError("the message has several fields: give one, /topic.field")
                raw_value = field(msg, p)
                values.append(sign * _value(column, p, raw_value) if column != "fix_quality" else _value(column, p, raw_value))
            except (LookupError, TypeError, ValueError, IndexError) as exc:
                raise LogError(f"{source}: topic {conn.topic} ({conn.msgtype}), column {column!r}: field "
                               f"{path or '(the only numeric field)'}: {exc}") from None
        rows[conn.topic].append((t, *values))
    signals: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    report_topics = {}
    for topic, columns in wanted.items():
        data = np.array(rows[topic], float)
        if len(data) == 0:
            if any(g.topic == topic for g in given):
                raise LogError(f"{source}: topic {topic} holds no message")
            continue
        data = data[np.argsort(data[:, 0], kind="stable")]
        keep = np.concatenate([[True], np.diff(data[:, 0]) > 0])
        data = data[keep]
        for i, (column, path, _) in enumerate(columns, 1):
            signals[column] = (data[:, 0], data[:, i])
        report_topics[topic] = {"type": topics[topic], "messages": int(len(data)),
                                "rate_hz": float(1.0 / np.median(np.diff(data[:, 0]))) if len(data) > 1 else math.nan,
                                "time": "header stamps" if header_used.get(topic) else "bag receive times",
                                "columns": {c: (path or "(the only numeric field)") for c, path, _ in columns}}
    report = {"topics": report_topics,
              "topics_not_used": {t: m for t, m in sorted(topics.items()) if t not in wanted}}
    return signals, report


def bag_streams(paths: list[Path], options, source: Path):
    """The recording's streams (measurements.recording._Streams) from ROS bags."""
    from .recording import _Streams

    given = [s for s in options.signals if isinstance(s, TopicSource)]
    signals, topics = read_bags(paths, given, source)
    report: dict = {"source": str(source), "files": {"bag": [str(p) for p in paths]}, "dbc": None, "notes": [],
                    "bag": topics, "clocks": {"reference": "the bag's clock: header stamps (receive times where a "
                                                           "message has no header)"}}
    gnss = None
    if "lat" in signals and "lon" in signals:
        t, lat = signals.pop("lat")
        lon = np.interp(t, *signals.pop("lon"))
        height = np.interp(t, *signals.pop("height")) if "height" in signals else np.zeros(len(t))
        quality = np.interp(t, *signals.pop("fix_quality")) if "fix_quality" in signals else np.ones(len(t))
        std = np.interp(t, *signals.pop("position_std")) if "position_std" in signals else np.full(len(t), np.nan)
        fix = (quality > 0) & np.isfinite(lat) & np.isfinite(lon)
        if fix.sum() >= 2:
            gnss = pd.DataFrame({"utc": t[fix], "lat": lat[fix], "lon": lon[fix], "height": height[fix],
                                 "quality": quality[fix], "speed": np.nan, "course": np.nan, "heading": np.nan,
                                 "position_std": std[fix]})
            report["first_fix_utc"] = float(t[fix][0])
        else:
            report["notes"].append(f"the NavSatFix topic holds {int(fix.sum())} messages with a fix: no positions")
    for column in ("height", "fix_quality", "position_std"):
        signals.pop(column, None)
    if not signals and gnss is None:
        raise LogError(f"{source}: no topic of a known type (NavSatFix, Imu, Odometry, TwistStamped, "
                       f"AckermannDriveStamped) and no --signal; topics: "
                       + ", ".join(f"{t} ({m})" for t, m in topics["topics_not_used"].items()))
    columns = {c: f"{t} ({v['type']}).{v['columns'][c]}" for t, v in topics["topics"].items() for c in v["columns"]
               if c in signals}
    if gnss is not None:
        columns.update({"x": "NavSatFix latitude/longitude -> east of the run's first fix (pymap3d)",
                        "y": "NavSatFix latitude/longitude -> north of the run's first fix (pymap3d)"})
    report["columns"] = {**columns, "t": "the bag's clock, s from the run's start"}
    held = {c for c in ("delta_cmd", "speed_cmd") if c in signals}
    return _Streams(gnss, signals, report, held, {c: resolution(v) for c, (_, v) in signals.items()})
