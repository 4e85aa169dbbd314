"""ROS bags as a recording: ROS 1 ``.bag``, ROS 2 ``.db3`` or ``.mcap`` files, or a
rosbag2 folder, read with rosbags (no ROS install).

Standard messages are mapped by their type, without options (TYPE_MAP):

- ``sensor_msgs/NavSatFix``: latitude, longitude, altitude -> x, y about the first fix; status ->
  ``fix_quality`` (NO_FIX -1 -> 0, FIX 0 -> 1, SBAS 1 -> 2 (differential), GBAS 2 -> 4 (ground-based
  augmentation, RTK's class)); the covariance's horizontal part -> ``position_std``;
- ``sensor_msgs/Imu``: ``yaw_rate`` from angular_velocity.z, or from the axis its accelerometer
  names vertical when that is x or y (an IMU mounted on its side: measurements.imu_axes), named;
- ``nav_msgs/Odometry``: ``v`` from twist.twist.linear.x, ``yaw_rate`` from twist.twist.angular.z
  (an IMU's wins: a wheel odometry's, one whose topic does not name a filter or fusion, is then
  ``odom_yaw_rate``, the input of identify's skid-steer model; another source ``yaw_rate_2``);
- ``geometry_msgs/TwistStamped``: ``v`` and ``yaw_rate`` likewise;
- ``ackermann_msgs/AckermannDriveStamped``: ``delta_cmd`` from drive.steering_angle, ``speed_cmd``
  from drive.speed.

Any numeric field of any topic, custom messages included: ``--signal COLUMN=/topic[.field.path]``
(``a.b[2].c``; a message with one numeric field needs no path), in expressions with units
(measurements.signal_expressions: a standard message's field has its SI unit, a custom one's must be
declared for an angle, a rate or a speed); ``lat``/``lon`` columns in degrees become x/y.
Topics of other types (/rosout, /tf, ...) are listed in the report, not read. Times are
the messages' header stamps where they have a header with a stamp, else the bag's receive times;
every topic is on that one clock, and the report says which each topic used. ``--time
/topic.field[unit]`` names a topic whose values are the data's own clock (a logger's counter written
beside its samples, a bag recorded while a log was replayed at another speed): every message's time on
the bag's clock is then carried onto it, linearly between that topic's messages (on_data_clock). Topics read on the
bag's receive times, or whose header stamps sit within STAMP_ON_RECEIVE s of them, share the bag's
clock (Streams.clocks): a lag between them is a sensor's own latency, never a clock to align.

Imported where used: rosbags (the bags extra).
"""
from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np

from .bag_records import check_bag_file
from .imu_axes import AXES, describe, vertical_axis
from .log import LogError
from .modes import MODE_VALUES, is_mode_name
from .runs import held as in_force
from .signal_expressions import SignalSpec, evaluate, parse_signal, unknown_name
from .streams import Reader, Series, Streams, gnss_table, iso
from .tables import parse_time

BAG_SUFFIXES = (".bag", ".db3", ".mcap")

# ackermann_msgs is not in the rosbags type stores; its layout (ROS 1 and 2 alike)
ACKERMANN = {
    "ackermann_msgs/msg/AckermannDrive": "float32 steering_angle\nfloat32 steering_angle_velocity\nfloat32 speed\n"
                                         "float32 acceleration\nfloat32 jerk\n",
    "ackermann_msgs/msg/AckermannDriveStamped": "std_msgs/Header header\nackermann_msgs/AckermannDrive drive\n",
}
NAVSAT_QUALITY = {-1: 0, 0: 1, 1: 2, 2: 4}
IMU = "sensor_msgs/msg/Imu"
FUSED = re.compile(r"filter|ekf|ukf|fus|global|map|slam|visual|lidar|icp|gps|gnss", re.I)   # not a wheel odometry
STAMP_ON_RECEIVE = 0.08     # s: header stamps this close to the receive times (median) are on the bag's clock
IMU_AXES_READ = tuple(f"linear_acceleration.{a}" for a in AXES) + ("angular_velocity.x", "angular_velocity.y")

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


