"""``fields PATH``: what a field file or folder holds (fields, area, rings, guidance lines,
headland, validity) and a drawing of it; ``--out DIR`` writes fields.png, fields.json and the
fields as GeoJSON (longitude/latitude) for any GIS.

Imported where used: matplotlib (start-up: 80 ms of CPU, 0.37 s with pyplot, on every command, measured: this
is the fields plugin; only a drawing needs it), agrobot.api (start-up: 0.1 s, measured with ``python3 -X importtime -m
agrobot --help``; only the command's run needs it).
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
from shapely.geometry import LineString, Polygon, mapping

from agrobot.orchestrator.atomic_files import atomic_write, write_json
from agrobot.orchestrator.cli import add_output_options

from .plan_cli import register as register_plan


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", type=Path, help="a GeoJSON, WKT, GML, KML/KMZ or ISO 11783-10 TaskData file, a polygon "
                   "CSV, an AgOpenGPS field folder, or a folder of such files; with --from-track a GNSS track (any "
                   "recording convert reads: NMEA, a bag, a TLG time log, a lat/lon table)")
    p.add_argument("--crs", default=None, help="the coordinates' CRS when the file does not name it (EPSG:6677 ...)")
    add_output_options(p, "folder for fields.png, fields.json, fields.geojson", required=False, plots=True)
    p.add_argument("--max-file-size", default=None, metavar="SIZE", help="the largest file read (500M, 4G ...; default "
                   "1G for a file read whole, 16G for a recording read as a stream)")
    t = p.add_argument_group("a field from a track (--from-track)")
    t.add_argument("--from-track", action="store_true", help="the field a machine worked: the outline of the ground "
                   "its track covered and its straight passes as AB lines (write it with --out, plan it with plan "
                   "OUT/fields.geojson)")
    t.add_argument("--width", type=float, default=None, help="working width [m] (default: the recording's, ISO DDI 67, "
                   "else the spacing of the passes)")
    t.add_argument("--signal", action="append", default=[], metavar="COLUMN=EXPR[unit]",
                   help="a table's position columns: --signal lat=TABLE.COLUMN --signal lon=TABLE.COLUMN")
    t.add_argument("--time", default=None, metavar="COLUMN[unit|datetime]", help="a table's time column (as convert)")


def run(args: argparse.Namespace) -> int:
    """Parse, read through agrobot.api, print."""
    from agrobot.api import fields as read

    found = read(args.source, crs=args.crs, out=args.out, overwrite=args.overwrite, plots=not args.no_plots,
                 from_track=args.from_track, width=args.width, signals=args.signal, time=args.time,
                 max_file_size=args.max_file_size)
    if found.track is not None:
        print(found.track)
    print(f"{args.source}: {len(found.fields)} field(s)")
    for why in found.skipped:
        print(f"  not read: {why}")
    print(f"{'field':32s} {'area [ha]':>10s} {'rings':>5s} {'lines':>5s} {'headland':>8s}  valid  coordinates")
    for f, s in zip(found.fields, found.summaries()):
        print(f"{f.name[:32]:32s} {s['area_ha']:10.3f} {s['rings']:5d} {len(s['lines']):5d} "
              f"{'yes' if s['headland'] else 'no':>8s}  {'yes' if s['valid'] else 'NO':5s}  {f.crs}")
        for g in s["lines"]:
            print(f"    {g['kind']} {g['name']!r}: {g['length_m']:.1f} m, heading {g['heading_deg']:.1f} deg (east = 0, "
                  f"counter-clockwise)")
        for problem in s["problems"]:
            print(f"    problem: {problem}")
        if f.properties.get("repaired"):
            print(f"    repaired: {f.properties['repaired']}")
    if args.out is not None:
        local = [f.name for f in found.fields if f.origin is None]
        print(f"written: {args.out}/{'' if args.no_plots else 'fields.png, '}fields.json, fields.geojson"
              + (f" (without {', '.join(local)}: local coordinates, no longitude/latitude)" if local else ""))
    return 0


def write_fields(folder: Path, source: str, fields, plots: bool = True, track: str | None = None) -> None:
    """fields.json, fields.geojson and (``plots``) fields.png of ``fields`` read from ``source``;
    ``track``: the line describing the GNSS track a field was made from, kept in fields.json."""
    write_json(folder / "fields.json", {"source": source, "fields": [f.summary() for f in fields],
                                        **({"track": track} if track is not None else {})})
    atomic_write(folder / "fields.geojson", lambda p: p.write_text(json.dumps(geojson(fields))))
    if plots:
        draw(fields, folder / "fields.png", source)


def geojson(fields) -> dict:
    """The fields with a geographic reference as a GeoJSON FeatureCollection in longitude/latitude
    (RFC 7946); a field in local coordinates has no place in it."""
    feats = []
    for f in fields:
        if f.origin is None:
            continue
        conv = f.to_geodetic
        poly = Polygon(conv(np.asarray(f.boundary.exterior.coords)),
                       [conv(np.asarray(h.coords)) for h in f.boundary.interiors])
        props = {"name": f.name, "area_ha": round(f.area_ha, 4), "kind": "boundary"}
        feats.append({"type": "Feature", "properties": props, "geometry": mapping(poly)})
        for g in f.lines:
            feats.append({"type": "Feature", "properties": {"name": g.name, "field": f.name, "kind": g.kind},
                          "geometry": mapping(LineString(conv(g.points)))})
    return {"type": "FeatureCollection", "features": feats}


def draw(fields, path: Path, title: str) -> Path:
    """Each field in its local frame, side by side (at most 12), with holes, headland and lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = fields[:12]
    cols = min(4, len(shown))
    rows = math.ceil(len(shown) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4.0 * rows), squeeze=False)
    for ax, f in zip(axes.flat, shown):
        x, y = f.boundary.exterior.xy
        ax.fill(x, y, color="#cfe8b0", edgecolor="#2f6b1f", lw=1.2, label="boundary")
        for k, hole in enumerate(f.boundary.interiors):
            hx, hy = hole.xy
            ax.fill(hx, hy, color="white", edgecolor="#8a3b12", lw=1, label="hole" if k == 0 else None)
        if f.headland is not None:
            hx, hy = f.headland.exterior.xy
            ax.plot(hx, hy, "--", color="#7a5c00", lw=1, label="headland")
        for k, g in enumerate(f.lines):
            ax.plot(g.points[:, 0], g.points[:, 1], color="tab:blue", lw=1.2, label="guidance line" if k == 0 else None)
        ax.set_title(f"{f.name[:28]}\n{f.area_ha:.2f} ha, {f.holes} hole(s), {len(f.lines)} line(s)"
                     + ("" if not f.problems() else f"\nINVALID: {f.problems()[0][:36]}..."), fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("east [m]" + ("" if f.origin else " (local)"), fontsize=8)
        ax.set_ylabel("north [m]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        if f.holes or f.lines or f.headland is not None:
            ax.legend(fontsize=6, loc="best")
    for ax in list(axes.flat)[len(shown):]:
        ax.axis("off")
    fig.suptitle(f"{title}: {len(fields)} field(s)" + (f", first {len(shown)} shown" if len(fields) > len(shown) else ""),
                 fontsize=10)
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=100, format="png"))
    plt.close(fig)
    return path


def register(registry) -> None:
    register_plan(registry)
    registry.add_command("fields", "list and draw the fields in a file or folder (GeoJSON, WKT, GML, KML, ISOXML, "
                                   "AgOpenGPS), or make one from a GNSS track (--from-track)",
                         add_arguments, run)
