"""A receiver's NMEA, both ways: the emulator writes GGA, VTG, RMC (date from a configurable
epoch), GST (the GPS error model's sigma) and ZDA with a configurable talker and sentence set;
the input side reads GN/GP/GL talkers, RMC, GST and HDT and counts the rest as unused without
calling it malformed. Carried over a real serial line (pyserial on pseudo-terminals) and read by
gpsd as a real client where gpsd is installed."""
from __future__ import annotations

import datetime
import json
import math
import os
import shutil
import socket
import subprocess
import threading
import time

import pytest

from agrobot.components.hardware.nmea import NMEAStream, Position, PositionError, Velocity, parse_epoch, receiver_sentences

LAT, LON = math.radians(51.98), math.radians(5.66)


def _sentence(talker: str, ident: str, **fields) -> bytes:
    from pynmeagps import GET, NMEAMessage

    return NMEAMessage(talker, ident, GET, **fields).serialize()


def test_every_sentence_round_trips_with_time_date_errors_and_talker():
    from pynmeagps import NMEAReader

    when = parse_epoch("2026-05-01T23:59:58Z") + datetime.timedelta(seconds=3.25)    # past midnight
    data = receiver_sentences(when, LAT, LON, 12.0, 1.2, -0.5, talker="GP", position_std=0.03)
    lines = data.split(b"\r\n")[:-1]
    assert [line[:6] for line in lines] == [b"$GPGGA", b"$GPGST", b"$PGRME", b"$GPVTG", b"$GPRMC", b"$GPZDA"]
    gst, rmc, zda = (NMEAReader.parse(lines[i]) for i in (1, 4, 5))
    hpe = float(lines[2].split(b",")[1])
    assert hpe == pytest.approx(1.1774 * 0.03, abs=1e-4)          # CEP50 of 3 cm per axis
    assert rmc.date == datetime.date(2026, 5, 2) and rmc.time == datetime.time(0, 0, 1, 250000)
    assert rmc.status == "A" and rmc.posMode == "R"
    assert (zda.day, zda.month, zda.year) == (2, 5, 2026)
    assert gst.stdLat == pytest.approx(0.03) and gst.stdLong == pytest.approx(0.03)
    items = NMEAStream().feed(data)
    pos = next(i for i in items if isinstance(i, Position))
    assert pos.latitude == pytest.approx(LAT, abs=1e-10) and pos.quality == 4
    vel = [i for i in items if isinstance(i, Velocity)]
    assert len(vel) == 2 and all(v.speed == pytest.approx(math.hypot(1.2, 0.5), abs=1e-3) for v in vel)
    assert next(i for i in items if isinstance(i, PositionError)).std_north == pytest.approx(0.03)


def test_the_input_side_reads_common_receivers_and_ignores_the_rest_quietly():
    from agrobot.components.nmea_gps import NMEAGPS

    stream = NMEAStream()
    data = (receiver_sentences(parse_epoch("2026-05-01T08:00:00Z"), LAT, LON, 0.0, 1.0, 0.0, talker="GL",
                               sentences=("GGA", "RMC", "GST"))
            + _sentence("GN", "HDT", headingT=90.0, headingTu="T")
            + _sentence("GP", "GSV", numMsg=1, msgNum=1, numSV=1, svid_01=5, elv_01=40, az_01=100, cno_01=40)
            + _sentence("GN", "GSA", opMode="A", navMode=3, PDOP=1.2, HDOP=0.7, VDOP=0.9)
            + receiver_sentences(parse_epoch("2026-05-01T08:00:00Z"), LAT, LON, 0.0, 1.0, 0.0, sentences=("ZDA",)))
    gps = NMEAGPS("gps", {"datum_latitude": LAT, "datum_longitude": LON})
    gps.stream = stream
    gps.frame = __import__("agrobot.components.hardware.nmea", fromlist=["LocalFrame"]).LocalFrame(LAT, LON, 0.0)
    gps.last_good = 0.0
    gps.apply(0.1, stream.feed(data))
    c = stream.counters
    assert (c.bad_checksum, c.malformed, c.partial) == (0, 0, 0) and c.unknown == 3         # GSV, GSA, ZDA
    y = gps.y
    assert y["fix_valid"] == 1.0 and abs(y["x"]) < 1e-6 and abs(y["y"]) < 1e-6
    assert y["position_std"] == pytest.approx(0.02)
    assert y["heading_valid"] == 1.0 and y["heading"] == pytest.approx(0.0, abs=1e-12)        # east
    assert y["vel_east"] == pytest.approx(1.0, abs=1e-3)
    # a receiver without a fix: quality 0, RMC status V: a poor fix, nothing malformed
    gps.apply(0.2, stream.feed(receiver_sentences(parse_epoch("2026-05-01T08:00:00Z"), None, None, 0, 0, 0, 0)))
    assert y["fix_valid"] == 0.0 and c.poor_fix == 1 and c.malformed == 0


def test_bad_server_settings_are_named():
    from agrobot.orchestrator.component import ComponentError

    from agrobot.components.nmea_server import NMEAServer

    for params, words in (({"talker": "XX"}, "talker 'XX'"), ({"sentences": "GGA,FOO"}, "sentences 'GGA,FOO'"),
                          ({"epoch": "yesterday"}, "epoch 'yesterday'"),
                          ({"serial_port": "/dev/does-not-exist"}, "cannot open serial port '/dev/does-not-exist'")):
        server = NMEAServer("nmea", {"port": 0, **params})
        with pytest.raises(ComponentError, match=words):
            server.initialize(0.0, 0.1)
        server.terminate()