# the units of standard messages' fields (REP 103: SI, angles in radians; NavSatFix in degrees)
FIELD_UNITS = [
    (("sensor_msgs/msg/NavSatFix",), {"latitude": "deg", "longitude": "deg", "altitude": "m"}),
    (("sensor_msgs/msg/Imu",), {"angular_velocity.": "rad/s", "linear_acceleration.": "m/s^2"}),
    (("nav_msgs/msg/Odometry",), {"twist.twist.linear.": "m/s", "twist.twist.angular.": "rad/s",
                                  "pose.pose.position.": "m"}),
    (("geometry_msgs/msg/TwistStamped",), {"twist.linear.": "m/s", "twist.angular.": "rad/s"}),
    (("geometry_msgs/msg/Twist",), {"linear.": "m/s", "angular.": "rad/s"}),
    (("geometry_msgs/msg/PoseStamped",), {"pose.position.": "m"}),
    (("ackermann_msgs/msg/AckermannDriveStamped",), {"drive.steering_angle": "rad", "drive.speed": "m/s",
                                                     "drive.steering_angle_velocity": "rad/s"}),
    (("ackermann_msgs/msg/AckermannDrive",), {"steering_angle": "rad", "speed": "m/s"}),
]


def field_unit(msgtype: str, path: str) -> str | None:
    """The SI unit of a standard message's field (None: a custom message, or a field without one)."""
    for types, fields in FIELD_UNITS:
        if msgtype in types:
            for prefix, unit in fields.items():
                if path == prefix or (prefix.endswith(".") and path.startswith(prefix)):
                    return unit
    return None


BITS = {"int8": 8, "uint8": 8, "byte": 8, "char": 8, "int16": 16, "uint16": 16, "int32": 32, "uint32": 32}
BASE, NAME, ARRAY, SEQUENCE = 1, 2, 3, 4      # rosbags' Nodetype of a field definition


def field_width(fielddefs: dict, msgtype: str, path: str) -> float | None:
    """The modulus 2^bits of the integer field of fixed width (uint16 ... uint32) at ``path``
    (``a.b[2].c``; empty: the message's one numeric field) of ``msgtype``, by the bag's message
    definitions (a counter's rate() unwraps at it: signal_expressions.counter_rate); None for a
    float, a 64-bit integer or a path they do not resolve."""
    kind, what = NAME, msgtype
    if not path:
        fields = fielddefs.get(msgtype, ((), ()))[1]
        numeric = [d for _, d in fields if int(d[0]) == BASE and d[1][0] not in ("string", "bool")]
        kind, what = numeric[0] if len(numeric) == 1 else (NAME, None)
    for part in path.split(".") if path else ():
        name, _, index = part.partition("[")
        fields = dict(fielddefs[what][1]) if kind == NAME and what in fielddefs else {}
        if name not in fields:
            return None
        kind, what = fields[name]
        if index:
            if int(kind) not in (ARRAY, SEQUENCE):
                return None
            kind, what = what[0]
    bits = BITS.get(what[0]) if int(kind) == BASE else None
    return float(2 ** bits) if bits else None


def split_name(name: str, topics: list[str]) -> tuple[str, str]:
    """(topic, field path) of ``/topic.field.path``: the longest topic of the bag that prefixes it
    (a topic name may hold dots only where the bag says so), else up to the first dot."""
    known = [t for t in topics if name == t or name.startswith(t + ".")]
    if known:
        topic = max(known, key=len)
        return topic, name[len(topic) + 1:]
    head, _, tail = name.rpartition("/")
    topic, _, path = tail.partition(".")
    return f"{head}/{topic}", path


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


def _mode_code(codes: dict, raw) -> float:
    """A mode channel's value: a number as it is, a text as its code (first seen, first numbered;
    at most MODE_VALUES texts)."""
    if isinstance(raw, (int, float, np.number)) and not isinstance(raw, bool):
        return float(raw)
    text = (raw.decode(errors="replace") if isinstance(raw, bytes) else str(raw)).strip()
    if text not in codes and len(codes) >= MODE_VALUES:
        raise ValueError(f"more than {MODE_VALUES} values ({', '.join(list(codes)[:5])} ...): not a mode")
    return float(codes.setdefault(text, len(codes)))


