"""The sweep bar's estimate of the time left (orchestrator.sweep._progress) when the points arrive in
batches, as the compiled engine's do: 400 points in batches of 25, one batch every 5.8 s (a 93 s
sweep), read on a clock the test sets. The truth is the time the remaining batches take."""
from __future__ import annotations

import io

from agrobot.orchestrator.sweep import _progress


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _left(bar) -> float:
    """Seconds left as the bar prints them (its rate, or the rate so far when it has none)."""
    d = bar.format_dict
    rate = d["rate"] or (d["n"] - d["initial"]) / d["elapsed"]
    return (d["total"] - d["n"]) / rate


def test_estimate_after_each_batch_is_the_time_the_remaining_batches_take():
    clock, batches, size, wait = Clock(), 16, 25, 5.8
    bar = _progress(batches * size, 0, True, file=io.StringIO())
    bar._time = clock                       # tqdm reads its clock through this attribute
    bar.start_t = bar.last_print_t = 0.0
    for done in range(1, batches):
        clock.now += wait
        for _ in range(size):               # a batch's points are stored one after the other
            clock.now += 1e-5
            bar.update(1)
        truth = (batches - done) * wait
        assert abs(_left(bar) - truth) <= 0.05 * truth, (done, _left(bar), truth)
    bar.close()


def test_estimate_of_a_resumed_sweep_counts_only_the_points_run_this_time():
    clock = Clock()
    bar = _progress(100, 60, True, file=io.StringIO())         # 60 points done by an earlier run
    bar._time = clock
    bar.start_t = bar.last_print_t = 0.0
    for _ in range(10):
        clock.now += 2.0
        bar.update(1)
    assert abs(_left(bar) - 30 * 2.0) <= 1.0, _left(bar)
    bar.close()
