"""Does the import audit name what it has not seen?
``python3 benchmarks/quirk_composition.py [--n 300] [--seed 5400] [--classes a b ...] [--clean N] [--misses]``.

Random compositions of quirk classes (harness.quirk_recordings: each a seeded, compatible subset
of 1-4 classes planted on a 90 s recording of a mower, a utility vehicle or a tractor, as one CSV,
one CSV per device, or a dual-antenna receiver's NMEA) are converted as a user converts them (agrobot.api.convert, default
options; the --signal mapping a user gives where a class needs one), and so are ``--clean``
recordings with no quirk. Per class the table prints: planted, named with the right number,
missed (an import that refuses counts as missed, its first words printed), and invented: how
many clean recordings the audit claims the class on.

Named, per class, and its tolerance (the audit's findings are read as measurements.audit emits
them: kind, channels, value, interval, meaning; the import's notes and log as convert returns them):

- reversing_unsigned: a finding whose kind says reversing, direction or sign, holding each
  stretch where the truth's speed is negative, both ends within 1.0 s;
- held_channel: a finding (kind: held, update) or a channel row (update_hz) for the channel giving
  its update rate within 10 % (or the hold factor);
- one_clock_weak: nothing realigned and no unresolved clock_offset or response_leads_input;
- units_row: the log's angles, rates and speed in SI: each the truth's times a scale within 3 % of 1
  (least squares through the origin at the log's times, moved by the lag within +-1 s that fits
  best; a mislabelled channel left out: it holds another quantity);
- quoted_rows: the import reads every file and the log's speed within 3 % as above;
- fix_quality_drop: a ``fix_quality`` column equal to the source's code on 95 % of the log's
  samples (the source's own times), or a finding naming each stretch within 1.0 s;
- mode_stretches: a finding (kind: mode, manual) naming the manual and the paused stretch within 1.0 s;
- heading_no_gyro: the import does not refuse, and the log's ``heading`` follows the truth's
  (median error under 2 deg where it is written, on at least 95 % of the log outside the heading's
  own planted silences, ENU or compass convention);
- clock_offset, leap_seconds: a clock_offset finding on the group's channels, or the alignment's
  found offset, within 0.05 s (leap seconds: 0.1 s) of the truth, either sign convention; or one
  reported "too weak to judge" (not acted on) whose interval holds the truth: honestly undecided,
  counted as named and shown apart ("of which too weak");
- gps_week_rollover: a finding or note giving 1024 weeks (619315200 s within a day);
- channel_dropouts: a gap finding on the channel whose longest gap is within 1.5 row periods of
  the truth's;
- raw_units: a finding on the channel giving the factor (57.3 or 3.6) within 3 %, or the log's
  channel in SI within 3 %;
- two_yaw_sources: a finding on both gyros giving the scale (or its inverse) within 0.02;
- mislabelled_channel: a mislabelled_channel finding on the channel;
- duplicate_stamps: a note or finding of the file giving the count of repeated stamps (those it
  holds readable: an NMEA copy or original with a bad checksum repeats none);
- out_of_order: a note or finding of the file giving the count of rows out of order (from the
  rows moved to every step back written);
- clock_jump: a finding giving the step within 0.05 s and its moment within 1.0 s;
- nmea_checksum: a note giving the count of sentences with a bad checksum;
- decimal_commas: every file read, a note of each naming the count of its columns written with a
  decimal comma;
- two_talkers: a note naming the two talkers and the count of epochs both gave (readable), and the
  log's track the combined (GN) solution's: the median size of its positions' second differences
  less the truth's (on their updates, where they are held) under 0.1 m.

A refusal is a miss, except for raw_units when the refusal names the channel and the factor.

Invented: on a clean recording, the class's claim (the same finding kinds, or for one_clock_weak and
clock_offset a realignment or an unresolved clock finding; for heading_no_gyro a heading the source
does not hold; for fix_quality_drop also a log whose fix_quality differs from the source's RTK fixed 4
on 5 % of its samples: a value the recording did not say). Targets: named >= 95 %,
invented <= 5 %.
"""
from __future__ import annotations

import argparse
import math
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))          # the test harness (harness/), beside the package

