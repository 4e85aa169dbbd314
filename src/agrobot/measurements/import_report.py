"""The import report as a person reads it: a few lines for the terminal."""
from __future__ import annotations

import math

from .audit import describe_audit


def describe(report: dict) -> str:
    """A few lines for the terminal: files, clocks, gaps, runs, what was used, what is missing."""
    files = report["files"]
    parts = [f"{len(v)} {k} file(s)" for k, v in files.items() if v]
    lines = [f"recording {report['source']}: {', '.join(parts) or 'no files'}"
             + (f", DBC {report['dbc']}" if report.get("dbc") else "")]
    if report.get("wheelbase"):
        lines.append(f"  wheelbase {report['wheelbase']['value']:.3g} m ({report['wheelbase']['from']}): recorded for "
                     f"identify and diagnose on the converted log")
    if report.get("steering_ratio"):
        lines.append(f"  {report['steering_ratio']['text']}")
    c = report.get("clocks", {})
    if "nmea_host_clock" in c:
        h = c["nmea_host_clock"]
        lat = h["nmea_latency_s"]
        lines.append(f"  host clock - GPS time: {h['offset_s']:+.4f} s, drift {h['drift_ppm']:+.1f} ppm; NMEA latency "
                     f"median {1e3 * lat['median']:.1f} ms, 95% {1e3 * lat['p95']:.1f} ms, max {1e3 * lat['max']:.1f} ms")
    if "can_clock" in c:
        k = c["can_clock"]
        lines.append(f"  CAN clock: {k['method']}; offset {k['offset_s']:+.4f} s, drift {k['drift_ppm']:+.1f} ppm")
    elif c.get("reference"):
        lines.append(f"  time base: {c['reference']}")
    g = report["gaps"]
    lines.append(f"  gaps: {len(g)}" + (": " + ", ".join(f"{x['stream']} {x['start']:.2f}-{x['end']:.2f} s"
                                                         for x in g[:4]) + (" ..." if len(g) > 4 else "") if g else ""))
    lines.append("  runs: " + (", ".join(f"{r['run']}: {r['start']:.1f}-{r['end']:.1f} s"
                                          + (f" ({r['mean_speed']:.2f} m/s)" if math.isfinite(r["mean_speed"]) else "")
                                          for r in report["runs"][:8]) or "none")
                 + (f" ... ({len(report['runs'])} runs)" if len(report["runs"]) > 8 else ""))
    u = report["used"]
    lines.append(f"  used: {u['how']}, {u['start']:.2f}-{u['end']:.2f} s after the start ({u['utc_start']}), "
                 f"{u['duration']:.1f} s at {report['rate_hz']:g} Hz")
    lines.append(f"  columns: {', '.join(report.get('present', []))}")
    load = report.get("dbc_load") or {}
    if load.get("repairs") or load.get("messages_left_out"):
        left = load.get("messages_left_out", {})
        lines.append(f"  DBC: {load['loader']}; " + ", ".join(f"{k} ({v})" for k, v in load.get("repairs", {}).items())
                     + (f"; left out: {', '.join(list(left)[:6])}{' ...' if len(left) > 6 else ''}" if left else ""))
    outside = report.get("can", {}).get("outside_declared_range", {})
    for name, o in list(outside.items())[:6]:
        lines.append(f"  plausibility: {name}: {o['outside']} of {o['of']} values outside the DBC's declared "
                     f"[{o['declared'][0]:g}|{o['declared'][1]:g}] (seen {o['seen'][0]:.4g} to {o['seen'][1]:.4g}; kept)")
    for split in report.get("splits", []):
        lines.append(f"  split: {split}")
    for quirk in report.get("quirks", []):
        lines.append(f"  quirk: {quirk}")
    for note in report.get("notes", []):
        lines.append(f"  note: {note}")
    for column, why in report.get("missing", {}).items():
        lines.append(f"  missing {column}: {why}")
    if report.get("audit"):
        lines += describe_audit(report["audit"])
    return "\n".join(lines)
