"""The two message sets guidance and tractor speak on CAN, behind one interface.

- ``agrobot``: the project's two frames (agrobot_tractor.dbc): GuidanceCommand (wheel angle, speed,
  safe state, counter) and TractorFeedback (wheel angle, yaw rate, speed, counter), 11-bit ids.
- ``isobus``: ISO 11783-7 guidance (isobus_guidance.dbc), J1939 29-bit ids: Guidance System
  Command (PGN 44288: curvature, 'intended to steer' status) and Machine Selected Speed Command
  (PGN 64835) from the guidance; Guidance Machine Info (PGN 44032: estimated curvature,
  mechanical lockout, steering readiness), Wheel-based Speed (PGN 65096) and the project's yaw
  rate (PGN 65312) from the tractor. Curvature and wheel angle through the wheelbase,
  kappa = tan(delta) / L, with ISO's sign (positive to the driver's right); frames are matched by
  PGN and taken only from the peer's source address (``peer_address``: the DBC's sender by default,
  -2 any), sent with the DBC's addresses or ``source_address``; reserved bits 1. ISO 11783-7
  defines no counter or checksum for these messages (AgIsoStack++ agrees), so none is added.

Both decode into the same dictionaries: a command {steer_angle_cmd, speed_cmd, engaged} and
feedback {steer_angle, yaw_rate, speed, ready, lockout} (the last two only from ISOBUS, 1/0).
A frame that does not decode is counted in ``bad``; one refused by a check (counter, checksum,
a value outside its DBC range, a foreign sender) in ``refused``.
"""
from __future__ import annotations

import math
from pathlib import Path

from .can_frames import DEFAULT_DBC, FrameCodec, load_dbc

ISOBUS_DBC = Path(__file__).resolve().parent / "isobus_guidance.dbc"
PROTOCOLS = ("agrobot", "isobus")
# SAE 2-bit states
ENABLED, NOT_AVAILABLE = 1, 3


def _pgn(frame_id: int) -> int:
    pf = (frame_id >> 16) & 0xFF
    return (frame_id >> 8) & (0x3FF00 if pf < 240 else 0x3FFFF)


class AgrobotMessages:
    """The project's frames (FrameCodec with the rolling counter)."""

    extended = False

    def __init__(self, db, side: str) -> None:
        names = ("GuidanceCommand", "TractorFeedback")
        send, receive = names if side == "guidance" else names[::-1]
        self.codec = FrameCodec(db, send, receive)

    @property
    def bad(self) -> int:
        return self.codec.bad

    @property
    def refused(self) -> int:
        return self.codec.bad_e2e + self.codec.out_of_range

    def command(self, steer_angle_cmd: float, speed_cmd: float, engaged: bool) -> list[tuple[int, bytes]]:
        return [self.codec.encode(SteerAngleCmd=steer_angle_cmd, SpeedCmd=max(0.0, speed_cmd), SafeState=int(not engaged))]

    def feedback(self, steer_angle: float, yaw_rate: float, speed: float, ready: bool = True,
                 lockout: bool = False, dt: float = 0.0) -> list[tuple[int, bytes]]:
        return [self.codec.encode(SteerAngle=steer_angle, YawRate=yaw_rate, Speed=max(0.0, speed))]

    def read_command(self, msg) -> dict | None:
        f = self.codec.decode(msg)
        return None if f is None else {"steer_angle_cmd": f["SteerAngleCmd"], "speed_cmd": f["SpeedCmd"],
                                       "engaged": not f["SafeState"]}

    def read_feedback(self, msg) -> dict | None:
        f = self.codec.decode(msg)
        return None if f is None else {"steer_angle": f["SteerAngle"], "yaw_rate": f["YawRate"], "speed": f["Speed"]}


