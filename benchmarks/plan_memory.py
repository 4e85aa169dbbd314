"""Time and peak memory of ``plan`` on large square fields, and of the route component stepping along
a large route: one line per case.

    python3 benchmarks/plan_memory.py [--sizes 5 500 5000] [--wavy] [--limit-gb 8] [--no-follow]

Each case runs in a child process (``python -m agrobot plan SQUARE --out DIR``) whose peak
resident memory is read from ``os.wait4``; the child's address space is capped at ``--limit-gb``
(a case over it fails instead of taking the machine). The squares are GeoJSON in local metres,
planned with the default settings (3 m working width, 4 m turn radius). The ``follow`` cases
build the field route component on the square and step it along the first and the last 2 km of
the route (the vehicle put on it every 0.1 m): its memory must not grow while it follows.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

FOLLOW = r"""
import resource, sys, time
from agrobot.components.field_route import FieldRoute, to_mission
from agrobot.fields.planner.sampling import ROUTE_STEP
route = FieldRoute("field", {"path": sys.argv[1]})
t0 = time.perf_counter()
route.initialize(0.0, 0.05)
planned = time.perf_counter() - t0
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
path, window = route.path, route.route
for start in (0.0, max(0.0, path.length - 2000.0)):       # the first and the last 2 km, 0.1 m a step
    route.i_cg = route.i_impl = int(start / ROUTE_STEP)
    for k in range(1, 20000):
        s = start + k * ROUTE_STEP
        if s >= path.length - 1.0:
            break
        x, y = to_mission(path.position([s]), window.origin, window.rotation)[0]
        route.u.update(x=x, y=y, implement_x=x, implement_y=y)
        route.step(k * 0.05, 0.05)
    assert abs(route.y["path_length"] - s) < 0.2, (route.y["path_length"], s)
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(f"{planned:.1f} {rss0 / 1024:.0f} {rss1 / 1024:.0f} {path.length / 1000:.1f}")
"""


def square(folder: Path, hectares: float, wavy: bool = False) -> Path:
    """A square field of ``hectares`` as GeoJSON in local metres; ``wavy``: its east and west sides
    waving (60 m, every 700 and 900 m), so that the swaths end at other places and every turn
    differs (between straight sides the turns repeat and are solved once)."""
    side = math.sqrt(hectares * 1e4)
    if wavy:
        ys = [side * k / 399 for k in range(400)]
        ring = ([[side + 60 * math.sin(2 * math.pi * y / 700), y] for y in ys]
                + [[60 * math.sin(2 * math.pi * y / 900 + 1), y] for y in reversed(ys)])
        ring.append(ring[0])
    else:
        ring = [[0.0, 0.0], [side, 0.0], [side, side], [0.0, side], [0.0, 0.0]]
    name = f"{'wavy' if wavy else 'square'} {hectares:g} ha"
    doc = {"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"name": name},
                                                       "geometry": {"type": "Polygon", "coordinates": [ring]}}]}
    path = folder / f"{name.replace(' ', '_')}.geojson"
    path.write_text(json.dumps(doc))
    return path


def measured(cmd: list[str], limit_gb: float) -> tuple[int, float, float, float, str]:
    """(exit code, wall seconds, CPU seconds, peak RSS in MB, stdout) of a child capped at limit_gb
    of address space (the CPU time does not grow when other work shares the machine)."""
    def cap():
        limit = int(limit_gb * 2 ** 30)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out:
        child = subprocess.Popen(cmd, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, text=True, env=env,
                                 preexec_fn=cap)
        _, status, usage = os.wait4(child.pid, 0)
        child.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - t0
        out.seek(0)
        text = out.read()
    return child.returncode, wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, text


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", type=float, nargs="+", default=[5.0, 500.0, 5000.0], help="square fields [ha]")
    parser.add_argument("--limit-gb", type=float, default=8.0, help="address-space cap of each child [GiB]")
    parser.add_argument("--route-step", type=float, default=None, help="passed to plan --route-step when given")
    parser.add_argument("--no-follow", action="store_true", help="leave out the route component cases")
    parser.add_argument("--wavy", action="store_true", help="also plan fields of the same sizes with waving sides")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="plan_memory.") as tmp:
        tmp = Path(tmp)
        print(f"{'case':<28}{'exit':>5}{'wall s':>9}{'CPU s':>8}{'peak MB':>9}{'route.csv MB':>14}"
              f"{'route.geojson MB':>18}  notes")
        for ha, wavy in [(ha, False) for ha in args.sizes] + ([(ha, True) for ha in args.sizes] if args.wavy else []):
            field = square(tmp, ha, wavy)
            out = tmp / f"plan_{field.stem}"
            cmd = [sys.executable, "-m", "agrobot", "plan", str(field), "--out", str(out)]
            if args.route_step is not None:
                cmd += ["--route-step", str(args.route_step)]
            code, wall, cpu, peak, text = measured(cmd, args.limit_gb)
            sizes = [(out / name).stat().st_size / 2 ** 20 if (out / name).exists() else float("nan")
                     for name in ("route.csv", "route.geojson")]
            note = next((line.strip() for line in text.splitlines() if " swaths, " in line), text.strip()[-160:])
            print(f"{'plan ' + field.stem.replace('_', ' '):<28}{code:>5}{wall:>9.1f}{cpu:>8.1f}{peak:>9.0f}{sizes[0]:>14.1f}"
                  f"{sizes[1]:>18.1f}  {note}", flush=True)
        if not args.no_follow:
            for ha in args.sizes:
                field = square(tmp, ha)
                code, wall, cpu, peak, text = measured([sys.executable, "-c", FOLLOW, str(field)], args.limit_gb)
                parts = text.split()
                note = (f"planned in {parts[-4]} s; {parts[-1]} km of route; max RSS {parts[-3]} MB after planning, "
                        f"{parts[-2]} MB after 2 x 2 km of following") if code == 0 and len(parts) >= 4 else text.strip()[-200:]
                print(f"{'follow ' + f'{ha:g} ha square':<28}{code:>5}{wall:>9.1f}{cpu:>8.1f}{peak:>9.0f}{'':>14}{'':>18}"
                      f"  {note}", flush=True)


if __name__ == "__main__":
    main()