from agrobot.api import convert                                   # noqa: E402
from agrobot.measurements.modes import stretches, unexplained_mask  # noqa: E402
from agrobot.measurements.signal_expressions import parse_signal  # noqa: E402
from harness.quirk_recordings import ORDER, START, WEEK_ROLLOVER, compose       # noqa: E402

GROUP_CHANNELS = {"imu": {"yaw_rate"}, "vehicle": {"delta_cmd", "delta", "v"}, "gnss": {"gnss", "x", "y", "gnss_speed",
                                                                                      "course_rate", "lat", "lon"}}
NUMBER = re.compile(r"(?<![\d.])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")     # "17.8-25.0 s": two numbers, not -25


def run(seed: int, folder: Path, classes, among=None) -> dict:
    """Compose (``classes``, or drawn ``among`` some), convert; {truth, ok, error, findings,
    channels, alignment, notes, log, report}."""
    truth = compose(seed, folder, classes=classes, among=among, added=True)
    out = {"truth": truth, "ok": False, "error": "", "findings": [], "channels": [], "alignment": {}, "notes": [],
           "log": None, "report": {}}
    signals = [parse_signal(s) for s in truth["signals"] or []]
    try:
        rec = convert(folder, signals=signals)
    except Exception as exc:         # noqa: BLE001 - a refusal is a miss, printed
        out["error"] = f"{type(exc).__name__}: {exc}"
        if "--sign-speed" not in out["error"]:
            return out
        out["refusal"] = out["error"]          # the remedy it names, applied as a user would
        try:
            rec = convert(folder, signals=signals, sign_speed=True)
        except Exception as again:   # noqa: BLE001
            out["error"] = f"{type(again).__name__}: {again}"
            return out
        out["error"] = ""
    audit = rec.report.get("audit", {})
    out.update(ok=True, findings=audit.get("findings", []), channels=audit.get("channels", []),
               alignment=audit.get("alignment", {}), notes=rec.report.get("notes", []), log=rec.log, report=rec.report)
    return out


# --- reading the audit -----------------------------------------------------------------------------------
def numbers(x) -> list[float]:
    """Every number in a finding (its values, intervals, lists, and the numbers in its text)."""
    if isinstance(x, bool) or x is None:
        return []
    if isinstance(x, (int, float)):
        return [float(x)] if math.isfinite(x) else []
    if isinstance(x, str):
        return [float(n) for n in NUMBER.findall(x)]
    if isinstance(x, dict):
        return [n for v in x.values() for n in numbers(v)]
    if isinstance(x, (list, tuple)):
        return [n for v in x for n in numbers(v)]
    return []


def of_kind(res: dict, *words) -> list[dict]:
    return [f for f in res["findings"] if any(w in f["kind"] for w in words)]


def naming(findings: list[dict], channels) -> list[dict]:
    """The findings that name one of ``channels`` (a row's 'a, b' names split)."""
    want = set(channels)
    return [f for f in findings if want & {n.strip() for c in f["channels"] for n in str(c).split(",")}]


def near(values, target: float, tol: float) -> bool:
    return any(abs(v - target) <= tol for v in values)


def covers(values, stretches, tol: float) -> bool:
    """Each [start, end] has both ends among ``values`` within ``tol``."""
    return all(near(values, a, tol) and near(values, b, tol) for a, b in stretches)


def log_truth_times(res: dict) -> np.ndarray:
    """The log's samples on the truth's clock (s from the recording's start; a receiver's dates
    1024 weeks early, named and not moved where its file is alone, taken back onto it)."""
    late = res["report"].get("used", {}).get("utc_start_s", START) - START
    return late - round(late / WEEK_ROLLOVER) * WEEK_ROLLOVER + res["log"]["t"].to_numpy(float)


def p90_ratio(res: dict, column: str, truth_column: str, absolute: bool = False) -> float:
    """p90(|log column|) / p90(|truth|) at the log's times (nan without the column)."""
    log = res["log"]
    if log is None or column not in log:
        return math.nan
    x = np.abs(log[column].to_numpy(float))
    y = np.abs(res["truth"]["drive"].at(truth_column, log_truth_times(res)))
    return float(np.percentile(x, 90) / max(np.percentile(y, 90), 1e-12))


# --- per class: named (with the truth) and claimed (on a clean recording) --------------------------------
REVERSING = ("revers", "direction", "sign")
HELD = ("held", "update")
GAPS = ("gap_bridged", "gap_split")
CLOCK = ("clock_offset",)