class IsobusMessages:
    """ISO 11783-7 guidance (see the module docstring)."""

    extended = True

    def __init__(self, db, side: str, wheelbase: float, source_address: int = -1, peer_address: int = -1) -> None:
        self.db, self.wheelbase, self.bad, self.refused = db, float(wheelbase), 0, 0
        self.messages = {m.name: m for m in db.messages}
        self.by_pgn = {_pgn(m.frame_id): m for m in db.messages}
        mine = ("GuidanceSystemCommand", "MachineSelectedSpeedCommand") if side == "guidance" else \
            ("GuidanceMachineInfo", "WheelBasedSpeedAndDistance", "AgrobotYawRate")
        self.ids = {}
        for name in mine:
            fid = self.messages[name].frame_id
            self.ids[name] = fid if source_address < 0 else (fid & ~0xFF) | (int(source_address) & 0xFF)
        self.distance = 0.0                     # m, Wheel-based Machine Distance
        theirs = [m for m in db.messages if m.name not in mine]
        self.peers = None if peer_address == -2 else \
            {m.frame_id & 0xFF for m in theirs} if peer_address < 0 else {int(peer_address) & 0xFF}

    def _frame(self, name: str, values: dict) -> tuple[int, bytes]:
        msg = self.messages[name]
        data = bytearray(msg.encode(values, strict=False))
        used = 0
        for s in msg.signals:                     # reserved bits are sent as 1 (J1939)
            used |= ((1 << s.length) - 1) << s.start
        for i in range(len(data)):
            data[i] |= ~(used >> (8 * i)) & 0xFF
        return self.ids[name], bytes(data)

    def curvature(self, steer_angle: float) -> float:
        """ISO curvature (1/km, right positive) of a wheel angle (rad, left positive)."""
        return -1000.0 * math.tan(steer_angle) / self.wheelbase

    def steer_angle(self, curvature_per_km: float) -> float:
        return math.atan(-curvature_per_km * self.wheelbase / 1000.0)

    def command(self, steer_angle_cmd: float, speed_cmd: float, engaged: bool) -> list[tuple[int, bytes]]:
        kappa = min(max(self.curvature(steer_angle_cmd), -8032.0), 8031.75)
        return [self._frame("GuidanceSystemCommand", {"CurvatureCommand": kappa, "CurvatureCommandStatus": int(engaged)}),
                self._frame("MachineSelectedSpeedCommand", {"SpeedSetpointCommand": min(max(speed_cmd, 0.0), 64.255),
                                                            "SpeedSetpointLimit": 64.255, "DirectionCommand": 1})]

    def feedback(self, steer_angle: float, yaw_rate: float, speed: float, ready: bool = True,
                 lockout: bool = False, dt: float = 0.0) -> list[tuple[int, bytes]]:
        self.distance = (self.distance + max(speed, 0.0) * dt) % 4211081.0
        kappa = min(max(self.curvature(steer_angle), -8032.0), 8031.75)
        return [self._frame("GuidanceMachineInfo", {"EstimatedCurvature": kappa, "MechanicalSystemLockout": int(lockout),
                                                    "SteeringSystemReadiness": ENABLED if ready else 0,
                                                    "SteeringInputPositionStatus": NOT_AVAILABLE,
                                                    "RequestResetCommandStatus": 0, "GuidanceLimitStatus": 0,
                                                    "ExitReasonCode": 0 if ready and not lockout else 63,
                                                    "RemoteEngageSwitchStatus": NOT_AVAILABLE}),
                self._frame("WheelBasedSpeedAndDistance", {"WheelBasedMachineSpeed": min(max(speed, 0.0), 64.255),
                                                           "WheelBasedMachineDistance": self.distance,
                                                           "MaximumTimeOfTractorPower": 250, "MachineDirection": 1,
                                                           "KeySwitchState": 1}),
                self._frame("AgrobotYawRate", {"YawRate": min(max(yaw_rate, -3.0), 3.0)})]

    def _decode(self, msg, names: tuple[str, ...]):
        if msg is None or not msg.is_extended_id:
            return None, None
        m = self.by_pgn.get(_pgn(msg.arbitration_id))
        if m is None or m.name not in names:
            return None, None
        if self.peers is not None and msg.arbitration_id & 0xFF not in self.peers:
            self.refused += 1            # the right message from the wrong sender
            return None, None
        try:
            return m.name, m.decode(bytes(msg.data), decode_choices=False)
        except Exception:                # noqa: BLE001 - a bad frame is counted, never raised
            self.bad += 1
            return None, None

    def _refuse(self):
        self.refused += 1
        return None

    def read_command(self, msg) -> dict | None:
        name, f = self._decode(msg, ("GuidanceSystemCommand", "MachineSelectedSpeedCommand"))
        if name == "GuidanceSystemCommand":
            if f["CurvatureCommand"] > 8031.75:          # 'not available'
                return {"engaged": False}
            if int(f["CurvatureCommandStatus"]) > 1:     # 2 error, 3 not available: not intended to steer
                return {"engaged": False}
            return {"steer_angle_cmd": self.steer_angle(f["CurvatureCommand"]),
                    "engaged": int(f["CurvatureCommandStatus"]) == 1}
        if name == "MachineSelectedSpeedCommand":
            return {"speed_cmd": f["SpeedSetpointCommand"]} if f["SpeedSetpointCommand"] <= 64.255 else self._refuse()
        return None

    def read_feedback(self, msg) -> dict | None:
        name, f = self._decode(msg, ("GuidanceMachineInfo", "WheelBasedSpeedAndDistance", "AgrobotYawRate"))
        if name == "GuidanceMachineInfo":
            out = {"ready": float(int(f["SteeringSystemReadiness"]) == ENABLED),
                   "lockout": float(int(f["MechanicalSystemLockout"]) == 1)}
            if f["EstimatedCurvature"] <= 8031.75:
                out["steer_angle"] = self.steer_angle(f["EstimatedCurvature"])
            return out
        if name == "WheelBasedSpeedAndDistance" and f["WheelBasedMachineSpeed"] <= 64.255:
            return {"speed": f["WheelBasedMachineSpeed"]}
        if name == "AgrobotYawRate":
            return {"yaw_rate": f["YawRate"]} if -3.0 <= f["YawRate"] <= 3.0 else self._refuse()
        return None


def messages_for(protocol: str, dbc: str, side: str, wheelbase: float, source_address: int = -1,
                 peer_address: int = -1):
    """The message set of a CAN component (``side``: 'guidance' or 'tractor'); ValueError/OSError
    name what is wrong."""
    if protocol not in PROTOCOLS:
        raise ValueError(f"protocol {protocol!r}: expected one of {', '.join(PROTOCOLS)}")
    if protocol == "agrobot":
        return AgrobotMessages(load_dbc(dbc or DEFAULT_DBC), side)
    if not wheelbase > 0:
        raise ValueError(f"wheelbase {wheelbase}: expected a positive length (m) to convert curvature")
    return IsobusMessages(load_dbc(dbc or ISOBUS_DBC), side, wheelbase, source_address, peer_address)
