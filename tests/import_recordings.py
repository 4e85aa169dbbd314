"""Generated recordings with one quirk each and a known truth, for the import audit's tests.

The truth: a kinematic car (wheelbase L = 0.32 m, the F1TENTH study's) driven at 2 +- 0.5 m/s
with a smooth random steering command; the wheels follow the command ``DELAY`` s late; the yaw
rate is r = v tan(delta) / L, the lateral acceleration v r, the track its integral. The channels
are written as a logger writes them, one CSV per device on its own stamps: ``gnss.csv`` (t, lat,
lon at 10 Hz), ``imu.csv`` (t, wz [rad/s], ay [m/s2] at 50 Hz), ``bywire.csv`` (t, steer [rad]
command, speed [m/s] at 30 Hz).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

L = 0.32
DELAY = 0.15
SIGNALS = ("delta_cmd=bywire.steer[rad]", "v=bywire.speed[m/s]", "yaw_rate=imu.wz[rad/s]", "ay=imu.ay[m/s2]",
           "lat=gnss.lat", "lon=gnss.lon")


def truth(seconds: float = 120.0, seed: int = 1, h: float = 0.002) -> pd.DataFrame:
    """The drive on a fine grid: t, delta_cmd, delta, v, r, ay, lat, lon."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, h)
    knots = np.arange(0.0, seconds + 2.0, 1.2)
    from scipy.interpolate import CubicSpline

    cmd = np.clip(CubicSpline(knots, rng.uniform(-0.25, 0.25, len(knots)))(t), -0.3, 0.3)
    delta = np.interp(t - DELAY, t, cmd, left=cmd[0])
    v = 2.0 + 0.5 * np.sin(2 * math.pi * t / 37.0) + 0.2 * np.sin(2 * math.pi * t / 9.0)
    r = v * np.tan(delta) / L
    psi = np.cumsum(r) * h
    east, north = np.cumsum(v * np.cos(psi)) * h, np.cumsum(v * np.sin(psi)) * h
    lat = 52.0 + np.degrees(north / 6_371_000.0)
    lon = 5.0 + np.degrees(east / (6_371_000.0 * math.cos(math.radians(52.0))))
    return pd.DataFrame({"t": t, "delta_cmd": cmd, "delta": delta, "v": v, "r": r, "ay": v * r, "lat": lat, "lon": lon})


def _sample(drive: pd.DataFrame, rate: float, columns: dict, late: float = 0.0, start: float = 1.7e9,
            noise: dict | None = None, seed: int = 2, drop=None, blank: tuple = ()) -> pd.DataFrame:
    """The drive's columns sampled at ``rate`` Hz, stamped ``late`` s late, with noise; ``drop(t)``
    the rows left out, or only the ``blank`` columns left empty there."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.5, drive["t"].iloc[-1] - 0.5, 1.0 / rate)
    out = {"t": start + t + late}
    for name, source in columns.items():
        x = np.interp(t, drive["t"], drive[source])
        out[name] = x + (noise or {}).get(name, 0.0) * rng.standard_normal(len(t))
    frame = pd.DataFrame(out)
    frame["t"] = frame["t"].map(lambda x: f"{x:.4f}")      # POSIX seconds to 0.1 ms, as a logger writes them
    if drop is not None and blank:
        frame.loc[drop(t), list(blank)] = np.nan
    elif drop is not None:
        frame = frame.loc[~drop(t)].reset_index(drop=True)
    return frame


def write_recording(folder: Path, seconds: float = 120.0, late: float = 0.0, drops: list | None = None,
                    second_imu: tuple[float, float] | None = None, swap: bool = False, seed: int = 1) -> Path:
    """The recording's three (or four) CSVs: ``late`` s on the by-wire kit's stamps; ``drops``
    [(start, end)] of the steering report's silences (the speed beside it goes on); ``second_imu`` (scale, late) a second gyro
    ``imu2.csv``; ``swap`` the IMU's wz and ay columns exchanged."""
    folder.mkdir(parents=True, exist_ok=True)
    drive = truth(seconds, seed)
    gnss = _sample(drive, 10.0, {"lat": "lat", "lon": "lon"})
    gnss["lat"], gnss["lon"] = gnss["lat"].round(9), gnss["lon"].round(9)
    imu = _sample(drive, 50.0, {"wz": "r", "ay": "ay"}, noise={"wz": 0.01, "ay": 0.05})
    if swap:
        imu = imu.rename(columns={"wz": "ay", "ay": "wz"})[["t", "wz", "ay"]]
    silent = None
    if drops:
        silent = lambda t: np.any([(t >= a) & (t < b) for a, b in drops], axis=0)  # noqa: E731
    bywire = _sample(drive, 30.0, {"steer": "delta_cmd", "speed": "v"}, late=late, noise={"speed": 0.02}, drop=silent,
                     blank=("steer",))
    gnss.to_csv(folder / "gnss.csv", index=False, float_format="%.10g")
    imu.to_csv(folder / "imu.csv", index=False, float_format="%.6g")
    bywire.to_csv(folder / "bywire.csv", index=False, float_format="%.6g")
    if second_imu is not None:
        scale, lag = second_imu
        imu2 = _sample(drive, 40.0, {"wz": "r"}, late=lag, noise={"wz": 0.01}, seed=3)
        imu2["wz"] *= scale
        imu2.to_csv(folder / "imu2.csv", index=False, float_format="%.6g")
    return folder


