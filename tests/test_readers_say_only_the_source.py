"""Nothing written that the source did not say: for each reader, a generated recording of random
values (hypothesis picks the seeds), converted; at every one of the source's own times the log
holds the source's value after unit conversion (fix quality, every channel), and where the source
is silent (a quality not given, a heading that stops) it holds NaN or no column, never a value
made up. Spikes are kept and clocks left as stamped (--keep-spikes, --align none): what is
tested is the reader and the grid, not the quirk finders."""
from __future__ import annotations

import datetime
import math
import struct

import numpy as np
import pandas as pd
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording
from harness.generated_recordings import EPOCH_1980, TLG_HEADER, _dm, sentence, track

START = datetime.datetime(2026, 5, 1, 8, 0, tzinfo=datetime.timezone.utc)
KNOTS = 1852.0 / 3600.0
SEEDS = given(seed=st.integers(0, 2**31 - 1))
FEW = settings(max_examples=3, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate))
OPTIONS = ImportOptions(keep_spikes=True, align="none")


def codes(rng, n: int, choices=(1, 2, 4, 5)) -> np.ndarray:
    """A receiver's fix quality: stretches of random length of random codes."""
    out, k = np.empty(n), 0
    while k < n:
        m = int(rng.integers(5, 60))
        out[k:k + m] = rng.choice(choices)
        k += m
    return out


def smooth(rng, t: np.ndarray, scale: float) -> np.ndarray:
    """A random smooth signal: three sines of random amplitude, frequency and phase."""
    a, f, p = rng.uniform(0.2, 1.0, 3), rng.uniform(0.02, 0.3, 3), rng.uniform(0, 2 * math.pi, 3)
    return scale * sum(a[i] * np.sin(2 * math.pi * f[i] * t + p[i]) for i in range(3)) / 3


def at_source(frame, report, column: str, t_src: np.ndarray, x_src: np.ndarray, atol: float) -> int:
    """Every log row at a source time holds the source's value (NaN where the source's is NaN);
    the number of rows compared."""
    t_abs = report["used"]["utc_start_s"] + frame["t"].to_numpy(float)
    j = np.clip(np.searchsorted(t_src, t_abs), 1, len(t_src) - 1)
    j = np.where(np.abs(t_src[j - 1] - t_abs) < np.abs(t_src[j] - t_abs), j - 1, j)
    same = np.abs(t_src[j] - t_abs) < 1e-3
    got, want = frame[column].to_numpy(float)[same], x_src[j[same]]
    assert np.array_equal(np.isnan(got), np.isnan(want)), f"{column}: NaN where the source says a value, or not"
    ok = np.isfinite(want)
    assert np.allclose(got[ok], want[ok], atol=atol, rtol=0), \
        f"{column}: {np.max(np.abs(got[ok] - want[ok])):.3g} from the source"
    return int(same.sum())


# --- NMEA ----------------------------------------------------------------------------------------------
@SEEDS
@FEW
def test_nmea_quality_speed_and_heading_are_the_receivers(tmp_path_factory, seed):
    rng = np.random.default_rng(seed)
    n = 600
    t = np.arange(n) / 10.0
    quality, knots = codes(rng, n), np.round((1.5 + smooth(rng, t, 1.0)) / KNOTS, 3)
    hdt = np.round(np.degrees(smooth(rng, t, 2.0)) % 360.0, 2)
    silent = (t >= 20.0) & (t < 26.0)                            # the heading stops for 6 s
    lines = []
    for k in range(n):
        utc = START + datetime.timedelta(seconds=float(t[k]))
        hms = utc.strftime("%H%M%S.") + f"{utc.microsecond // 10000:02d}"
        lat, lon = track(float(t[k]))
        pos = f"{_dm(lat, 2)},N,{_dm(lon, 3)},E"
        lines.append(sentence(f"GPGGA,{hms},{pos},{int(quality[k])},12,0.8,10.0,M,47.0,M,,"))
        lines.append(sentence(f"GPRMC,{hms},A,{pos},{knots[k]:.3f},90.0,{utc.strftime('%d%m%y')},,,A"))
        if not silent[k]:
            lines.append(sentence(f"GPHDT,{hdt[k]:.2f},T"))
    path = tmp_path_factory.mktemp("nmea") / "drive.nmea"
    path.write_text("\n".join(lines) + "\n")
    frame, report = import_recording(path, OPTIONS)
    utc = START.timestamp() + t
    assert at_source(frame, report, "fix_quality", utc, quality, 0.0) > 500
    at_source(frame, report, "gnss_speed", utc, knots * KNOTS, 1e-9)
    heading = np.where(silent, np.nan, np.angle(np.exp(1j * (math.pi / 2 - np.radians(hdt)))))
    keep = ~silent | ((t > 20.05) & (t < 25.95))                 # at the silence's edges the receiver's last word
    assert at_source(frame, report, "heading", utc[keep], heading[keep], 1e-9) > 500