def open_bags(paths: list[Path]):
    """An open rosbags AnyReader of ``paths``, each bag file's records checked first
    (measurements.bag_records); a LogError names the file and what cannot be read."""
    from rosbags.highlevel import AnyReader

    paths = [Path(p) for p in paths]
    for p in paths:
        for file in (sorted(p.iterdir()) if p.is_dir() else [p]):
            if file.suffix in BAG_SUFFIXES and file.is_file():
                check_bag_file(file)
    try:
        reader = AnyReader(paths, default_typestore=typestore())
        reader.open()
    except Exception as exc:                         # noqa: BLE001 - rosbags raises many kinds
        raise LogError(f"{', '.join(map(str, paths))}: cannot read as a ROS bag: {type(exc).__name__}: {exc}") from None
    return reader


def bag_messages(reader, connections: list, paths: list[Path]):
    """(connection, receive time in ns, raw bytes) of ``connections``; damage found while reading
    is a LogError naming the bag, the message count read and the last topic and receive time."""
    count, last = 0, None
    try:
        for count, (conn, receive_ns, raw) in enumerate(reader.messages(connections=connections), 1):
            last = (conn.topic, receive_ns)
            yield conn, receive_ns, raw
    except Exception as exc:                         # noqa: BLE001 - rosbags raises many kinds on damaged bytes
        after = f" after topic {last[0]} at receive time {last[1] * 1e-9:.9f} s" if last else ""
        raise LogError(f"{', '.join(map(str, paths))}: cannot read as a ROS bag, it is damaged: message "
                       f"{count + 1 if last else 1} cannot be read{after} ({type(exc).__name__}: {exc})") from None


def read_bags(paths: list[Path], given: list, source: Path) -> tuple[dict, dict]:
    """(column -> (times, values in the column's unit), report) of the bags: the standard types
    by TYPE_MAP, the ``given`` expressions (SignalSpec) by their ``/topic.field`` names. A
    LogError names the bag, the topic or the field."""
    reader = open_bags(paths)
    try:
        return _read(reader, given, source)
    finally:
        reader.close()


def _read(reader, given: list, source: Path) -> tuple[dict, dict]:
    """(column -> (times, values), report) of an open bag: the topics' fields that ``given`` names
    and the standard types' (TYPE_MAP), read message by message, then evaluated."""
    topics = {c.topic: c.msgtype for c in reader.connections}
    wanted = _named_fields(given, topics, source)
    auto = _standard_fields(given, topics, wanted)
    _imu_axes_wanted(auto, topics, wanted)
    labels = {n: {} for spec in given if is_mode_name(spec.column) for n in spec.names[:1]}    # a mode's text values
    rows, header_used = _messages(reader, wanted, auto, source, labels)
    series, report_topics, stamps = _topic_series(rows, header_used, wanted, topics, given, source)
    for name, s in series.items():                 # an integer field's width: a counter's rate() unwraps at it
        topic = next(t for t, names in wanted.items() if name in names)
        s.wrap = field_width(reader.typestore.fielddefs, topics[topic], wanted[topic][name])
    turned = _vertical_yaw_rates(auto, series, topics)
    sums: dict = {}
    signals = _evaluated(given, auto, series, topics, report_topics, source, sums)
    report = {"topics": report_topics, "stamp_vs_receive": stamps, "sums": sums,
              "mode_labels": {spec.column: list(labels[spec.names[0]]) for spec in given
                              if spec.names[0] in labels and labels[spec.names[0]] and spec.column in signals},
              "topics_not_used": {t: m for t, m in sorted(topics.items()) if t not in wanted}}
    others = [s for c, s in auto.items() if c.startswith("yaw_rate_") and c in signals]
    if others:
        report["choices"] = [f"yaw_rate: {auto['yaw_rate'].names[0]} (the first gyro topic) used; also "
                             + ", ".join(f"{s.names[0]} as {s.column}" for s in others)
                             + " (the audit compares them; --signal yaw_rate=/topic.angular_velocity.z chooses)"]
    if "odom_yaw_rate" in auto and "odom_yaw_rate" in signals:
        report.setdefault("choices", []).append(
            f"odom_yaw_rate: {auto['odom_yaw_rate'].names[0]} (a wheel odometry's turn rate, beside the gyro's "
            f"yaw_rate {auto['yaw_rate'].names[0]}): the input identify's skid-steer model takes "
            f"(identification.skid_steer); the audit compares it with yaw_rate; --signal "
            f"yaw_rate_2={auto['odom_yaw_rate'].names[0]} keeps it a second yaw-rate source only")
    if turned:
        report["choices"] = turned + report.get("choices", [])
    return signals, report


