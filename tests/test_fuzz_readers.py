"""Fuzzed recordings and field files: random bytes, and real files from tests/data (and generated
ones) with bytes flipped, cut, repeated or inserted, go through the readers as a user's would
(measurements.recording.import_recording, fields.read_fields). Each gives a log whose time
increases and whose values are finite where they must be, or the readers' own error (an
InputError: exit 2 from the command line), never another exception, within a time and memory
bound. Fixed seed (derandomized): the same examples every run."""
from __future__ import annotations

import resource
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from agrobot.orchestrator.errors import InputError
from harness.generated_recordings import write_candump, write_nmea, write_timelog

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
SETTINGS = settings(max_examples=300, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
SECONDS = 20.0          # one example's bound (the readers take well under one on these sizes)
GROWTH_MB = 600.0       # the process's peak memory may grow by this much over a whole test


def _mutations():
    """A list of edits (kind, where as a fraction of the file, length, byte)."""
    edit = st.tuples(st.sampled_from(["flip", "cut", "repeat", "insert", "truncate", "zero"]),
                     st.floats(0.0, 1.0), st.integers(1, 64), st.integers(0, 255))
    return st.lists(edit, min_size=1, max_size=6)


def mutate(data: bytes, edits) -> bytes:
    out = bytearray(data)
    for kind, where, length, byte in edits:
        i = min(int(where * len(out)), max(len(out) - 1, 0))
        if kind == "flip" and out:
            out[i] ^= byte or 1
        elif kind == "cut":
            del out[i:i + length]
        elif kind == "repeat":
            out[i:i] = out[i:i + length]
        elif kind == "insert":
            out[i:i] = bytes([byte]) * length
        elif kind == "truncate":
            del out[i:]
        elif kind == "zero":
            out[i:i + length] = bytes(len(out[i:i + length]))
    return bytes(out)


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _import(path: Path, options=None) -> None:
    """A recording read whole: a valid log with a well-formed audit, or the readers' own error."""
    from agrobot.measurements.recording import import_recording

    start = time.perf_counter()
    try:
        frame, report = import_recording(path, options)
    except InputError as exc:
        assert str(exc) and "Traceback" not in str(exc)
        return
    finally:
        assert time.perf_counter() - start < SECONDS
    t = frame["t"].to_numpy(float)
    assert len(t) >= 2 and np.all(np.diff(t) > 0) and np.isfinite(t).all()
    for column in ("x", "y", "delta", "v", "yaw_rate"):
        if column in frame:
            assert np.isfinite(frame[column].to_numpy(float)).all(), column
    assert "used" in report
    _well_formed(frame.attrs["audit"])


def _well_formed(findings) -> None:
    """Every finding in the shape measurements.audit documents, JSON-able, its numbers finite."""
    import json
    import math

    from agrobot.measurements import audit

    kinds = [line.split("``")[1] for line in audit.__doc__.splitlines() if line.startswith("- ``")]
    for f in findings:
        extra = {"updates_hz"} if f.get("kind") == "held_samples" else set()
        assert set(f) == {"kind", "channels", "value", "interval", "unit", "meaning", "resolved"} | extra, f
        assert f["kind"] in kinds and isinstance(f["resolved"], bool) and f["meaning"] and f["channels"]
        assert math.isfinite(f["value"]) and (f["interval"] is None or all(math.isfinite(x) for x in f["interval"]))
    json.dumps(findings, allow_nan=False)


def _fields(path: Path) -> None:
    from agrobot.fields import read_fields

    start = time.perf_counter()
    try:
        fields = read_fields(path)
    except InputError as exc:
        assert str(exc)
        return
    finally:
        assert time.perf_counter() - start < SECONDS
    names = [f.name for f in fields]
    assert len(names) == len(set(names))
    for f in fields:
        xy = np.asarray(f.boundary.exterior.coords)
        assert np.isfinite(xy).all() and np.abs(xy).max() <= 4.1e7


# --- the bases: real copies and generated recordings --------------------------------------------------------------
def _bases() -> dict[str, bytes]:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        return {"nmea": (DATA / "nmea_gpsd_testlogs" / "nmea-rtk.log").read_bytes(),
                "nmea_generated": write_nmea(tmp / "g.nmea", 20.0).read_bytes(),
                "can": write_candump(tmp / "c.log", 15.0).read_bytes(),
                "tlg_bin": (write_timelog(tmp / "t", 60) / "TLG00001.bin").read_bytes(),
                "tlg_xml": (tmp / "t" / "TLG00001.xml").read_bytes()}


BASES = _bases()
KML = (b'<kml xmlns="http://www.opengis.net/kml/2.2"><Document><Placemark><name>square</name><Polygon>'
       b'<outerBoundaryIs><LinearRing><coordinates>5,52,0 5.002,52,0 5.002,52.001,0 5,52.001,0 5,52,0</coordinates>'
       b'</LinearRing></outerBoundaryIs><innerBoundaryIs><LinearRing><coordinates>5.0005,52.0002 5.001,52.0002 '
       b'5.001,52.0006 5.0005,52.0002</coordinates></LinearRing></innerBoundaryIs></Polygon></Placemark></Document></kml>')
FIELD_FILES = [DATA / "fields2cover_data" / "test.json", DATA / "fields2cover_data" / "test_2_cell.json",
               DATA / "fields2cover_data" / "Envelope.xml", "square.kml"]
START_MB: list[float] = []     # the peak when this file's first test starts (other files may run before it)


@pytest.fixture(autouse=True, scope="module")
def _peak_at_start():
    START_MB.append(_peak_mb())


@pytest.mark.slow
@SETTINGS
@given(kind=st.sampled_from(["nmea", "nmea_generated"]), edits=_mutations())
def test_a_mutated_nmea_capture_is_read_or_refused_by_name(kind, edits):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "gps.nmea"
        path.write_bytes(mutate(BASES[kind], edits))
        _import(path)


@pytest.mark.slow
@SETTINGS
@given(edits=_mutations())
def test_a_mutated_candump_is_read_or_refused_by_name(edits):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bus.log"
        path.write_bytes(mutate(BASES["can"], edits))
        _import(path)


@SETTINGS
@given(edits=_mutations(), header=st.booleans())
def test_a_mutated_time_log_is_read_or_refused_by_name(edits, header):
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "task"
        folder.mkdir()
        (folder / "TLG00001.bin").write_bytes(BASES["tlg_bin"] if header else mutate(BASES["tlg_bin"], edits))
        (folder / "TLG00001.xml").write_bytes(mutate(BASES["tlg_xml"], edits) if header else BASES["tlg_xml"])
        _import(folder)


@SETTINGS
@given(index=st.integers(0, len(FIELD_FILES) - 1), edits=_mutations())
def test_a_mutated_field_file_is_read_or_refused_by_name(index, edits):
    with tempfile.TemporaryDirectory() as tmp:
        source = FIELD_FILES[index]
        path = Path(tmp) / (source.name if isinstance(source, Path) else source)
        path.write_bytes(mutate(source.read_bytes() if isinstance(source, Path) else KML, edits))
        _fields(path)


@settings(SETTINGS, max_examples=500)
@given(data=st.binary(max_size=3000), suffix=st.sampled_from([".nmea", ".log", ".geojson", ".xml", ".kml", ".kmz",
                                                               ".csv", ".wkt", "TLG.bin"]))
def test_random_bytes_under_any_name_are_refused_by_name(data, suffix):
    with tempfile.TemporaryDirectory() as tmp:
        if suffix == "TLG.bin":
            folder = Path(tmp) / "task"
            folder.mkdir()
            (folder / "TLG00001.bin").write_bytes(data)
            (folder / "TLG00001.xml").write_bytes(BASES["tlg_xml"])
            _import(folder)
            return
        path = Path(tmp) / f"file{suffix}"
        path.write_bytes(data)
        if suffix in (".nmea", ".log"):
            _import(path)
        else:
            _fields(path)


TABLES = None


def _tables() -> dict[str, bytes]:
    """The generated recording of tests/import_recordings.py (one channel group 0.85 s late)."""
    global TABLES
    if TABLES is None:
        from tests.import_recordings import write_recording

        with tempfile.TemporaryDirectory() as tmp:
            rec = write_recording(Path(tmp) / "rec", seconds=25.0, late=0.85)
            TABLES = {p.name: p.read_bytes() for p in rec.iterdir()}
    return TABLES


@settings(SETTINGS, max_examples=12)
@given(name=st.sampled_from(["gnss.csv", "imu.csv", "bywire.csv"]), edits=_mutations(),
       align=st.sampled_from(["auto", "none", "bywire=0.85", "imu=-0.3"]), max_gap=st.sampled_from([0.0, 0.5, 5.0]))
def test_a_mutated_table_recording_is_audited_or_refused_by_name(name, edits, align, max_gap):
    """The audit and the alignment on a recording with one file damaged."""
    from agrobot.measurements.recording import ImportOptions
    from agrobot.measurements.signal_expressions import parse_signal
    from tests.import_recordings import SIGNALS

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "rec"
        folder.mkdir()
        for file, data in _tables().items():
            (folder / file).write_bytes(mutate(data, edits) if file == name else data)
        _import(folder, ImportOptions(signals=[parse_signal(s) for s in SIGNALS], wheelbase=0.32, align=align,
                                      max_gap=max_gap))


@settings(SETTINGS, max_examples=60)
@given(n=st.lists(st.integers(0, 400), min_size=1, max_size=4), seed=st.integers(0, 2 ** 16),
       constant=st.booleans(), repeat=st.booleans(), scale=st.sampled_from([1e-9, 1.0, 1e6]))
def test_the_audit_of_arbitrary_streams_is_well_formed(n, seed, constant, repeat, scale):
    """Channels of any length (0 to 400 samples), repeated stamps, constant or huge values: the
    audit gives well-formed findings or a LogError, nothing else."""
    from agrobot.measurements import LogError
    from agrobot.measurements.audit import audit_streams
    from agrobot.measurements.recording import ImportOptions
    from agrobot.measurements.streams import Streams

    rng = np.random.default_rng(seed)
    names = ["delta_cmd", "v", "yaw_rate", "ay"]
    signals = {}
    for name, k in zip(names, n):
        t = np.sort(rng.uniform(0, 60, k))
        if repeat and k > 2:
            t[1] = t[0]
        x = np.full(k, 1.0) if constant else scale * rng.standard_normal(k)
        signals[name] = (t, x)
    streams = Streams(None, signals, {}, {"delta_cmd"} & set(signals), {}, groups={c: c for c in signals})
    try:
        audit = audit_streams(streams, ImportOptions(wheelbase=1.4), "fuzz")
    except LogError as exc:
        assert str(exc)
        return
    _well_formed(audit["findings"])


def test_the_fuzzing_stayed_within_its_memory_bound():
    """Last in the file: every example above ran in this process; its peak grew this little."""
    assert _peak_mb() - START_MB[0] < GROWTH_MB