# --- tables ---------------------------------------------------------------------------------------------
@SEEDS
@FEW
def test_a_tables_columns_and_fix_quality_are_its_own(tmp_path_factory, seed):
    rng = np.random.default_rng(seed)
    t = 1.7e9 + np.arange(400) / 10.0
    lat, lon = zip(*(track(float(x - t[0])) for x in t))
    table = pd.DataFrame({"t": t, "lat": lat, "lon": lon, "fix_quality": codes(rng, len(t)),
                          "v [km/h]": np.round(7 + smooth(rng, t, 3.0), 6), "delta [deg]": np.round(smooth(rng, t, 20), 6)})
    folder = tmp_path_factory.mktemp("table")
    table.to_csv(folder / "drive.csv", index=False)
    frame, report = import_recording(folder / "drive.csv", OPTIONS)
    assert at_source(frame, report, "fix_quality", t, table["fix_quality"].to_numpy(), 0.0) > 390
    at_source(frame, report, "v", t, table["v [km/h]"].to_numpy() / 3.6, 1e-9)
    at_source(frame, report, "delta", t, np.radians(table["delta [deg]"].to_numpy()), 1e-9)
    table.drop(columns="fix_quality").to_csv(folder / "silent.csv", index=False)
    frame, report = import_recording(folder / "silent.csv", OPTIONS)
    assert "fix_quality" not in frame or frame["fix_quality"].isna().all()       # not given: none made up
    assert any("does not give the receiver's fix quality" in n for n in report["notes"])


# --- CAN ------------------------------------------------------------------------------------------------
@SEEDS
@FEW
def test_can_signals_are_the_frames_values_at_the_frames_times(tmp_path_factory, seed):
    rng = np.random.default_rng(seed)
    t = np.arange(1200) / 20.0
    angle = np.round(smooth(rng, t, 0.5) / 1e-4).astype(int)
    yaw = np.round(smooth(rng, t, 0.4) / 1e-4).astype(int)
    speed = np.round((2.0 + smooth(rng, t, 1.0)) / 1e-3).astype(int)
    start = 1_777_622_400.0
    lines = [f"({start + t[k]:.6f}) can0 280#"
             + (struct.pack("<hhH", angle[k], yaw[k], speed[k]) + bytes([(k % 16) << 4, 0])).hex().upper()
             for k in range(len(t))]
    path = tmp_path_factory.mktemp("can") / "drive.log"
    path.write_text("\n".join(lines) + "\n")
    frame, report = import_recording(path, OPTIONS)
    assert at_source(frame, report, "delta", start + t, angle * 1e-4, 1e-9) > 1100
    at_source(frame, report, "yaw_rate", start + t, yaw * 1e-4, 1e-9)
    at_source(frame, report, "v", start + t, speed * 1e-3, 1e-9)
    assert "fix_quality" not in frame


# --- ISO 11783-10 time log ------------------------------------------------------------------------------
@SEEDS
@FEW
def test_a_time_logs_position_status_is_its_fix_quality_and_15_is_unknown(tmp_path_factory, seed):
    rng = np.random.default_rng(seed)
    n = 300
    status = codes(rng, n, (1, 2, 4, 5, 15))
    folder = tmp_path_factory.mktemp("tlg")
    (folder / "TLG00001.xml").write_text(TLG_HEADER)
    out = bytearray()
    for k in range(n):
        utc = START + datetime.timedelta(seconds=k)
        since = utc - EPOCH_1980
        lat, lon = track(float(k))
        out += (struct.pack("<IH", int(round((since.total_seconds() % 86400) * 1000)), since.days)
                + struct.pack("<iiB", round(lat * 1e7), round(lon * 1e7), int(status[k]))
                + struct.pack("<BBi", 1, 0, 2000))
    (folder / "TLG00001.bin").write_bytes(bytes(out))
    frame, report = import_recording(folder, OPTIONS)
    truth = np.where(status == 15, np.nan, status)
    assert at_source(frame, report, "fix_quality", START.timestamp() + np.arange(n), truth, 0.0) > 250


# --- ROS bags -------------------------------------------------------------------------------------------
@SEEDS
@FEW
def test_a_bags_navsat_status_and_gyro_are_the_messages(tmp_path_factory, seed):
    from tests.test_other_data import write_bag

    rng = np.random.default_rng(seed)
    t = START.timestamp() + np.arange(300) / 5.0
    lat, lon = zip(*(track(float(x - t[0])) for x in t))
    epochs = pd.DataFrame({"utc": t, "lat": lat, "lon": lon, "height": 10.0, "quality": codes(rng, len(t), (1, 2, 4))})
    path = write_bag(tmp_path_factory.mktemp("bag") / "drive", "ros2", epochs)
    frame, report = import_recording(path, OPTIONS)
    assert at_source(frame, report, "fix_quality", t, epochs["quality"].to_numpy(float), 0.0) > 250
    at_source(frame, report, "yaw_rate", t, 0.2 * np.sin(0.1 * (t - t[0])), 1e-9)    # the bag writer's gyro
