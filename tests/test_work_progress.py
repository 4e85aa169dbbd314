"""A counted stage says what it does, how far it is and about what remains (orchestrator.work_progress)."""
import re

from agrobot.orchestrator.work_progress import Work


def test_a_counted_stage_tells_its_fraction_and_what_remains():
    lines = []
    with Work(lines.append, "fitting the candidate effects", 4, "fits", every=0.0) as work:
        work.step()
        work.step()
        work.more(4)               # a further round: 8 in all
        work.step()
    assert lines[0] == "fitting the candidate effects: 4 fits"
    assert re.match(r"fitting the candidate effects: 1 of 4 fits \(25%\), \d+ s so far, about \d+ s left", lines[1])
    assert "2 of 4 fits (50%)" in lines[2]
    assert "3 of 8 fits (38%)" in lines[3]           # the total grown by more(4)
    assert re.match(r"fitting the candidate effects: 3 fits done in \d+ s$", lines[-1])


def test_the_estimate_is_the_rate_so_far_times_what_remains(monkeypatch):
    import agrobot.orchestrator.work_progress as wp

    clock = iter([0.0, 0.0, 10.0, 10.0, 10.0])      # made at 0; one of four done after 10 s
    monkeypatch.setattr(wp.time, "perf_counter", lambda: next(clock))
    work = Work(None, "replaying", 4, "stages")
    work.__enter__()
    work.done = 1
    assert work.line() == "replaying: 1 of 4 stages (25%), 10 s so far, about 30 s left"
