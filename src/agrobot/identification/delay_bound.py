"""A delay that ends on its zero bound is not concluded: it is searched again below zero, down to
DELAY_LIMIT, and judged there.

A delay is never negative, but a fit of the yaw on an input read from another clock is: the yaw
stamped before the input that causes it is a clock offset between the two channels (their clocks
are not to be trusted), not a delay. So, after the widened fit, with the 95 % interval [lo, hi]:

* hi < 0: a clock offset of ``value`` s, said so (align the channels and identify again);
* lo < 0 <= hi: not told apart from no delay: the delay is below hi;
* on DELAY_LIMIT still: cannot decide (the input and the yaw do not line up within that);
* lo >= 0: a delay, as any other;
* and whatever the interval, cannot decide when parameters that shape the response (a cornering
  stiffness, a steering gain) sit on their bounds: the delay then only makes up for them.

A delay below zero beside a steering lag T > 0 trades against it (over the response's band a lead
and a first-order lag of about the same size cancel: e^(-s tau) / (1 + s T) ~ 1 - s (tau + T)), so
it is judged on the net delay tau + T (traded_verdict): below zero with its whole interval, a clock
offset of tau + T; else no clock offset, the delay stays on its bound 0 s and is at most the net's
upper limit.
"""
from __future__ import annotations

import math

DELAY_LIMIT = (-1.0, 0.5)      # s: how far the delay is searched when it ends on its zero bound
WIDENED = (f"ended on its bound 0 s and was searched again down to {DELAY_LIMIT[0]:g} s (a negative delay is a "
           f"clock offset between the input's and the yaw's channels)")


def delay_verdict(q: dict, shaping_on_bound: list[str] = ()) -> dict:
    """The delay's quantity after the widened fit (value, std, interval, unit), judged as the
    module says (``shaping_on_bound``: the names of the response's parameters on a bound): adds
    ``verdict``, ``identifiable`` and a ``note``."""
    lo, hi = q["interval"]
    out = {**q, "widened": WIDENED}
    if shaping_on_bound:
        return {**out, "verdict": "cannot decide: on its bound", "identifiable": False, "value": float("nan"),
                "on_bound": 0.0, "searched_below_zero": q["value"],
                "note": f"cannot decide: on its bound 0 s; searched below zero it goes to {q['value']:.3g} s "
                        f"[{lo:.3g}, {hi:.3g}], but {', '.join(shaping_on_bound)} {'sits' if len(shaping_on_bound) == 1 else 'sit'} on "
                        f"{'its bound' if len(shaping_on_bound) == 1 else 'their bounds'}: the delay "
                        f"only makes up for a response the model does not pin down (drive more, or in a wider "
                        f"range of speeds and turns)"}
    if not math.isfinite(q["std"]) or abs(q["value"] - DELAY_LIMIT[0]) < 5e-3:
        return {**out, "verdict": "cannot decide: on its bound", "identifiable": False, "value": float("nan"),
                "on_bound": q["value"], "note": f"cannot decide: on its bound {q['value']:.3g} s after it {WIDENED}: "
                f"the input and the yaw do not line up within {-DELAY_LIMIT[0]:g} s"}
    if hi < 0:
        return {**out, "verdict": "clock offset", "identifiable": False, "clock_offset": q["value"],
                "note": f"not a delay: the yaw answers {-q['value']:.3g} s [{-hi:.3g}, {-lo:.3g}] before its input, "
                        f"a clock offset between the input's and the yaw's channels (their clocks are not to be "
                        f"trusted); move them with convert --align GROUP=SECONDS and identify again"}
    if lo < 0:
        return {**out, "verdict": "below its upper limit", "identifiable": False, "upper_limit": hi,
                "note": f"not told apart from no delay: its 95 % interval [{lo:.3g}, {hi:.3g}] s reaches below zero; "
                        f"the delay is at most {hi:.3g} s"}
    return {**out, "verdict": "delay", "identifiable": True}


def traded_verdict(q: dict, on_bound: dict, lag: float, net: float, net_std: float) -> dict:
    """The widened delay ``q`` (below zero beside the lag ``lag`` > 0) judged on the net delay
    ``net`` = tau + T (std ``net_std``), as the module says; ``on_bound``: the delay's quantity on
    its bound 0 s, what stands when no clock offset is found."""
    lo, hi = net - 1.96 * net_std, net + 1.96 * net_std
    traded = (f"searched below zero the delay goes to {q['value']:.3g} s beside a lag of {lag:.3g} s: they trade, "
              f"the net delay tau + T is {net:.3g} [{lo:.3g}, {hi:.3g}] s")
    if hi < 0:
        out = delay_verdict({**q, "value": net, "std": net_std, "interval": [lo, hi]})
        return {**out, "net_delay": net, "note": f"{traded}; {out['note']}"}
    return {**on_bound, "value": 0.0, "std": net_std, "interval": [0.0, max(hi, 0.0)], "widened": WIDENED, "verdict": "below its upper limit", "identifiable": False,
            "upper_limit": max(hi, 0.0), "net_delay": net, "searched_below_zero": q["value"],
            "note": f"{traded}, not below zero: no clock offset; the delay stays on its bound 0 s beside the lag and is "
                    f"at most {max(hi, 0.0):.3g} s"}