def _pty_pair():
    """(master fd, slave device path) of a raw pseudo-terminal."""
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    return master, os.ttyname(slave), slave


def test_nmea_goes_out_and_comes_in_over_a_serial_line():
    """The server writes on a pty's serial device; what arrives on the other end is written into a
    second pty, whose device the receiver component reads with pyserial."""
    from agrobot.components.nmea_gps import NMEAGPS
    from agrobot.components.nmea_server import NMEAServer

    out_master, out_device, out_slave = _pty_pair()
    in_master, in_device, in_slave = _pty_pair()
    server = NMEAServer("nmea", {"port": 0, "serial_port": out_device, "datum_latitude": LAT, "datum_longitude": LON,
                                 "talker": "GP", "sentences": "GGA,RMC,GST"})
    gps = NMEAGPS("gps", {"url": in_device, "datum_latitude": LAT, "datum_longitude": LON})
    server.initialize(0.0, 0.1)
    gps.initialize(0.0, 0.1)
    try:
        got = b""
        for k in range(5):
            server.u.update(x=3.0 + k, y=4.0, vel_east=1.0, vel_north=0.0, fix_valid=1.0)
            server.step(0.1 * k, 0.1)
        deadline = time.monotonic() + 5
        while got.count(b"\n") < 15 and time.monotonic() < deadline:
            got += os.read(out_master, 4096)
        assert got.count(b"$GPGGA") == 5 and got.count(b"$GPRMC") == 5 and got.count(b"$GPGST") == 5
        os.write(in_master, got)
        time.sleep(0.2)
        gps.step(0.5, 0.1)
        assert gps.y["fix_valid"] == 1.0
        assert gps.y["x"] == pytest.approx(7.0, abs=1e-3) and gps.y["y"] == pytest.approx(4.0, abs=1e-3)
        assert gps.y["position_std"] == pytest.approx(0.02)
    finally:
        server.terminate()
        gps.terminate()
        for fd in (out_master, out_slave, in_master, in_slave):
            os.close(fd)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.skipif(shutil.which("gpsd") is None, reason="gpsd is not installed (CI installs it as root; "
                    "locally: apt-get install gpsd)")
def test_gpsd_reads_the_emulated_receiver_with_time_speed_course_and_error():
    from agrobot.components.nmea_server import NMEAServer

    nmea_port, gpsd_port = _free_port(), _free_port()
    server = NMEAServer("nmea", {"port": nmea_port, "datum_latitude": LAT, "datum_longitude": LON,
                                 "epoch": "2026-05-01T08:00:00Z", "position_std": 0.02})
    server.initialize(0.0, 0.1)
    gpsd = subprocess.Popen(["gpsd", "-N", "-n", "-G", "-S", str(gpsd_port), f"tcp://127.0.0.1:{nmea_port}"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    tpv: list[dict] = []
    stop = threading.Event()

    def client():
        deadline = time.monotonic() + 10
        while not stop.is_set() and time.monotonic() < deadline:
            try:
                sock = socket.create_connection(("127.0.0.1", gpsd_port), timeout=1)
                break
            except OSError:
                time.sleep(0.1)
        else:
            return
        sock.sendall(b'?WATCH={"enable":true,"json":true}\n')
        buf = b""
        sock.settimeout(0.5)
        while not stop.is_set():
            try:
                buf += sock.recv(65536)
            except OSError:
                continue
            *lines, buf = buf.split(b"\n")
            tpv.extend(m for m in (json.loads(line) for line in lines if line.strip()) if m.get("class") in ("TPV", "GST"))
        sock.close()

    reader = threading.Thread(target=client, daemon=True)
    reader.start()
    try:
        k = 0
        t_end = time.monotonic() + 12
        while time.monotonic() < t_end and len([m for m in tpv if "speed" in m]) < 5:
            t = 0.2 * k
            # north-east at 2 m/s: course 45 deg
            server.u.update(x=1.414 * t, y=1.414 * t, vel_east=1.414, vel_north=1.414, fix_valid=1.0)
            server.step(t, 0.2)
            k += 1
            time.sleep(0.2)
    finally:
        stop.set()
        reader.join(timeout=3)
        server.terminate()
        gpsd.terminate()
        gpsd.wait(timeout=5)
    good = [m for m in tpv if "speed" in m and "time" in m]
    assert good, f"gpsd reported no TPV with speed and time: {tpv[:3]}"
    last = good[-1]
    assert last["time"].startswith("2026-05-01T08:")
    assert last["speed"] == pytest.approx(2.0, abs=0.01) and last["track"] == pytest.approx(45.0, abs=0.5)
    assert last.get("mode") == 3 or last.get("mode") == 2
    # 2 cm per axis, as gpsd states it (95 %, from PGRME): epx, epy a few centimetres. gpsd 3.22 keeps
    # eph from HDOP x its UERE (metres) whatever the receiver says; GST it reports as its own class.
    with_error = [m for m in good if "epx" in m and "epy" in m]
    assert len(with_error) >= 3, good[-3:]
    assert all(0.02 <= m["epx"] <= 0.1 and 0.02 <= m["epy"] <= 0.1 for m in with_error), with_error[-1]
    print(f"gpsd TPV: speed {last['speed']} m/s, track {last['track']} deg, epx {with_error[-1]['epx']} m, "
          f"epy {with_error[-1]['epy']} m, eph {last.get('eph')} m")
    gst = [m for m in tpv if m["class"] == "GST"]
    assert gst and gst[-1]["lat"] == pytest.approx(0.02) and gst[-1]["lon"] == pytest.approx(0.02)
