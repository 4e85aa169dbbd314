"""A table's heading column (a dual-antenna receiver's, an INS's) as the log's yaw angle ``heading``:
radians, ENU (anticlockwise from east), unwrapped on its own stamps.

Its unit is the declared one (a header's ``[deg]``, a units row, ``--signal heading=...[deg]``);
undeclared, values beyond 2 pi + 0.1 are degrees (no angle in radians reaches them), said so.
Its sense is read against the track: the course of the fixes (measurements.direction.course) turns
with an anticlockwise heading and against a clockwise one (rank correlation of the two rates at
least 0.3 either way; reversing turns the course by pi, not its rate). A clockwise heading is a compass
heading from north, psi = pi/2 - heading; without a track to judge by, a heading in degrees is
taken as receivers write it (clockwise from north) and one in radians as ENU, said so.
"""
from __future__ import annotations

import math

import numpy as np

from .direction import angle_rate, course, rank_correlation

SENSE = 0.3             # the least |correlation| of the heading's rate with the course's that decides its sense


def sense(gnss, t: np.ndarray, psi: np.ndarray) -> tuple[int, float | None]:
    """(+1 when the heading turns with the course (anticlockwise), -1 against it, 0 undecided; the
    rank correlation of the two rates, None without a track to judge by). Both rates are read on the
    same chords (direction.angle_rate): a 20 Hz heading differenced per sample is its noise."""
    if gnss is None or len(gnss) < 20 or len(t) < 20:
        return 0, None
    tc, c, _ = course(gnss)
    rate = angle_rate(tc, c)
    hr = angle_rate(tc, np.interp(tc, t, np.unwrap(psi)))
    inside = (tc >= t[0]) & (tc <= t[-1]) & np.isfinite(rate) & np.isfinite(hr)
    if inside.sum() < 20 or np.std(rate[inside]) == 0 or np.std(hr[inside]) == 0:
        return 0, None
    rho = rank_correlation(rate[inside], hr[inside])
    return (0 if not abs(rho) >= SENSE else (1 if rho > 0 else -1)), rho


def as_yaw(streams, declared: bool) -> None:
    """streams.signals["heading"] (in radians if ``declared``, else of unknown unit) as the ENU yaw
    angle, unwrapped, in place; the choices in report["columns"]["heading"]."""
    t, x = streams.signals["heading"]
    said = []
    degrees = not declared and float(np.nanmax(np.abs(x))) > 2 * math.pi + 0.1
    if degrees:
        x = np.radians(x)
        said.append("no unit declared: its values reach beyond 2 pi, so degrees (declare one with --signal "
                    "heading=COLUMN[unit])")
    turns, rho = sense(streams.gnss, t, x)
    compass = turns < 0 or (turns == 0 and degrees)
    if compass:
        x = math.pi / 2 - x
    why = "no track to judge by" if rho is None else \
        f"the track does not decide: its rate correlates {rho:+.2f} with the course's, |rho| below {SENSE}"
    said.append(("clockwise from north (a compass heading): psi = pi/2 - heading" if compass else
                 "anticlockwise from east (ENU)") + (" by its turns against the course of the fixes" if turns else
                                                    f" as receivers write it ({why})" if compass
                                                    else f" ({why})"))
    streams.signals["heading"] = (t, np.unwrap(x))
    columns = streams.report.setdefault("columns", {})
    columns["heading"] = columns.get("heading", "heading") + "; " + "; ".join(said) + "; the yaw angle a gyro-less " \
        "machine's yaw stage is identified on"