def _imu_axes_wanted(auto: dict, topics: dict[str, str], wanted: dict) -> None:
    """The accelerometer and the other gyro axes of each IMU topic a yaw rate is taken from,
    added to ``wanted`` (read, not written: imu_axes names the vertical axis from them)."""
    for spec in auto.values():
        topic, path = split_name(spec.names[0], list(topics))
        if spec.column.startswith("yaw_rate") and topics.get(topic) == IMU:
            for p in IMU_AXES_READ:
                wanted[topic].setdefault(f"{topic}.{p}", p)


def _vertical_yaw_rates(auto: dict, series: dict, topics: dict[str, str]) -> list[str]:
    """A yaw rate the standard map takes from an IMU's z whose accelerometer reads gravity on x
    or y: that axis's angular velocity instead, signed as the reading; one note per IMU turned."""
    notes = []
    for column, spec in list(auto.items()):
        topic, path = split_name(spec.names[0], list(topics))
        if not column.startswith("yaw_rate") or topics.get(topic) != IMU or path != "angular_velocity.z":
            continue
        names = {a: f"{topic}.linear_acceleration.{a}" for a in AXES}
        found = vertical_axis({a: series[n].values for a, n in names.items() if n in series})
        if found is None or found[0] == "z" or f"{topic}.angular_velocity.{found[0]}" not in series:
            continue
        axis, sign, means = found
        name = f"{topic}.angular_velocity.{axis}"
        auto[column] = SignalSpec(column, ((name, sign),), 0.0, None, f"{column}={'-' if sign < 0 else ''}{name}")
        notes.append(describe(topic, axis, sign, means))
    return notes


def _named_fields(given: list, topics: dict[str, str], source: Path) -> dict[str, dict[str, str]]:
    """topic -> {name: field path} of every ``/topic.field`` the ``given`` expressions name; a
    LogError names a name that is not a topic's field, or a topic the bag does not hold."""
    wanted: dict[str, dict[str, str]] = {}
    for spec in given:
        for name in spec.names:
            if not name.startswith("/"):
                raise LogError(f"{source}: --signal {spec}: {name!r} is not a topic's field; a ROS bag's signals are "
                               f"named /topic.field.path (topics: {', '.join(sorted(topics))})")
            topic, path = split_name(name, list(topics))
            if topic not in topics:
                near = unknown_name(str(source), spec, topic, sorted(topics), "topic")
                raise LogError(str(near).split(" (convert")[0].split("; ")[0] + "; topics: "
                               + ", ".join(f"{t} ({m})" for t, m in sorted(topics.items())))
            wanted.setdefault(topic, {})[name] = path
    return wanted


def wheel_odometry(topic: str, msgtype: str) -> bool:
    """An Odometry topic whose name does not say it is fused or estimated otherwise (FUSED): a wheel
    odometry, whose turn rate is the input of a skid-steered vehicle's yaw model."""
    return msgtype == "nav_msgs/msg/Odometry" and not FUSED.search(topic)


def _standard_fields(given: list, topics: dict[str, str], wanted: dict) -> dict[str, SignalSpec]:
    """column -> expression of the standard types' fields (TYPE_MAP; the first topic of the first
    type that has a column gives it, a column ``given`` is not taken), added to ``wanted``. Another
    gyro topic is kept as yaw_rate_2 ... for the audit to compare (the first is used); a wheel
    odometry's (wheel_odometry) as ``odom_yaw_rate``, identify's skid-steer input."""
    taken = {g.column for g in given}
    auto: dict[str, SignalSpec] = {}
    for msgtype, fields in TYPE_MAP.items():
        for topic in sorted(t for t, m in topics.items() if m == msgtype):
            for column, path in fields:
                if column not in taken:
                    taken.add(column)
                elif column == "yaw_rate" and "yaw_rate" in auto and auto["yaw_rate"].names[0].split(".")[0] != topic:
                    column = ("odom_yaw_rate" if wheel_odometry(topic, msgtype) and "odom_yaw_rate" not in taken else
                              f"yaw_rate_{sum(c.startswith('yaw_rate') for c in auto) + 1}")
                    taken.add(column)
                else:
                    continue
                name = f"{topic}.{path}"
                wanted.setdefault(topic, {})[name] = path
                auto[column] = SignalSpec(column, ((name, 1.0),), 0.0, None, f"{column}={name}")
    return auto