def named_reversing(res, t) -> bool:
    """A finding, or the refusal whose remedy was applied, names every reversing stretch."""
    said = [numbers(f) for f in of_kind(res, *REVERSING)] + [numbers(res.get("refusal", ""))]
    return any(covers(n, t["stretches"], 1.0) for n in said)


def named_held(res, t) -> bool:
    names = {"position": {"gnss", "x", "y", "lat", "lon"}}.get(t["channel"], {t["channel"]})
    targets = (t["update_hz"], 1.0 / t["update_hz"], float(t["factor"]))
    found = [n for f in naming(of_kind(res, *HELD), names) for n in numbers(f)]
    found += [v for r in res["channels"] if names & {n.strip() for n in r["channel"].split(",")}
              for k, v in r.items() if "update" in k and isinstance(v, (int, float))]
    return any(near(found, x, 0.1 * x) for x in targets)


def realigned(res) -> bool:
    moved = bool(res["alignment"].get("offsets_s"))
    return moved or any(not f["resolved"] for f in of_kind(res, "clock_offset", "response_leads_input"))


def named_one_clock(res, t) -> bool:
    return res["ok"] and not realigned(res)


def scale_to_truth(res: dict, column: str) -> float:
    """The log's column as the truth's times a scale: least squares through the origin, the truth
    taken at the log's times moved by the lag within +-1 s that fits best (another class's clock
    offset left unaligned is not a unit; noise it adds to the log does not bias the scale, as it
    biases a percentile)."""
    x = res["log"][column].to_numpy(float)
    t = log_truth_times(res)
    best = (-1.0, math.nan)
    for lag in np.arange(-1.0, 1.0001, 0.02):
        y = res["truth"]["drive"].at(column, t + lag)
        ok = np.isfinite(x) & np.isfinite(y)
        fit = np.corrcoef(x[ok], y[ok])[0, 1] if ok.sum() > 10 else -1.0
        if fit > best[0]:
            best = (fit, float(x[ok] @ y[ok] / max(y[ok] @ y[ok], 1e-12)))
    return best[1]


def named_units(res, t) -> bool:
    if not res["ok"]:
        return False
    other = res["truth"]["planted"].get("mislabelled_channel", {}).get("channel")   # holds another quantity
    ratios = [scale_to_truth(res, c) for c in ("delta", "yaw_rate", "v")
              if c in t["units"] and c != other and res["log"] is not None and c in res["log"]]
    return bool(ratios) and all(abs(r - 1) <= 0.03 for r in ratios)


def named_quoted(res, t) -> bool:
    if not res["ok"]:
        return False
    return "v" not in res["log"] or abs(p90_ratio(res, "v", "v") - 1) <= 0.03 or "reversing_unsigned" in res["truth"]["planted"]


def named_fix(res, t) -> bool:
    if any(covers(numbers(f), [s[:2] for s in t["stretches"]], 1.0) for f in of_kind(res, "fix", "quality")):
        return True
    if not res["ok"] or "fix_quality" not in res["log"]:
        return False
    times = log_truth_times(res)
    want = np.full(len(times), 4.0)
    for a, b, code in t["stretches"]:
        want[(times >= a) & (times < b)] = code
    return float(np.mean(res["log"]["fix_quality"].to_numpy(float) == want)) >= 0.95


def named_modes(res, t) -> bool:
    """The hand-driven stretches found where identify and diagnose read the log (measurements.modes:
    the command does not explain the steering there); a paused stretch drives nothing to explain."""
    if any(covers(numbers(f), t["manual"] + t["paused"], 1.0) for f in of_kind(res, "mode", "manual")):
        return True
    if not res["ok"] or not {"delta", "delta_cmd"} <= set(res["log"].columns):
        return False
    found, _ = unexplained_mask(res["log"])
    at = log_truth_times(res)
    return bool(t["manual"]) and covers([x for a, b in stretches(found, at) for x in (a, b)], t["manual"], 1.0)


