"""What a sweep will cost, told before it is paid, and which points keep their signals.

The nominal run (the study's own values, run first: the oscillation bound's reference,
orchestrator.sweep_judgement) is timed and its files weighed; the sweep's cost is

    time ~ 5 s + points x t_nominal / workers,     disk ~ kept x size_with_signals + (points - kept) x size_without

and a sweep expected beyond ``DISK_LIMIT`` or ``TIME_LIMIT`` (or beyond the free space of its
folder) is refused before any point runs, unless asked (``--accept-cost``).

Signals (the ``--keep-signals`` policy): ``all``, ``none``, or ``worst``: every point's metrics,
and signals only for the ``WORST`` points farthest outside their bounds (orchestrator.sweep_judgement.severity)
and a sample of ``SAMPLE`` points spread evenly over the sweep. Default: all for a sweep of up to
``ALL_SIGNALS_UP_TO`` points with the Python engine, worst beyond; none with the compiled engine
(its points take milliseconds: writing each one's signals would cost more than running it). Under
``worst`` each point's worker writes its signals and the sweep removes them as soon as the point
is neither among the worst so far nor in the sample, so the disk holds about WORST + SAMPLE +
workers points' signals at any time.
"""
from __future__ import annotations

import heapq
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

from .study_files import StudyError

DISK_LIMIT = 5e9             # bytes: beyond this a sweep asks for --accept-cost
TIME_LIMIT = 12 * 3600.0     # s: the same
ALL_SIGNALS_UP_TO = 50
WORKER_START_S = 5.0         # s: a worker process's start (its imports), paid once per sweep
WORST = 10
SAMPLE = 10
POLICIES = ("all", "none", "worst")


class CostRefused(StudyError):
    """A sweep expected beyond the stated disk or time limit, not asked for (exit 2)."""


def policy(keep_signals: bool | str | None, engine: str, points: int) -> str:
    """The signal policy of a sweep: ``keep_signals`` True/False/a policy name, None: the default."""
    if keep_signals is True:
        return "all"
    if keep_signals is False:
        return "none"
    if keep_signals in POLICIES:
        return str(keep_signals)
    if keep_signals is not None:
        raise StudyError(f"keep_signals={keep_signals!r}: expected True, False or one of {', '.join(POLICIES)}")
    if engine != "python":
        return "none"
    return "all" if points <= ALL_SIGNALS_UP_TO else "worst"


def folder_bytes(folder: Path) -> tuple[int, int]:
    """(bytes of the signal files, bytes of the other files) in a point's folder."""
    signals = other = 0
    for path in Path(folder).iterdir():
        if path.is_file():
            size = path.stat().st_size
            if is_signal_file(path):
                signals += size
            else:
                other += size
    return signals, other


def is_signal_file(path: Path) -> bool:
    return path.name.startswith("signals.") or path.name == "run.mcap"


def human_bytes(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if n < 1000 or unit == "TB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.3g} {unit}"
        n /= 1000
    return f"{n:.3g} TB"


def human_time(s: float) -> str:
    if s < 90:
        return f"{s:.0f} s"
    if s < 5400:
        return f"{s / 60:.0f} min"
    return f"{s / 3600:.1f} h"


@dataclass(frozen=True)
class Cost:
    points: int
    workers: int
    seconds: float
    disk: float
    kept: int                # points whose signals are kept
    signal_bytes: int        # of one point
    other_bytes: int         # of one point

    def line(self, policy_name: str, nominal_s: float) -> str:
        kept = {"all": "signals of every point", "none": "metrics of every point, no signals",
                "worst": f"metrics of every point, signals of the {WORST} worst and a sample of {SAMPLE}"}[policy_name]
        return (f"sweep: {self.points} points on {self.workers} worker{'s' if self.workers > 1 else ''}: about "
                f"{human_time(self.seconds)} (the nominal run took {nominal_s:.1f} s) and {human_bytes(self.disk)} "
                f"on disk ({kept}; {human_bytes(self.signal_bytes)} of signals per point)")


def estimate(points: int, workers: int, nominal_s: float, signal_bytes: int, other_bytes: int,
             policy_name: str) -> Cost:
    """The sweep's expected time and disk use from its nominal run (the module docstring)."""
    kept = {"all": points, "none": 0, "worst": min(points, WORST + SAMPLE + workers)}[policy_name]
    rounds = math.ceil(points / max(workers, 1))
    disk = kept * (signal_bytes + other_bytes) + (points - kept) * other_bytes
    start = WORKER_START_S if points else 0.0
    return Cost(points, workers, start + rounds * nominal_s, float(disk), kept, signal_bytes, other_bytes)


def check_cost(cost: Cost, folder: Path, accept: bool) -> None:
    """Refuse a sweep beyond the limits (or the folder's free space) unless ``accept``."""
    free = shutil.disk_usage(_existing(folder)).free
    if cost.disk > free:
        raise CostRefused(f"sweep: about {human_bytes(cost.disk)} expected on disk, {human_bytes(free)} free where "
                          f"{folder} is; fewer points, --keep-signals worst or --no-keep-signals use less")
    over = []
    if cost.disk > DISK_LIMIT:
        over.append(f"{human_bytes(cost.disk)} on disk (limit {human_bytes(DISK_LIMIT)})")
    if cost.seconds > TIME_LIMIT:
        over.append(f"{human_time(cost.seconds)} (limit {human_time(TIME_LIMIT)})")
    if over and not accept:
        raise CostRefused(f"sweep: expected {' and '.join(over)}; pass --accept-cost (Python: accept_cost=True) to "
                          f"run it anyway, or run fewer points (--engine compiled runs a point in milliseconds; "
                          f"--no-keep-signals keeps no signals)")


def _existing(folder: Path) -> Path:
    folder = Path(folder).absolute()
    while not folder.exists():
        folder = folder.parent
    return folder


def sample_points(keys: list[str], size: int | None = None) -> set[str]:
    """``size`` (default SAMPLE) point keys spread evenly over the sweep (the first included)."""
    size = SAMPLE if size is None else size
    if len(keys) <= size:
        return set(keys)
    step = len(keys) / size
    return {keys[int(i * step)] for i in range(size)}


class SignalKeeper:
    """Under the ``worst`` policy: keeps the signals of the WORST points of highest severity seen
    so far and of the sample; removes every other point's signal files once it is stored."""

    def __init__(self, sample: set[str], worst: int | None = None) -> None:
        self.sample, self.worst = sample, WORST if worst is None else worst
        self.heap: list[tuple[float, str]] = []        # (severity, key): the kept worst, least severe first

    def keep(self, key: str, score: float, points_dir: Path) -> None:
        """Add a stored point (of the folder ``points_dir``); drop the signals of whichever is no longer kept."""
        dropped = None
        if len(self.heap) < self.worst:
            heapq.heappush(self.heap, (score, key))
        elif score > self.heap[0][0]:
            dropped = heapq.heapreplace(self.heap, (score, key))[1]
        else:
            dropped = key
        if dropped is not None and dropped not in self.sample:
            for path in (Path(points_dir) / dropped).glob("*"):
                if is_signal_file(path):
                    path.unlink(missing_ok=True)

    def kept(self) -> list[str]:
        return sorted({k for _, k in self.heap} | self.sample)
