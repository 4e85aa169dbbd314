"""Every file of the shared real data through the project's readers, whole, one table:

    python3 benchmarks/real_data.py [--root ../shared/realdata]

Per file (or per recording folder): the format it was read as, what it gave (log rows and
columns, DBC messages, fields with their area), and what was skipped, repaired or named (the
quirks, the DBC's repairs and left-out messages, a log's missing canonical columns), with the
seconds it took. The F1TENTH runs are converted with the gyro declared in deg/s, the step tests
with their time from time.csv, as docs/bring-your-own-data.md shows.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
F1TENTH = ["delta_cmd=commandData.delta[rad]", "yaw_rate=imuData.wz[deg/s]", "v=pfOdomData.vx[m/s]",
           "x=pfOdomData.x[m]", "y=pfOdomData.y[m]"]
STEPS = ["x=trajectory.col1[m]", "y=trajectory.col2[m]", "heading=trajectory.col3[rad]", "v=trajectory.col4[m/s]",
         "delta_cmd=input.col1[rad]", "speed_cmd=input.col2[m/s]"]


def _log_row(root: Path, path: Path, fmt: str, options) -> tuple:
    from agrobot.measurements.recording import import_recording

    start = time.perf_counter()
    try:
        frame, report = import_recording(path, options)
        named = report.get("quirks", []) + [f"missing {c}" for c in report["missing"]]
        notes = [n for n in report.get("notes", []) if "index the writer left" not in n]
        gave = (f"{len(frame)} rows, {report['used']['duration']:.0f} s at {report['rate_hz']:.3g} Hz "
                f"({report['used']['how'].split(' (')[0]}): {', '.join(frame.columns[:7])}"
                + (" ..." if len(frame.columns) > 7 else ""))
        return (str(path.relative_to(root)), fmt, gave, "; ".join(named + notes[:1])[:160] or "-",
                f"{time.perf_counter() - start:.1f}")
    except Exception as exc:          # noqa: BLE001 - the table reports what failed
        return (str(path.relative_to(root)), fmt, f"FAILED: {exc}"[:160], "", f"{time.perf_counter() - start:.1f}")


def logs(root: Path) -> list[tuple]:
    from agrobot.measurements.recording import ImportOptions
    from agrobot.measurements.signal_expressions import parse_signal

    rows = []
    for path in sorted((root / "nmea_gpsd_testlogs").glob("*.log")):
        rows.append(_log_row(root, path, "NMEA", ImportOptions()))
    for path in sorted((root / "isoxml_dev4ag_timelogs").glob("TLG*.xml")):
        rows.append(_log_row(root, path, "ISO 11783-10 TLG", ImportOptions()))
    for run in sorted((root / "f1tenth_frictionmaps").rglob("DS*")):
        if run.is_dir():
            rows.append(_log_row(root, run, "tables joined on time",
                                 ImportOptions(signals=[parse_signal(s) for s in F1TENTH])))
    folders = sorted((root / "f1tenth_autokoopman_steps").rglob("measurement_*"), key=lambda p: int(p.name.split("_")[1]))
    for m in folders:
        rows.append(_log_row(root, m, "headerless tables", ImportOptions(signals=[parse_signal(s) for s in STEPS],
                                                                          time="time.col1[s]")))
    return rows


def dbcs(root: Path) -> list[tuple]:
    from agrobot.measurements.dbc import load_dbc_file

    rows = []
    for path in sorted((root / "opendbc").rglob("*.dbc")):
        start = time.perf_counter()
        try:
            db, report = load_dbc_file(path)
            repairs = ", ".join(f"{k} ({v})" for k, v in report.repairs.items())
            left = ", ".join(report.skipped)
            rows.append((str(path.relative_to(root)), "DBC", f"{len(db.messages)} messages, "
                         f"{sum(len(m.signals) for m in db.messages)} signals; {report.loader}"[:110],
                         ("; ".join(x for x in (repairs, f"left out: {left}" if left else "") if x))[:160] or "-",
                         f"{time.perf_counter() - start:.1f}"))
        except Exception as exc:      # noqa: BLE001
            rows.append((str(path.relative_to(root)), "DBC", f"FAILED: {exc}"[:160], "", ""))
    return rows


def fields(root: Path) -> list[tuple]:
    from agrobot.fields.readers import read_fields

    rows = []
    targets = [(p, None) for p in sorted((root / "fields2cover_data").iterdir()) if p.suffix in (".xml", ".json", ".geojson")]
    targets += [(root / "isoxml_dev4ag_timelogs" / "TASKDATA.XML", None),
                (root / "isoxml_dev4ag_timelogs" / "PARTFIELDS_TASKDATA.XML", None),
                (root / "iam_field_open_autonomous_tractor" / "datasets" / "iam_field" / "field_boundaries.csv", "EPSG:6677")]
    for path, crs in targets:
        start = time.perf_counter()
        try:
            found = read_fields(path, crs)
            area = sum(f.area_ha for f in found)
            problems = sum(bool(f.problems()) for f in found)
            rows.append((str(path.relative_to(root)), f"fields ({found[0].crs.split(' (')[0][:40]})",
                         f"{len(found)} field(s), {area:.2f} ha, {sum(f.holes for f in found)} hole(s), "
                         f"{sum(len(f.lines) for f in found)} line(s)",
                         f"{problems} self-intersecting" if problems else "-", f"{time.perf_counter() - start:.1f}"))
        except Exception as exc:          # noqa: BLE001
            rows.append((str(path.relative_to(root)), "fields", f"not a field file: {exc}"[:120], "", ""))
    return rows


def tracks(root: Path) -> list[tuple]:
    """Each time log's track as the field the harvester worked (fields --from-track)."""
    from agrobot.fields.track import field_from_track
    from agrobot.measurements.recording import positions

    rows = []
    for path in sorted((root / "isoxml_dev4ag_timelogs").glob("TLG*.xml")):
        start = time.perf_counter()
        try:
            t, lat, lon, report = positions(path)
            f = field_from_track(t, lat, lon, path.stem, str(path), report.get("working_width_m"))
            rows.append((str(path.relative_to(root)), "field from its track",
                         f"{f.area_ha:.2f} ha worked, {f.properties['passes']} passes, width "
                         f"{f.properties['working_width_m']:g} m", "-", f"{time.perf_counter() - start:.1f}"))
        except Exception as exc:          # noqa: BLE001
            rows.append((str(path.relative_to(root)), "field from its track", f"not made: {exc}"[:120], "", ""))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", type=Path, default=ROOT.parent / "shared" / "realdata")
    args = ap.parse_args()
    if not args.root.is_dir():
        sys.exit(f"{args.root}: not found")
    rows = logs(args.root) + dbcs(args.root) + fields(args.root) + tracks(args.root)
    head = ("file", "read as", "gave", "skipped, repaired or named", "s")
    widths = [max(len(str(r[i])) for r in rows + [head]) for i in range(4)]
    print(" | ".join(f"{h:{w}s}" for h, w in zip(head, widths)) + " | s")
    print("-|-".join("-" * w for w in widths) + "-|--")
    for r in rows:
        print(" | ".join(f"{str(x):{w}s}" for x, w in zip(r, widths)) + f" | {r[4]}")
    failed = [r for r in rows if str(r[2]).startswith(("FAILED", "not a field", "not made"))]
    print(f"\n{len(rows)} files or folders read, {len(failed)} not")


if __name__ == "__main__":
    main()