def heading_error(res) -> float:
    """Median |log heading - truth| [deg] where the log has one (inf unless on 95 % of its samples
    outside the heading's own planted silences, where nothing is written: beyond the heading's first
    and last update it is not written either), the better of the ENU and the compass convention."""
    if not res["ok"] or "heading" not in res["log"]:
        return math.inf
    h = res["log"]["heading"].to_numpy(float)
    ok = np.isfinite(h)
    times = log_truth_times(res)
    silent = np.zeros(len(h), bool)
    drop = res["truth"]["planted"].get("channel_dropouts", {})
    for a, b in drop.get("gaps", []) if drop.get("channel") == "heading" else []:
        silent |= (times >= a - 0.15) & (times <= b + 0.15)      # the gap and a fix either side
    if ok[~silent].mean() < 0.95:
        return math.inf
    psi = res["truth"]["drive"].at("psi", times)[ok]
    return min(float(np.median(np.degrees(np.abs(np.angle(np.exp(1j * (h[ok] - ref))))))) for ref in (psi, math.pi / 2 - psi))


def named_heading(res, t) -> bool:
    return heading_error(res) < 2.0


def named_offset(tol: float):
    def judge(res, t) -> bool:
        chans = GROUP_CHANNELS[t["group"]]
        found = [abs(f["value"]) for f in naming(of_kind(res, *CLOCK), chans)]
        found += [abs(o["late_s"]) for g, o in res["alignment"].get("found", {}).items() if g == t["group"]]
        return near(found, abs(t["late_s"]), tol) or (t.get("weak", True) and too_weak(res, t))
    return judge


def too_weak(res, t) -> bool:
    """The offset reported "too weak to judge" (not acted on) on the group's channels, its interval
    holding the truth (either sign convention): honestly undecided, not wrong."""
    return any(f["interval"] is not None and "too weak to judge" in f["meaning"]
               and any(f["interval"][0] <= x <= f["interval"][1] for x in (t["late_s"], -t["late_s"]))
               for f in naming(of_kind(res, *CLOCK), GROUP_CHANNELS[t["group"]]))


def named_rollover(res, t) -> bool:
    values = [abs(n) for f in res["findings"] for n in numbers(f)] + [abs(n) for s in res["notes"] for n in numbers(s)]
    return near(values, abs(t["late_s"]), 86400.0) or any("1024" in str(x) and "week" in str(x).lower()
                                                         for x in res["findings"] + res["notes"])


def named_dropouts(res, t) -> bool:
    rate = {"log": 20.0, "gnss": 10.0, "imu": 50.0, "vehicle": 20.0}[t["file"]]
    return any(near([f["value"]], t["longest_s"], 1.5 / rate) for f in naming(of_kind(res, *GAPS), {t["channel"]}))


def named_raw_units(res, t) -> bool:
    k = t["factor"]
    if not res["ok"] and t["channel"] in res["error"] and near(numbers(res["error"]), k, 0.03 * k):
        return True             # refused, naming the channel and the factor
    if any(near(numbers(f), k, 0.03 * k) or near(numbers(f), 1 / k, 0.03 / k) for f in naming(res["findings"], {t["channel"]})):
        return True
    return res["ok"] and abs(p90_ratio(res, t["channel"], t["channel"]) - 1) <= 0.03


def named_two_gyros(res, t) -> bool:
    s = t["scale"]
    found = [f for f in of_kind(res, "ambiguous_channel", "scale_disagreement")
             if {"yaw_rate", "yaw_rate_2"} <= set(f["channels"])]
    return any(near([f["value"]], s, 0.02) or near([f["value"]], 1 / s, 0.02) for f in found)


def named_mislabel(res, t) -> bool:
    return bool(naming(of_kind(res, "mislabelled"), {t["channel"]}))


def file_notes(res, t, *words) -> list:
    tags = [s for s in res["notes"] if str(s).startswith(f"{t['file']}.") and any(w in str(s) for w in words)]
    return tags + [f for f in res["findings"] if any(w in f["kind"] or w in f["meaning"] for w in words)]


def named_duplicates(res, t) -> bool:
    """The count of repeated stamps the file holds readable (an NMEA copy with a corrupt checksum repeats none)."""
    return any(near(numbers(x), t.get("readable", t["count"]), 0.0) for x in file_notes(res, t, "repeat", "duplicate"))


def named_order(res, t) -> bool:
    most = res["truth"]["written"][t["file"]]["step_backs"]
    return any(any(t["count"] <= n <= most for n in numbers(x)) for x in file_notes(res, t, "order", "step back"))