def _messages(reader, wanted: dict, auto: dict, source: Path, labels: dict) -> tuple[dict[str, list], dict[str, bool]]:
    """(topic -> rows (stamp, receive time, every wanted field's value), topic -> whether its
    stamps are the headers'): the wanted topics' messages, decoded; a LogError names a message
    that cannot be decoded or a field it lacks. A mode channel's text (``labels``: name -> {text:
    code}) is written as its code."""
    rows: dict[str, list] = {t: [] for t in wanted}
    header_used: dict[str, bool] = {}
    connections = [c for c in reader.connections if c.topic in wanted]
    # rosbags reads every topic when given no connection: nothing wanted, nothing read
    for conn, receive_ns, raw in (bag_messages(reader, connections, [source]) if connections else ()):
        try:
            msg = reader.deserialize(raw, conn.msgtype)
        except Exception as exc:                     # noqa: BLE001 - an unknown type or a broken message
            why = "its bytes are damaged" if conn.msgtype in reader.typestore.fielddefs else \
                "the bag carries no definition for it and the standard type stores do not know it"
            raise LogError(f"{source}: topic {conn.topic}: message {len(rows[conn.topic]) + 1} of the topic (receive "
                           f"time {receive_ns * 1e-9:.9f} s) cannot be decoded as {conn.msgtype}: {why} "
                           f"({type(exc).__name__}: {exc})") from None
        t, from_header = _stamp(msg, receive_ns)
        header_used.setdefault(conn.topic, from_header)
        values = []
        for name, path in wanted[conn.topic].items():
            try:
                p = path or _numeric_field(msg)
                if p is None:
                    raise LookupError("the message has several fields: give one, /topic.field")
                column = next((c for c, s in auto.items() if s.names[0] == name), "")
                raw = field(msg, p)
                values.append(_mode_code(labels[name], raw) if name in labels else _value(column, p, raw))
            except (LookupError, TypeError, ValueError, IndexError) as exc:
                raise LogError(f"{source}: topic {conn.topic} ({conn.msgtype}): field "
                               f"{path or '(the only numeric field)'}: {exc}") from None
        rows[conn.topic].append((t, receive_ns * 1e-9, *values))
    return rows, header_used


def _topic_series(rows: dict, header_used: dict, wanted: dict, topics: dict, given: list,
                  source: Path) -> tuple[dict[str, Series], dict, dict]:
    """(name -> Series, topic -> its report, topic -> receive time - header stamp statistics) of
    the rows: sorted by stamp, a repeated stamp dropped (the first kept); a topic ``given`` names
    that holds no message is refused."""
    series: dict[str, Series] = {}
    report_topics, stamps = {}, {}
    for topic, names in wanted.items():
        data = np.array(rows[topic], float)
        if len(data) == 0:
            if any(n in s.names for s in given for n in names):
                raise LogError(f"{source}: topic {topic} holds no message")
            continue
        data = data[np.argsort(data[:, 0], kind="stable")]
        data = data[np.concatenate([[True], np.diff(data[:, 0]) > 0])]
        for i, (name, path) in enumerate(names.items(), 2):
            series[name] = Series(data[:, 0], data[:, i], field_unit(topics[topic], path), name)
        late = data[:, 1] - data[:, 0]                 # receive time - header stamp
        if header_used.get(topic) and len(late):
            stamps[topic] = {"median": float(np.median(late)), "p95": float(np.percentile(late, 95)),
                             "min": float(late.min()), "max": float(late.max())}
        report_topics[topic] = {"type": topics[topic], "messages": int(len(data)),
                                "rate_hz": float(1.0 / np.median(np.diff(data[:, 0]))) if len(data) > 1 else math.nan,
                                "time": "header stamps" if header_used.get(topic) else "bag receive times",
                                "columns": {}}
    return series, report_topics, stamps


