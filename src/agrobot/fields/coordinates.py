"""How a field file's numbers become local metres: a CRS the file names, or ``crs`` given by the
user (any pyproj input: "EPSG:6677"), or, when neither says, longitude/latitude if every value
fits and the extent is under half a degree (a field, not a continent), else local metres as
written. Longitude and latitude written the wrong way round, and coordinates that are no place
on Earth, are refused naming the value. Everything geographic goes to the local frame of
fields.field.local_frame.

Imported where used: pyproj (start-up: 28 ms of CPU on every command, measured: the fields plugin loads this
module; only a file in a projected CRS needs it).
"""
from __future__ import annotations

import re

import numpy as np

from .field import FieldError, local_frame

MAX_GEOGRAPHIC_EXTENT = 0.5        # deg: beyond this a file of small numbers is metres, not degrees
EARTH_CIRCUMFERENCE = 40_075_017.0  # m (WGS 84 equator): no coordinate of a field on Earth is larger


class Coordinates:
    """How a file's numbers become local metres: lon/lat, a projected CRS, or local as written."""

    def __init__(self, where: str, declared: str | None, given: str | None, sample):
        self.where = where
        self.crs = None
        text = given or declared
        if text:
            import pyproj

            try:
                self.crs = pyproj.CRS.from_user_input(_epsg(text))
            except pyproj.exceptions.CRSError as exc:
                raise FieldError(f"{where}: unknown CRS {text!r} ({exc}); expected e.g. EPSG:4326, EPSG:28992 or "
                                 f"EPSG:6677") from None
            self.kind = "geographic" if self.crs.is_geographic else "projected"
            self.text = f"{self.crs.to_string()} ({'given' if given else 'named by the file'})"
        else:            # each field's own extent: one file may hold fields continents apart
            rings = sample if isinstance(sample, list) else [sample]
            allpts = np.vstack(rings)
            on_earth(where, allpts)
            ok = len(allpts) > 0 and np.all(np.abs(allpts[:, 0]) <= 180) and np.all(np.abs(allpts[:, 1]) <= 90)
            extent = max(float(np.max(np.ptp(r, axis=0))) for r in rings) if len(allpts) else 0.0
            swapped = len(allpts) > 0 and np.all(np.abs(allpts[:, 0]) <= 90) and np.all(np.abs(allpts[:, 1]) <= 180)
            if not ok and swapped and extent < MAX_GEOGRAPHIC_EXTENT:
                lat = float(allpts[np.argmax(np.abs(allpts[:, 1])), 1])
                raise FieldError(f"{where}: latitude {lat:g} deg is beyond +-90 (the second number of a point is the "
                                 f"latitude); every point fits longitude/latitude with the two swapped: write "
                                 f"longitude first (GeoJSON RFC 7946, KML), or give --crs for metres of a projection")
            self.kind = "geographic" if ok and extent < MAX_GEOGRAPHIC_EXTENT else "local"
            self.text = ("longitude/latitude (WGS 84): the values fit and each field spans under half a degree"
                         if self.kind == "geographic" else "local metres as written (no CRS named; too large for degrees)")

    def lonlat(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, float)[:, :2]
        if self.kind == "projected":
            import pyproj

            t = pyproj.Transformer.from_crs(self.crs, "EPSG:4326", always_xy=True)
            lon, lat = t.transform(xy[:, 0], xy[:, 1])
            return np.column_stack([lon, lat])
        return xy

    def frame(self, rings: list[np.ndarray], origin=None):
        """(origin, rings -> local) for the rings of one file."""
        if self.kind == "local":
            for r in rings:
                on_earth(self.where, np.asarray(r, float)[:, :2])
            return None, (lambda xy: on_earth(self.where, np.asarray(xy, float)[:, :2]))
        lonlat = [self.lonlat(r) for r in rings]
        bad = [p for r in lonlat for p in r if not (abs(p[0]) <= 180 and abs(p[1]) <= 90)]
        if bad:
            raise FieldError(f"{self.where}: coordinates {bad[0].tolist()} are not longitude/latitude under {self.text}")
        origin, to_local = local_frame(lonlat, origin)
        return origin, (lambda xy: to_local(self.lonlat(xy)))


def on_earth(where: str, xy: np.ndarray) -> np.ndarray:
    """``xy`` when every coordinate is a finite number no larger than the Earth's circumference
    (a local or projected metre beyond it is no place on Earth); else a FieldError naming it."""
    bad = ~np.isfinite(xy) | (np.abs(xy) > EARTH_CIRCUMFERENCE)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise FieldError(f"{where}: coordinate {xy[i, j]:g} (point {i + 1}, {'xy'[j]}) is beyond the Earth: expected "
                         f"finite metres within +-{EARTH_CIRCUMFERENCE:.4g} (or longitude/latitude in degrees)")
    return xy


def _epsg(text: str) -> str:
    m = re.search(r"EPSG:{1,2}(\d+)$", text.strip(), re.I)
    return f"EPSG:{m.group(1)}" if m else text.strip()