def named_jump(res, t) -> bool:
    return any(near([abs(n) for n in numbers(f)], abs(t["by_s"]), 0.05) and near(numbers(f), t["at_s"], 1.0)
               for f in of_kind(res, "jump", "step", "clock"))


def named_checksum(res, t) -> bool:
    return any(near(numbers(x), t["count"], 0.0) for x in res["notes"] if "checksum" in str(x))


def named_decimal_commas(res, t) -> bool:
    """Every file read, each named with the count of its columns written with a decimal comma."""
    if not res["ok"]:
        return False
    notes = [x for x in res["notes"] if "decimal comma" in str(x)]
    return all(any(str(x).startswith(f"{f}.csv") and near(numbers(str(x).split("in ", 1)[-1]), k, 0.0) for x in notes)
               for f, k in t["columns"].items())


def named_two_talkers(res, t) -> bool:
    """A note naming the two talkers and the epochs both gave, and the log's track the combined
    solution's (the median size of its positions' second differences under 0.1 m: the GPS-only
    one's 0.3-0.8 m noise is not in it)."""
    said = [x for x in res["notes"] if "two talkers" in str(x)]
    if not res["ok"] or not any(near(numbers(str(x).split(" on ", 1)[-1]), t["readable"], 0.0) for x in said):
        return False
    xy = res["log"][["x", "y"]].to_numpy(float)
    new = np.r_[True, np.any(np.diff(xy, axis=0) != 0, axis=1)]          # the updates of held positions
    at, drive = log_truth_times(res)[new], res["truth"]["drive"]
    truth = np.column_stack([drive.at("east", at), drive.at("north", at)])
    return float(np.nanmedian(np.hypot(*(np.diff(xy[new], 2, axis=0) - np.diff(truth, 2, axis=0)).T))) < 0.1


def _mentions(res, *words) -> bool:
    return any(any(w in str(x).lower() for w in words) for x in res["notes"] + [f["meaning"] for f in res["findings"]])


def wrong_fix_quality(res) -> bool:
    """A clean recording is RTK fixed (4) throughout: a log that says otherwise on 5 % of its samples."""
    return res["ok"] and "fix_quality" in res["log"] and float(np.mean(res["log"]["fix_quality"] != 4.0)) > 0.05


JUDGES = {      # class: (named, claimed on a clean recording)
    "reversing_unsigned": (named_reversing, lambda r: bool(of_kind(r, *REVERSING))),
    "held_channel": (named_held, lambda r: bool(of_kind(r, *HELD))),
    "one_clock_weak": (named_one_clock, realigned),
    "units_row": (named_units, lambda r: _mentions(r, "units row", "row of units")),
    "quoted_rows": (named_quoted, lambda r: _mentions(r, "quote")),
    "decimal_commas": (named_decimal_commas, lambda r: _mentions(r, "decimal comma")),
    "fix_quality_drop": (named_fix, lambda r: bool(of_kind(r, "fix", "quality")) or wrong_fix_quality(r)),
    "mode_stretches": (named_modes, lambda r: bool(of_kind(r, "mode", "manual"))),
    "heading_no_gyro": (named_heading, lambda r: r["ok"] and "heading" in r["log"] and r["truth"]["layout"] != "nmea"),
    "clock_offset": (named_offset(0.05), realigned),
    "leap_seconds": (named_offset(0.1), lambda r: any(near([abs(f["value"])], 18.0, 1.0) for f in of_kind(r, *CLOCK))),
    "gps_week_rollover": (named_rollover, lambda r: _mentions(r, "1024 week", "rollover")),
    "channel_dropouts": (named_dropouts, lambda r: bool(of_kind(r, *GAPS))),
    "raw_units": (named_raw_units, lambda r: _mentions(r, "mix-up", "looks like degrees", "km/h")),
    "two_yaw_sources": (named_two_gyros, lambda r: bool(of_kind(r, "ambiguous_channel"))),
    "mislabelled_channel": (named_mislabel, lambda r: bool(of_kind(r, "mislabelled"))),
    "duplicate_stamps": (named_duplicates, lambda r: _mentions(r, "repeat the time", "duplicate")),
    "out_of_order": (named_order, lambda r: _mentions(r, "step back", "out of order")),
    "clock_jump": (named_jump, lambda r: bool(of_kind(r, "jump"))),
    "nmea_checksum": (named_checksum, lambda r: _mentions(r, "checksum")),
    "two_talkers": (named_two_talkers, lambda r: _mentions(r, "two talkers")),
}