def _evaluated(given: list, auto: dict, series: dict, topics: dict, report_topics: dict,
               source: Path, sums: dict) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """column -> (times, values) of every expression whose names the bag holds (``given`` first,
    then the standard fields); a fix's quality and error, and the standard positions, are taken
    as they are (no unit conversion). Each topic's report names the columns it gave; ``sums``
    gets each sum's fastest term's share (signal_expressions.evaluate)."""
    signals: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for spec in list(given) + list(auto.values()):
        if not all(n in series for n in spec.names):
            continue
        if spec.column in ("fix_quality", "position_std") or is_mode_name(spec.column):
            s = series[spec.names[0]]
            signals[spec.column] = (s.t, s.values)
            how = spec.names[0]
        elif spec.column in ("lat", "lon", "height") and spec in auto.values():
            s = series[spec.names[0]]
            signals[spec.column] = (s.t, s.values)
            how = spec.names[0]
        else:
            t, v, how = evaluate(spec, {n: series[n] for n in spec.names}, str(source), sums=sums)
            signals[spec.column] = (t, v)
        for n in spec.names:
            topic = split_name(n, list(topics))[0]
            if topic in report_topics:
                report_topics[topic]["columns"][spec.column] = how
    return signals


def list_bag(paths: list[Path]) -> list[str]:
    """``--list``: each topic, its type, count and rate, and the numeric fields of its first message."""
    reader = open_bags(paths)
    lines = []
    try:
        lines.append(f"ROS bag {', '.join(p.name for p in paths)}: {len(reader.connections)} topic(s), "
                     f"{(reader.end_time - reader.start_time) * 1e-9:.1f} s")
        for conn in sorted(reader.connections, key=lambda c: c.topic):
            count = conn.msgcount
            rate = count / max((reader.end_time - reader.start_time) * 1e-9, 1e-9)
            used = [c for c, _ in TYPE_MAP.get(conn.msgtype, [])]
            lines.append(f"  {conn.topic} ({conn.msgtype}): {count} messages, about {rate:.3g} Hz"
                         + (f"; read without options as {', '.join(used)}" if used else ""))
            first = next(bag_messages(reader, [conn], paths), None)
            if first is None:
                continue
            try:
                msg = reader.deserialize(first[2], conn.msgtype)
            except Exception as exc:                 # noqa: BLE001
                lines.append(f"    (cannot decode: {type(exc).__name__}: {exc})")
                continue
            for path, value in _numeric_paths(msg)[:40]:
                unit = field_unit(conn.msgtype, path)
                lines.append(f"    {conn.topic}.{path}{f' [{unit}]' if unit else ''}: {value:.6g} (first message)")
    finally:
        reader.close()
    return lines


def _numeric_paths(msg, prefix: str = "") -> list[tuple[str, float]]:
    """(field path, value) of a message's numeric fields, nested ones with dotted paths; its
    constants (a type's ClassVars, rosgraph_msgs/Log's DEBUG = 1 ...) are not fields."""
    out = []
    declared = getattr(type(msg), "__annotations__", {})
    for k in (f.name for f in dataclasses.fields(msg)) if dataclasses.is_dataclass(msg) else ():
        if k.startswith("__") or str(declared.get(k, "")).startswith(("ClassVar", "typing.ClassVar")):
            continue                    # a constant (rosbags declares them ClassVar, as text dataclasses keep)
        v = getattr(msg, k)
        path = f"{prefix}{k}"
        if isinstance(v, bool):
            continue
        if isinstance(v, (int, float, np.number)):
            out.append((path, float(v)))
        elif isinstance(v, np.ndarray) and v.dtype.kind in "iuf" and v.size <= 9:
            out += [(f"{path}[{i}]", float(x)) for i, x in enumerate(v.ravel())]
        elif hasattr(v, "__dataclass_fields__") and k not in ("header", "stamp"):
            out += _numeric_paths(v, path + ".")
    return out


CLOCK_COLUMN = "data_clock"      # the --time topic's values, read as a column and taken out


