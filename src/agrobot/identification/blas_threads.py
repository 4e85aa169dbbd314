"""The BLAS libraries on one thread while a log is identified or diagnosed (threadpoolctl), as the
engine runs a study (orchestrator.engine): the fits' matrices are a few columns wide, and on a busy
machine a BLAS thread pool spends more waking its threads than computing (the 2-norm of 30,000
samples: 11 ms instead of 5 us at load 16). The diagnosis's worker processes limit theirs too."""
from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def one_blas_thread(function):
    """``function`` run with the BLAS libraries limited to one thread (restored on return)."""
    @functools.wraps(function)
    def limited(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return function(*args, **kwargs)
    return limited