def why_missed(res: dict) -> str:
    if not res["ok"]:
        return "refused: " + res["error"].split("\n")[0][:90]
    kinds = sorted({f["kind"] for f in res["findings"]})
    return "findings: " + (", ".join(kinds) or "none")


def weakly(res: dict, c: str) -> bool:
    """Named only as "too weak to judge" with the truth inside the interval (clock classes)."""
    t = res["truth"]["planted"][c]
    return c in ("clock_offset", "leap_seconds") and too_weak(res, t) and not JUDGES[c][0](res, {**t, "weak": False})


def miss_lines(rows: list[dict], clean: list[dict]) -> list[str]:
    """One line per missed planted quirk and per class claimed on a clean recording, with its seed."""
    out = [f"missed: seed {r['truth']['seed']} {c} ({r['truth']['layout']}, {'+'.join(r['truth']['classes'])}): "
           f"{why_missed(r)[:140]}" for r in rows for c in r["truth"]["planted"]
           if not JUDGES[c][0](r, r["truth"]["planted"][c])]
    return out + [f"invented: seed {r['truth']['seed']} {c} ({r['truth']['layout']})"
                  for r in clean for c, j in JUDGES.items() if j[1](r)]


def table(rows: list[dict], clean: list[dict], classes) -> list[str]:
    """The per-class table: planted, named, missed, invented on the clean recordings."""
    out = [f"| class | planted | named | of which too weak | missed | named % | invented (of {len(clean)} clean) | "
           f"invented % | a miss |", "|---|---|---|---|---|---|---|---|---|"]
    for c in classes:
        hits = [r for r in rows if c in r["truth"]["planted"]]
        named = [JUDGES[c][0](r, r["truth"]["planted"][c]) for r in hits]
        claimed = sum(bool(JUDGES[c][1](r)) for r in clean)
        miss = next((why_missed(r) for r, ok in zip(hits, named) if not ok), "")
        pct = f"{100 * sum(named) / len(hits):.0f}" if hits else "-"
        weak = sum(weakly(r, c) for r in hits)
        out.append(f"| {c} | {len(hits)} | {sum(named)} | {weak} | {len(hits) - sum(named)} | {pct} | {claimed} | "
                   f"{100 * claimed / max(len(clean), 1):.0f} | {miss[:110]} |")
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=300, help="random compositions (default 300)")
    p.add_argument("--seed", type=int, default=5400, help="the first composition's seed (default 5400)")
    p.add_argument("--clean", type=int, default=None, help="clean recordings (default n / 5, at least 20)")
    p.add_argument("--classes", nargs="+", default=None, choices=ORDER, metavar="CLASS",
                   help=f"draw compositions among these classes only ({', '.join(ORDER)})")
    p.add_argument("--misses", action="store_true",
                   help="print every miss and every claim on a clean recording with its seed")
    args = p.parse_args(argv)
    clean_n = args.clean if args.clean is not None else max(20, args.n // 5)
    started = time.perf_counter()
    rows, clean = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.n):
            rows.append(run(args.seed + k, Path(tmp) / f"q{k}", None, args.classes))
        for k in range(clean_n):
            clean.append(run(args.seed + 100_000 + k, Path(tmp) / f"c{k}", classes=[]))
    refused = sum(not r["ok"] for r in rows)
    print(f"{args.n} compositions (seeds {args.seed}..{args.seed + args.n - 1}), {clean_n} clean; "
          f"{refused} refused by the import; {time.perf_counter() - started:.0f} s")
    print("\n".join(table(rows, clean, args.classes or ORDER)))
    planted = [(c, r) for r in rows for c in r["truth"]["planted"]]
    named = sum(JUDGES[c][0](r, r["truth"]["planted"][c]) for c, r in planted)
    weak = sum(weakly(r, c) for c, r in planted)
    print(f"all planted quirks: {named}/{len(planted)} named ({100 * named / max(len(planted), 1):.1f} %; "
          f"{weak} of them too weak to judge with the truth inside the interval); "
          f"clean recordings with any claim: {sum(any(j[1](r) for j in JUDGES.values()) for r in clean)}/{len(clean)}")
    if args.misses:
        print("\n".join(miss_lines(rows, clean)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