def clock_spec(text: str | None, source: Path) -> SignalSpec | None:
    """``--time`` for a bag: ``/topic[.field][unit]`` with a unit of time, read as a signal; None
    without --time. Any other form is refused, naming what a bag's --time takes."""
    if text is None:
        return None
    spec = parse_time(text)
    if len(spec.columns) != 1 or not spec.columns[0].startswith("/") or spec.unit in (None, "datetime"):
        raise LogError(f"{source}: --time {text!r}: a ROS bag takes --time /topic.field[unit] (s, ms, us, ns): the "
                       f"topic whose values are the data's own clock; without --time the bag's clock is used (header "
                       f"stamps, else receive times)")
    return parse_signal(f"{CLOCK_COLUMN}={spec.columns[0]}[{spec.unit}]")


def on_data_clock(signals: dict, clock: tuple[np.ndarray, np.ndarray], text: str, source: Path) -> tuple[dict, float]:
    """(signals on the data's clock, seconds of data per second of the bag): each time t on the bag's
    clock becomes c(t), c linear between the clock topic's messages (its bag times -> its values [s])
    and extended beyond them at its mean rate. The clock's values must increase."""
    tb, tv = (np.asarray(a, float) for a in clock)
    rising = np.diff(tv) > 0                # a NaN neither rises nor falls: refused as a restart is
    if len(tv) < 2 or not rising.all():
        i = int(np.argmax(~rising)) + 1 if len(tv) >= 2 else 0
        raise LogError(f"{source}: --time {text!r}: the clock's values must increase from one message to the next; "
                       + (f"message {i + 1} holds {tv[i]:.9g} s after {tv[i - 1]:.9g} s (a counter that wraps or "
                          f"restarts: convert the stretch before it with --time-range)" if len(tv) >= 2 else
                          f"it holds {len(tv)} message(s)"))
    rate = float((tv[-1] - tv[0]) / (tb[-1] - tb[0]))

    def move(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, float)
        out = np.interp(t, tb, tv)
        out = np.where(t < tb[0], tv[0] + (t - tb[0]) * rate, out)
        return np.where(t > tb[-1], tv[-1] + (t - tb[-1]) * rate, out)

    return {c: (move(t), v) for c, (t, v) in signals.items()}, rate