TLG_HEADER = ('<?xml version="1.0" encoding="UTF-8"?>\n<TIM A="" D="4">\n<PTN A="" B="" D="" H="" I=""/>\n'
              '<DLV A="018D" B="" C="DET-1"/>\n<DLV A="0090" B="" C="DET-1"/>\n</TIM>\n')


def write_ddi_timelog(folder: Path, seconds: int = 120, speed_mm_s: int = 2500, yaw_mdeg: int = 45000,
                      clock_ahead: float = 2040.0) -> Path:
    """A 1 Hz ISO 11783-10 time log heading north at ``speed_mm_s`` (DDI 397, Actual Speed, mm/s)
    with a yaw angle (DDI 144, 0.001 deg) and the GNSS time in every record (PTN H, I), the
    terminal's clock (TIM) ``clock_ahead`` s ahead of it."""
    import datetime
    import struct

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "TLG00001.xml").write_text(TLG_HEADER)
    epoch = datetime.datetime(1980, 1, 1, tzinfo=datetime.timezone.utc)
    start = datetime.datetime(2026, 5, 1, 8, 0, tzinfo=datetime.timezone.utc)
    out = bytearray()
    for k in range(seconds):
        gps = start + datetime.timedelta(seconds=k)
        tim = gps + datetime.timedelta(seconds=clock_ahead)
        lat = 52.0 + math.degrees(k * speed_mm_s / 1000.0 / 6_371_000.0)
        for when, fmt in ((tim, "<IH"),):
            since = when - epoch
            out += struct.pack(fmt, int(round((since.total_seconds() % 86400) * 1000)), since.days)
        g = gps - epoch
        out += struct.pack("<iiB", round(lat * 1e7), round(5.0 * 1e7), 4)
        out += struct.pack("<IH", int(round((g.total_seconds() % 86400) * 1000)), g.days)
        out += struct.pack("<B", 2) + struct.pack("<Bi", 0, speed_mm_s) + struct.pack("<Bi", 1, yaw_mdeg)
    (folder / "TLG00001.bin").write_bytes(bytes(out))
    return folder


def _ring(lat0: float, lon0: float, north_m: float, east_m: float, kind: int = 1) -> str:
    """An LSG ring (type ``kind``: 1 exterior, 2 interior) of a rectangle from (lat0, lon0)."""
    dlat = math.degrees(north_m / 6_371_000.0)
    dlon = math.degrees(east_m / (6_371_000.0 * math.cos(math.radians(lat0))))
    corners = [(lat0, lon0), (lat0, lon0 + dlon), (lat0 + dlat, lon0 + dlon), (lat0 + dlat, lon0)]
    return f'<LSG A="{kind}">' + "".join(f'<PNT A="2" C="{a:.9f}" D="{b:.9f}"/>' for a, b in corners) + "</LSG>"


def write_xfr_taskdata(folder: Path, version: int = 4) -> Path:
    """An ISO 11783-10 TaskData whose partfield lives in an external file (XFR -> PFD00001.XML,
    root XFC): a 200 x 100 m boundary with a 20 x 10 m hole written as a boundary polygon of its
    own, 50 m north and 50 m east of the corner; in version 4 also an empty guidance pattern
    and an AB line. The truth: 2.0 ha less 0.02 ha, one hole, one line."""
    folder.mkdir(parents=True, exist_ok=True)
    lat0, lon0 = 52.0, 5.0
    dlat = math.degrees(50.0 / 6_371_000.0)
    dlon = math.degrees(50.0 / (6_371_000.0 * math.cos(math.radians(lat0))))
    guidance = ""
    if version >= 4:
        guidance = ('<GGP A="GGP1" B="lines"><GPN A="GPN1" B="empty" C="1"><LSG A="5"/></GPN>'
                    f'<GPN A="GPN2" B="AB" C="1"><LSG A="5"><PNT A="6" C="{lat0 + dlat / 5:.9f}" D="{lon0 + dlon / 5:.9f}"/>'
                    f'<PNT A="7" C="{lat0 + dlat / 5:.9f}" D="{lon0 + 3 * dlon:.9f}"/></LSG></GPN></GGP>')
    (folder / "PFD00001.XML").write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n<XFC>\n<PFD A="PFD1" C="north field" D="19800">'
        f'<PLN A="1">{_ring(lat0, lon0, 100.0, 200.0)}</PLN>'
        f'<PLN A="1">{_ring(lat0 + dlat, lon0 + dlon, 10.0, 20.0)}</PLN>{guidance}</PFD>\n</XFC>\n')
    (folder / "TASKDATA.XML").write_text(
        f'<?xml version="1.0" encoding="UTF-8"?>\n<ISO11783_TaskData VersionMajor="{version}" VersionMinor="0" '
        'ManagementSoftwareManufacturer="test" ManagementSoftwareVersion="1" DataTransferOrigin="1">\n'
        '<XFR A="PFD00001" B="1"/>\n</ISO11783_TaskData>\n')
    return folder
