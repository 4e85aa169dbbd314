"""AgOpenGPS field folders (file names in any letter case): Field.txt (StartFix latitude,
longitude: the local frame's origin), Boundary.txt (rings: the first the fence, the others
holes), Headland.txt, TrackLines.txt, ABLines.txt and CurveLines.txt (local east/north metres)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from agrobot.orchestrator.source_files import regular_file

from .field import Field, FieldError, GuidanceLine, polygon


def read_agopengps(folder: Path) -> list[Field]:
    origin = _aog_origin(folder)
    rings = _aog_rings(aog_file(folder, "Boundary.txt"))
    if not rings:
        raise FieldError(f"{aog_file(folder, 'Boundary.txt')}: no boundary ring in it (expected $Boundary, a True/False "
                         f"drive-through flag, a point count, then easting,northing,heading lines)")
    boundary = polygon(rings[0], rings[1:])
    crs = f"AgOpenGPS local metres about StartFix {origin[0]:.7f}, {origin[1]:.7f}"
    f = Field(folder.name, boundary, origin, str(folder), crs)
    head = aog_file(folder, "Headland.txt")
    if head.exists():
        hl = _aog_rings(head)
        if hl:
            f.headland = polygon(hl[0], hl[1:])
    f.lines = _aog_tracks(folder)
    return [f]


def aog_file(folder: Path, name: str) -> Path:
    """An AgOpenGPS file of the folder in whatever letter case it was written (Boundary.Txt,
    BOUNDARY.TXT); the name as given when the folder has none."""
    if (folder / name).exists():
        return folder / name
    lower = name.lower()
    found = [p for p in folder.iterdir() if p.name.lower() == lower] if folder.is_dir() else []
    return found[0] if found else folder / name


def boundary_without_field_txt(folder: Path) -> bool:
    return folder.is_dir() and aog_file(folder, "Boundary.txt").exists() and not aog_file(folder, "Field.txt").exists()


def is_agopengps(folder: Path) -> bool:
    return folder.is_dir() and aog_file(folder, "Field.txt").exists() and aog_file(folder, "Boundary.txt").exists()


def text_lines(path: Path) -> list[str]:
    try:
        return [ln.strip() for ln in regular_file(path, FieldError).read_text(encoding="utf-8-sig", errors="replace")
                .splitlines()]
    except OSError as exc:
        raise FieldError(f"{path}: cannot read: {exc}") from None


def _aog_origin(folder: Path) -> tuple[float, float]:
    path = aog_file(folder, "Field.txt")
    if not path.exists():
        raise FieldError(f"{folder}: an AgOpenGPS field folder (it has {aog_file(folder, 'Boundary.txt').name}) without "
                         f"Field.txt: its StartFix line gives the latitude,longitude that the boundary's local metres "
                         f"are measured from")
    lines = text_lines(path)
    for i, line in enumerate(lines[:-1]):
        if line.lower().startswith("startfix"):
            parts = lines[i + 1].split(",")
            try:
                return float(parts[0]), float(parts[1])
            except (ValueError, IndexError):
                raise FieldError(f"{path}: line {i + 2}: StartFix must be followed by 'latitude,longitude', got "
                                 f"{lines[i + 1]!r}") from None
    raise FieldError(f"{path}: no StartFix line (the field's origin, 'latitude,longitude' on the next line)")


def _aog_rings(path: Path) -> list[np.ndarray]:
    """Rings of a Boundary.txt or Headland.txt: [$header] {[True|False]... count, count lines e,n[,h]}."""
    if not path.exists():
        return []
    lines = [ln for ln in text_lines(path) if ln]
    i = 1 if lines and lines[0].startswith("$") else 0
    rings = []
    while i < len(lines):
        while i < len(lines) and lines[i].lower() in ("true", "false"):
            i += 1
        if i >= len(lines):
            break
        try:
            count = int(lines[i])
        except ValueError:
            raise FieldError(f"{path}: line {i + 1}: expected a point count, got {lines[i]!r}") from None
        pts = []
        for k in range(i + 1, i + 1 + count):
            try:
                e, n = (float(x) for x in lines[k].split(",")[:2])
            except (ValueError, IndexError):
                raise FieldError(f"{path}: line {k + 1}: expected easting,northing[,heading], got "
                                 f"{lines[k] if k < len(lines) else 'the end of the file'!r}") from None
            pts.append((e, n))
        if len(pts) >= 3:
            rings.append(np.array(pts))
        i += 1 + count
    return rings


def _aog_tracks(folder: Path) -> list[GuidanceLine]:
    out = []
    track = aog_file(folder, "TrackLines.txt")
    if track.exists():              # name, heading, A, B, nudge, mode, visible, count, count points
        lines = [ln for ln in text_lines(track) if ln]
        i = 1 if lines and lines[0].startswith("$") else 0
        while i + 7 < len(lines):
            name = lines[i]
            try:
                a = [float(x) for x in lines[i + 2].split(",")[:2]]
                b = [float(x) for x in lines[i + 3].split(",")[:2]]
                count = int(lines[i + 7])
                pts = [[float(x) for x in lines[k].split(",")[:2]] for k in range(i + 8, i + 8 + count)]
            except (ValueError, IndexError):
                raise FieldError(f"{track}: track {name!r} (line {i + 1}): expected name, heading, A 'e,n', B 'e,n', "
                                 f"nudge, mode, visible, a point count and the points") from None
            out.append(GuidanceLine(name, np.array(pts if len(pts) >= 2 else [a, b], float)))
            i += 8 + count
    ab = aog_file(folder, "ABLines.txt")
    if ab.exists():                  # name, heading [deg, from north clockwise], easting, northing
        for k, line in enumerate(ln for ln in text_lines(ab) if ln and not ln.startswith("$")):
            parts = line.split(",")
            try:
                heading, e, n = (float(x) for x in parts[1:4])
            except (ValueError, IndexError):
                raise FieldError(f"{ab}: line {k + 1}: expected name,heading,easting,northing, got {line!r}") from None
            d = np.array([math.sin(math.radians(heading)), math.cos(math.radians(heading))])
            out.append(GuidanceLine(parts[0], np.array([[e, n], [e + 100 * d[0], n + 100 * d[1]]])))
    curve = aog_file(folder, "CurveLines.txt")
    if curve.exists():               # $CurveLines, then name, heading, count, count points
        lines = [ln for ln in text_lines(curve) if ln]
        i = 1 if lines and lines[0].startswith("$") else 0
        while i + 2 < len(lines):
            try:
                count = int(lines[i + 2])
                pts = [[float(x) for x in lines[k].split(",")[:2]] for k in range(i + 3, i + 3 + count)]
            except (ValueError, IndexError):
                raise FieldError(f"{curve}: curve {lines[i]!r} (line {i + 1}): expected name, heading, a point count "
                                 f"and the points") from None
            if len(pts) >= 2:
                out.append(GuidanceLine(lines[i], np.array(pts, float)))
            i += 3 + count
    return out
