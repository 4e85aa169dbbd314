"""Calls between the orchestrator's modules in one run of a command, counted with cProfile.

    python benchmarks/module_calls.py -- run studies/field_coverage.toml --set field.max_swaths=2 \
        --out /tmp/module_calls --overwrite --no-plots

The command (everything after ``--``) runs in this process as ``python -m agrobot`` would
run it; afterwards every call from a function defined in one ``orchestrator/*.py`` file to a
function defined in another is summed per (caller module, callee module) pair (cProfile's caller
table: number of calls, recursion included). The table lists every pair, most calls first, and
the calls from the study description (``study*.py``, ``ssp.py``) to any module above it.
"""
from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
from collections import Counter
from pathlib import Path

ORCHESTRATOR = Path(__file__).resolve().parents[1] / "orchestrator"
DESCRIPTION = ("study", "study_schema", "study_files", "ssp")
BELOW_DESCRIPTION = ("errors", "units", "component", "fmu_description")


def module_of(filename: str) -> str | None:
    path = Path(filename)
    return path.stem if path.parent == ORCHESTRATOR and path.suffix == ".py" else None


def calls_between_modules(stats: pstats.Stats) -> Counter:
    counts: Counter = Counter()
    for (filename, _, _), (_, _, _, _, callers) in stats.stats.items():
        callee = module_of(filename)
        if callee is None:
            continue
        for (caller_file, _, _), (_, calls, _, _) in callers.items():
            caller = module_of(caller_file)
            if caller is not None and caller != callee:
                counts[(caller, callee)] += calls
    return counts


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--" not in argv:
        argparse.ArgumentParser(usage=__doc__).error("give the command after '--'")
    command = argv[argv.index("--") + 1:]
    from agrobot.orchestrator.cli import main as orchestrator_main

    profile = cProfile.Profile()
    profile.enable()
    try:
        status = orchestrator_main(command)
    finally:
        profile.disable()
    counts = calls_between_modules(pstats.Stats(profile))
    print(f"\ncommand: python -m agrobot {' '.join(command)} (exit {status})")
    print(f"{'caller module':<16} {'callee module':<16} {'calls':>9}")
    for (a, b), n in counts.most_common():
        print(f"{a:<16} {b:<16} {n:>9}")
    up = sum(n for (a, b), n in counts.items() if a in DESCRIPTION and b not in DESCRIPTION + BELOW_DESCRIPTION)
    print(f"\ncalls from the study description up to the modules above it: {up}")
    print(f"study -> build: {counts[('study', 'build')]}, build -> study: {counts[('build', 'study')]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
