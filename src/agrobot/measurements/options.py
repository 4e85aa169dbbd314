"""How to read a recording: the options ``convert``, ``identify`` and ``diagnose`` share."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from agrobot.orchestrator.resolver import resolve

from .signal_expressions import parse_signal


@dataclass
class ImportOptions:
    """How to read a recording (the ``convert``/``identify``/``diagnose`` options)."""

    dbc: Path | None = None                     # None: the project's agrobot_tractor.dbc
    signals: list = field(default_factory=list)  # SignalSpec per column (measurements.signal_expressions)
    wheelbase: float | None = None              # m: curvature <-> wheel angle (None: the study's, else 1.4)
    rate: float | None = None                   # Hz of the log (default: the GNSS epoch rate, else <= 50 Hz)
    run: int | None = None                      # 1-based index of the run to use
    time_range: tuple[float, float] | None = None   # s from the first sample
    min_speed: float = 0.2                      # m/s: driving
    min_stop: float = 3.0                       # s: a shorter stop does not end a run
    min_run: float = 10.0                       # s: shorter runs are listed, not used
    trim_standstill: bool = False               # leave out the standstill either side of the run used
    steering_ratio: float | None = None         # recorded steering angles / road-wheel angles (None: the study's, else 1)
    steering_ratio_from: str = ""               # given | study | default: who chose it (for_vehicle fills it)
    bus: str | None = None                      # the CAN bus to read (candump's can0, a Vector channel)
    time: str | None = None                     # a table's time column(s) (measurements.tables.parse_time)
    keep_spikes: bool = False                   # keep the samples found to be spikes (they are named either way)
    max_gap: float = 0.5                        # s: a channel's gap up to this is bridged (linear; held for a command)
    align: str = "auto"                         # auto | none | GROUP=SECONDS (measurements.audit.parse_align)
    sign_speed: bool = False                    # an unsigned speed made negative where the machine reverses
    where: str | None = None                    # the stretches judged: 'mode == auto' (measurements.modes)
    keep_unexplained: bool = False              # keep the stretches the command does not explain (measurements.modes)
    min_stretch: float = 15.0                   # s: a selected stretch shorter than this is left out (measurements.modes)
    said: set = field(default_factory=set, repr=False, compare=False)   # selection lines printed already

    def __post_init__(self):
        """A signal given as its ``--signal`` text (``"yaw_rate=imuData.wz[deg/s]"``, as the Python API
        takes it) is parsed, a malformed one refused with what was expected (a LogError)."""
        self.signals = [parse_signal(s) if isinstance(s, str) else s for s in self.signals]

    def for_vehicle(self, study=None) -> "ImportOptions":
        """These options with what they leave open taken from the study's [vehicle] table
        (steering_ratio, wheelbase), else its yaw plant's l_f + l_r, else the paper tractor's."""
        vehicle = (study.section("vehicle") if study is not None else None) or {}
        wheelbase = self.wheelbase or vehicle.get("wheelbase")
        model = resolve(study) if wheelbase is None and study is not None else None
        if model is not None and model.find(role="yaw_plant"):
            p = model.parameters(model.find(role="yaw_plant")[0])
            wheelbase = float(p.get("l_f", 1.0)) + float(p.get("l_r", 0.4))
        origin = self.steering_ratio_from or ("given" if self.steering_ratio else
                                              "study" if vehicle.get("steering_ratio") else "default")
        return replace(self, wheelbase=float(wheelbase or 1.4), steering_ratio_from=origin,
                       steering_ratio=float(self.steering_ratio or vehicle.get("steering_ratio", 1.0)))

    @property
    def maps_a_table(self) -> bool:
        """Options that only a table import uses: a table given with them is not a log as it is."""
        return bool(self.signals) or self.time is not None
