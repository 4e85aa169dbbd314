"""What a run records: every numeric scalar output of every component, kept at the instants it can
change (multiples of the component's step) and held in between when the table is built; strings,
bytes and whole arrays of an FMU are exchanged between components but not recorded (array elements
are). The recorder is an observer of the engine (orchestrator.observers). Each column's unit is
the output's declared one (``units``; time in s): the DataFrame carries them in
``attrs["units"]``, the signal file in its metadata (orchestrator.atomic_files)."""
from __future__ import annotations

from dataclasses import dataclass, field
from operator import itemgetter
from typing import Any, Callable

import numpy as np
import pandas as pd

from .errors import ComputationError
from .observers import Observer


@dataclass
class RecordedSignals:
    columns: list[str]
    data: np.ndarray            # shape (n_samples, 1 + n_signals); column 0 is time
    wall_time_s: float
    completed: bool
    events: list[tuple[float, str, str]] = field(default_factory=list)   # (t, component, message)
    realtime: dict | None = None                                          # pacing statistics
    ended_by: dict | None = None          # {"component", "t", "reason"}: a component ended the run
    units: dict[str, str] = field(default_factory=dict)                  # column -> unit ("t": s)

    def to_frame(self):
        """The signals as a DataFrame, each column's unit in ``attrs["units"]``."""
        frame = pd.DataFrame(self.data, columns=["t"] + self.columns)
        frame.attrs["units"] = dict(self.units)
        return frame


def _numeric_scalar(value) -> bool:
    return isinstance(value, (int, float, np.number)) and not isinstance(value, (str, bytes))


def _single(key: str):
    return lambda d: (d[key],)


class _Buffer:
    """Outputs of one component at multiples of its ratio (base steps per step), as the Python
    numbers they are (a list takes a tuple's items in one copy; an ``array('d')`` parses each one:
    7 % of a figure-8 run), made floats when the table is asked for (np.fromiter: half the time of
    np.array, which first looks for nested sequences)."""

    __slots__ = ("name", "ratio", "width", "get", "buf")

    def __init__(self, name: str, ratio: int, outputs: list[str]) -> None:
        self.name, self.ratio, self.width = name, ratio, len(outputs)
        self.get: Callable[[dict], Any] = itemgetter(*outputs) if len(outputs) > 1 else _single(outputs[0])
        self.buf: list = []

    def fill(self, block: np.ndarray) -> None:
        """``block`` (rows, width): sample j of the buffer held over base steps j*ratio .. (j+1)*ratio - 1."""
        try:
            kept = np.fromiter(self.buf, dtype=float, count=len(self.buf)).reshape(-1, self.width)
        except (TypeError, ValueError) as exc:
            raise ComputationError(f"component {self.name!r}: an output it declares numeric held a value that is "
                                   f"not a number ({exc})") from None
        if self.ratio == 1:
            block[:] = kept[:block.shape[0]]
            return
        for j in range(self.ratio):            # every ratio-th row from j: each sample held (no repeated copy)
            rows = block[j::self.ratio]
            rows[:] = kept[:rows.shape[0]]


class SignalRecorder(Observer):
    """The signal table of a system: ``columns`` (``component.output``) and, after a run or part
    of one, ``rows(first, last)``, time first."""

    def __init__(self, system, period: int) -> None:
        outputs: dict[str, list[str]] = {}
        self.units = {"t": "s"}
        for node in system.nodes.values():
            for v in node.component.variables:
                if v.causality == "output" and _numeric_scalar(v.start):
                    outputs.setdefault(node.name, []).append(v.name)
                    self.units[f"{node.name}.{v.name}"] = v.unit
        self.columns = [f"{name}.{out}" for name, outs in outputs.items() for out in outs]
        self._layout = [(name, system.nodes[name].ratio, outs) for name, outs in outputs.items()]
        self._period = period
        self._buffers: list[_Buffer] = []
        self._published: dict = {}

    def started(self, sim) -> None:
        self._buffers = [_Buffer(name, ratio, outs) for name, ratio, outs in self._layout]
        self._published = sim.published
        self.recorded = self._keeper(self._buffers)           # the hook: one call at each base step

    def _keeper(self, buffers: list[_Buffer]):
        """``keep(phase)``: each due buffer's outputs appended, as plain statements; a buffer of
        ratio r is due when r divides ``phase`` (k modulo the engine's period, a multiple of r)."""
        space: dict = {"P": self._published}
        body = []
        for ratio in sorted({b.ratio for b in buffers}):
            indent = "    " if ratio == 1 else "        "
            if ratio != 1:
                body.append(f"    if not phase % {ratio}:")
            for i, b in enumerate(buffers):
                if b.ratio == ratio:
                    space[f"e{i}"], space[f"g{i}"] = b.buf.extend, b.get
                    body.append(f"{indent}e{i}(g{i}(P[{b.name!r}]))")
        exec(compile("def keep(phase):\n" + ("\n".join(body) or "    pass") + "\n", "<recorder>", "exec"), space)
        return space["keep"]

    def recorded(self, phase: int) -> None:
        """Append the outputs due at ``phase`` (``started`` replaces this hook by its generated form)."""
        self._keeper(self._buffers)(phase)

    def rows(self, t0: float, h: float, first: int, last: int) -> np.ndarray:
        """Time and signals of base steps ``first`` .. ``last - 1`` (``first``: where the buffers
        were last cleared)."""
        n = max(last - first, 0)
        if not n or not self._buffers:
            return np.empty((0, 1 + len(self.columns)))
        table = np.empty((n, 1 + len(self.columns)))
        table[:, 0] = t0 + (first + np.arange(n)) * h
        column = 1
        for b in self._buffers:                     # each buffer into its columns (no block of its own to join)
            b.fill(table[:, column:column + b.width])
            column += b.width
        return table

    def clear(self) -> None:
        for b in self._buffers:
            del b.buf[:]
