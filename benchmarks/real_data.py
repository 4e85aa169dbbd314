"""Every file of the shared real data through the project's readers, one table:

    python3 benchmarks/real_data.py [--root ../shared/realdata]

Per file: the format the reader took it for, what it gave (log rows and columns, or fields with
their area), and what is missing (a log's canonical columns it lacks, a field's problems).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def logs(root: Path) -> list[tuple[str, str, str, str]]:
    from measurements.recording import import_recording

    rows = []
    for path in sorted((root / "nmea_gpsd_testlogs").glob("*.log")) + [root / "isoxml_dev4ag_timelogs"]:
        try:
            frame, report = import_recording(path)
            fmt = "ISO 11783-10 TaskData + TLG" if path.is_dir() else \
                f"NMEA ({report['nmea']['epochs']} epochs, qualities {'/'.join(report['nmea']['by_quality'])})"
            rows.append((str(path.relative_to(root)), fmt,
                         f"{len(frame)} rows at {report['rate_hz']:g} Hz: {', '.join(c for c in frame.columns[:8])}"
                         + (" ..." if len(frame.columns) > 8 else ""), ", ".join(report["missing"]) or "-"))
        except Exception as exc:          # noqa: BLE001 - the table reports what failed
            rows.append((str(path.relative_to(root)), "?", f"FAILED: {exc}", ""))
    return rows


def fields(root: Path) -> list[tuple[str, str, str, str]]:
    from fields.readers import read_fields

    rows = []
    targets = [(p, None) for p in sorted((root / "fields2cover_data").iterdir()) if p.suffix in (".xml", ".json", ".geojson")]
    targets += [(root / "isoxml_dev4ag_timelogs" / "TASKDATA.XML", None),
                (root / "isoxml_dev4ag_timelogs" / "PARTFIELDS_TASKDATA.XML", None),
                (root / "iam_field_open_autonomous_tractor" / "datasets" / "iam_field" / "field_boundaries.csv", "EPSG:6677")]
    for path, crs in targets:
        try:
            found = read_fields(path, crs)
            area = sum(f.area_ha for f in found)
            problems = sum(bool(f.problems()) for f in found)
            rows.append((str(path.relative_to(root)), f"fields ({found[0].crs.split(' (')[0][:40]})",
                         f"{len(found)} field(s), {area:.2f} ha, {sum(f.holes for f in found)} hole(s), "
                         f"{sum(len(f.lines) for f in found)} line(s)",
                         f"{problems} self-intersecting" if problems else "-"))
        except Exception as exc:          # noqa: BLE001
            rows.append((str(path.relative_to(root)), "fields", f"not a field file: {exc}"[:90], ""))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", type=Path, default=ROOT.parent / "shared" / "realdata")
    args = ap.parse_args()
    if not args.root.is_dir():
        sys.exit(f"{args.root}: not found")
    rows = logs(args.root) + fields(args.root)
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    print(f"{'file':{widths[0]}s}  {'read as':{widths[1]}s}  {'gave':{widths[2]}s}  missing")
    for r in rows:
        print(f"{r[0]:{widths[0]}s}  {r[1]:{widths[1]}s}  {r[2]:{widths[2]}s}  {r[3]}")


if __name__ == "__main__":
    main()
