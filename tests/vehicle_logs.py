"""The F1TENTH logs the tests read: the copies in tests/data (their licences there) through the
package's readers (agrobot.measurements.f1tenth)."""
from __future__ import annotations

from pathlib import Path

from agrobot.measurements import f1tenth

DATA = Path(__file__).resolve().parent / "data"
FRICTIONMAPS = DATA / "f1tenth_frictionmaps" / "DataSets"
AUTOKOOPMAN = DATA / "f1tenth_autokoopman_steps" / "F1tenthCar"
ROOT_STUDIES = Path(__file__).resolve().parent.parent / "studies"


def frictionmaps_log(run: str | Path, rate: float | None = None):
    """One FrictionMaps data set (``"DS1"`` of tests/data, or a folder)."""
    return f1tenth.frictionmaps_log(Path(run) if Path(run).is_dir() else FRICTIONMAPS / str(run), rate)


def autokoopman_log(measurements=None, hole: float = 1.0):
    return f1tenth.autokoopman_log(AUTOKOOPMAN, measurements, hole)