def bag_streams(paths: list[Path], options, source: Path):
    """The recording's streams from ROS bags."""
    clock = clock_spec(options.time, source)
    try:
        signals, topics = read_bags(paths, list(options.signals) + ([clock] if clock else []), source)
    except LogError as err:            # the clock is read as a signal: its errors are said as the --time given
        raise LogError(str(err).replace(f"--signal {CLOCK_COLUMN}=", "--time ")) from None
    reference = "the bag's clock: header stamps (receive times where a message has no header)"
    notes = list(topics.pop("choices", []))
    if clock is not None:
        signals, rate = on_data_clock(signals, signals.pop(CLOCK_COLUMN), options.time, source)
        reference = (f"{clock.names[0]} [{clock.unit}] (--time): the data's own clock, each message's time on the "
                     f"bag's clock carried onto it between that topic's messages")
        notes.append(f"time: {clock.names[0]} [{clock.unit}] runs {rate:.4g} s per second of the bag's clock"
                     + (f" (the bag took {1 / rate:.3g} s per second of data: recorded while a log was replayed "
                        f"slower?)" if rate < 0.95 else f" (the bag took {1 / rate:.3g} s per second of data: "
                        f"recorded while a log was replayed faster?)" if rate > 1.05 else ""))
    report: dict = {"source": str(source), "files": {"bag": [str(p) for p in paths]}, "dbc": None,
                    "notes": notes, "stamp_vs_receive": topics.pop("stamp_vs_receive", {}), "sums": topics.pop("sums"),
                    "bag": topics, "clocks": {"reference": reference}}
    gnss = None
    if "lat" in signals and "lon" in signals:
        t, lat = signals.pop("lat")
        lon = np.interp(t, *signals.pop("lon"))
        height = np.interp(t, *signals.pop("height")) if "height" in signals else np.zeros(len(t))
        quality = in_force(t, *signals.pop("fix_quality")) if "fix_quality" in signals else np.full(len(t), np.nan)
        std = np.interp(t, *signals.pop("position_std")) if "position_std" in signals else np.full(len(t), np.nan)
        fix = (quality != 0) & np.isfinite(lat) & np.isfinite(lon)          # NaN: a quality not given
        if fix.sum() >= 2:
            gnss = gnss_table(t[fix], lat[fix], lon[fix], height[fix], quality[fix], None, std[fix])
            report["first_fix_utc"] = iso(float(t[fix][0]))
        else:
            report["notes"].append(f"the NavSatFix topic holds {int(fix.sum())} messages with a fix: no positions")
    for column in ("height", "fix_quality", "position_std"):
        signals.pop(column, None)
    if not signals and gnss is None:
        raise LogError(f"{source}: no topic of a known type (NavSatFix, Imu, Odometry, TwistStamped, "
                       f"AckermannDriveStamped) and no --signal; topics: "
                       + ", ".join(f"{t} ({m})" for t, m in topics["topics_not_used"].items())
                       + "; map a field with --signal COLUMN=/topic.field[unit] (convert SOURCE --list shows the fields)")
    columns = {c: how for v in topics["topics"].values() for c, how in v["columns"].items() if c in signals}
    if gnss is not None:
        named = {c: next((f"{t} ({v['type']})" for t, v in topics["topics"].items() if c in v["columns"]), c)
                 for c in ("lat", "lon")}
        source_of = named["lat"] if named["lat"] == named["lon"] else f"{named['lat']} and {named['lon']}"
        columns.update({"x": f"latitude/longitude of {source_of} -> east of the run's first fix (pymap3d)",
                        "y": f"latitude/longitude of {source_of} -> north of the run's first fix (pymap3d)"})
    report["columns"] = {**columns, "t": ("the data's clock (--time), " if clock else "the bag's clock, ")
                         + "s from the run's start"}
    held = {c for c in signals if c in ("delta_cmd", "speed_cmd") or is_mode_name(c)}   # a mode: held at its own times
    groups = {c: topic for topic, v in topics["topics"].items() for c in v["columns"] if c in signals}
    fixes = next((topic for topic, v in topics["topics"].items() if "lat" in v["columns"]), None)
    if gnss is not None and fixes is not None:
        groups["gnss"] = fixes          # the receiver's fixes keep their topic's clock
    clocks = bag_clocks(topics["topics"], report["stamp_vs_receive"], paths)
    if clock is not None:
        clocks = {topic: f"the data's clock ({clock.names[0]}, --time)" for topic in clocks}
    return Streams(gnss, signals, report, held, {}, groups=groups, labels=topics.pop("mode_labels", {}), clocks=clocks)


def bag_clocks(report_topics: dict, stamps: dict, paths: list[Path]) -> dict[str, str]:
    """topic -> the bag's clock, for the topics on it: one recorder stamps every message's
    receive time, so a topic read on receive times is on it, and so is one whose header stamps sit
    within STAMP_ON_RECEIVE s of its receive times (median): stamped by a clock that agrees with
    the recorder's to better than the least offset the audit would align. A topic stamped farther
    off keeps a clock of its own."""
    bag = f"the bag's receive clock ({', '.join(Path(p).name for p in paths)})"
    return {topic: bag for topic, v in report_topics.items()
            if v.get("time") != "header stamps" or abs(stamps.get(topic, {}).get("median", math.inf)) <= STAMP_ON_RECEIVE}


class BagReader(Reader):
    """ROS bags: ROS 1 and ROS 2 files, and rosbag2 folders (a metadata.yaml in them)."""

    kind, name, listed = "bag", "ROS bags", "ROS topics and types"
    files = "*.bag, *.db3, *.mcap, a rosbag2 folder"
    suffixes = BAG_SUFFIXES
    streamed = True

    def claims(self, path: Path) -> bool:
        return super().claims(path) or (path.is_dir() and (path / "metadata.yaml").is_file())

    def streams(self, files: dict[str, list[Path]], options, source: Path) -> Streams:
        return bag_streams(files[self.kind], options, source)

    def listing(self, paths: list[Path], options, source: Path) -> list[str]:
        return list_bag(paths)


READER = BagReader()
