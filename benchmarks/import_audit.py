"""The import audit (measurements.audit) of every recording in the shared real data:

    python3 benchmarks/import_audit.py [--root ../shared/realdata] [--quick]

Per recording: each channel's rate, gaps and group, then every finding (kind, value, interval,
resolved) as the import prints it. The F1TENTH runs are read with the signals a user names
(docs/bring-your-own-data.md), the IMU's ``ax`` declared as the lateral acceleration in g (its
axes are turned 90 deg about z); the step tests with their time from time.csv; the time logs and
the NMEA captures as they are. ``--quick``: one recording of each kind.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
F1TENTH = ["delta_cmd=commandData.delta[rad]", "yaw_rate=imuData.wz[deg/s]", "v=pfOdomData.vx[m/s]",
           "x=pfOdomData.x[m]", "y=pfOdomData.y[m]", "ay=imuData.ax[g]"]
STEPS = ["x=trajectory.col1[m]", "y=trajectory.col2[m]", "heading=trajectory.col3[rad]", "v=trajectory.col4[m/s]",
         "delta_cmd=input.col1[rad]"]


def recordings(root: Path, quick: bool):
    """(name, path, ImportOptions) of every recording."""
    from agrobot.measurements.recording import ImportOptions
    from agrobot.measurements.signal_expressions import parse_signal

    def opts(signals=(), **kw):
        return ImportOptions(signals=[parse_signal(s) for s in signals], **kw)

    runs = sorted((root / "f1tenth_frictionmaps" / "DataSets").glob("DS*"))
    for ds in runs[:1] if quick else runs:
        yield f"f1tenth_frictionmaps/{ds.name}", ds, opts(F1TENTH, wheelbase=0.32)
    steps = sorted((root / "f1tenth_autokoopman_steps" / "F1tenthCar").glob("measurement_*"),
                   key=lambda p: int(p.name.split("_")[1]))
    for m in steps[:1] if quick else steps[::10]:
        yield f"f1tenth_autokoopman_steps/{m.name}", m, opts(STEPS, wheelbase=0.32, time="time.col1[s]")
    tlg = root / "isoxml_dev4ag_timelogs"
    if tlg.is_dir():
        yield "isoxml_dev4ag_timelogs (the longest TLG)", tlg, opts()
    logs = sorted((root / "nmea_gpsd_testlogs").glob("*.log"))
    for log in logs[:2] if quick else logs:
        yield f"nmea_gpsd_testlogs/{log.name}", log, opts()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    here = [d / "shared" / "realdata" for d in (ROOT.parent, ROOT.parent.parent)]
    p.add_argument("--root", type=Path, default=next((d for d in here if d.is_dir()), here[0]))
    p.add_argument("--quick", action="store_true")
    args = p.parse_args(argv)
    from agrobot.measurements.audit import describe_audit
    from agrobot.measurements.recording import import_recording

    if not args.root.is_dir():
        print(f"error: --root {args.root}: no such folder (the shared real data)", file=sys.stderr)
        return 2
    summary = []
    for name, path, options in recordings(args.root, args.quick):
        start = time.perf_counter()
        print(f"== {name}")
        try:
            frame, report = import_recording(path, options)
        except Exception as exc:          # noqa: BLE001 - the table reports what failed
            print(f"  refused: {exc}")
            summary.append((name, "refused", str(exc)[:80], f"{time.perf_counter() - start:.1f}"))
            continue
        print("\n".join(describe_audit(report["audit"])))
        kinds = [f["kind"] + ("" if f["resolved"] else "!") for f in report["audit"]["findings"]]
        summary.append((name, f"{report['used']['duration']:.0f} s", ", ".join(sorted(set(kinds))) or "-",
                        f"{time.perf_counter() - start:.1f}"))
    print("\n| recording | log | findings (! unresolved) | s |\n|---|---|---|---|")
    for row in summary:
        print("| " + " | ".join(row) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
