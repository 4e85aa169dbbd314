"""The engine's work at one instant, for one set of due components, as straight-line Python.

A due set (orchestrator.schedule) becomes three functions made once per run and set, each a
sequence of plain statements with the components' dictionaries, step methods and steps bound as
names (no loop over connection tuples at every base step):

    publish_and_step(t, k):  if k: P[c] = dict(c.y) for the continuous components slower than the
                             base step; for each sampled one, in dependency order: u[i] = P[src][o]
                             for each of its inputs, step(t, dt), P[name] = y
    actuate(t):              u[i] = P[src][o], actuate(t) for the hardware adapters (None: none due)
    integrate(t):            u[i] = P[src][o] for every continuous and advancing input, then every
                             continuous step(t, dt), then every advance(t, dt)

``P`` is the engine's table of published outputs (``Simulation.published``). The statements are
those of the master algorithm (orchestrator.engine), in its order, so a run is the same to the bit.
"""
from __future__ import annotations

from typing import Any, Callable


class _Names:
    """The names a generated function binds, one per object it reaches."""

    def __init__(self, published: dict) -> None:
        self.space: dict[str, Any] = {"P": published, "dict": dict}
        self._ids: dict[int, str] = {}

    def __call__(self, obj: Any, prefix: str) -> str:
        name = self._ids.get(id(obj))
        if name is None:
            name = self._ids[id(obj)] = f"{prefix}{len(self._ids)}"
            self.space[name] = obj
        return name


def _pulls(names: _Names, node) -> list[str]:
    u = names(node.component.u, "u")
    return [f"    {u}[{inp!r}] = P[{src.name!r}][{out!r}]" for inp, src, out in node.sources]


def _function(names: _Names, title: str, args: str, body: list[str]) -> Callable:
    source = f"def {title}({args}):\n" + ("\n".join(body) if body else "    pass") + "\n"
    exec(compile(source, f"<instant {title}>", "exec"), names.space)       # noqa: S102 - our own statements
    return names.space[title]


def instant_functions(nodes: list, sampled: set[str], published: dict) -> tuple[Callable, Callable | None, Callable]:
    """(publish_and_step, actuate or None, integrate) for the nodes due at one phase (sampled ones
    in dependency order, then continuous ones)."""
    names = _Names(published)
    s_nodes = [nd for nd in nodes if nd.name in sampled]
    c_nodes = [nd for nd in nodes if nd.name not in sampled]
    slow = [nd for nd in c_nodes if nd.ratio != 1]
    head = ["    if k:"] + [f"        P[{nd.name!r}] = dict({names(nd.component, 'c')}.y)" for nd in slow] if slow else []
    for nd in s_nodes:
        comp = names(nd.component, "c")
        head += _pulls(names, nd) + [f"    {names(nd.component.step, 's')}(t, {names(nd.step, 'd')})",
                                     f"    P[{nd.name!r}] = {comp}.y"]
    actuated = [nd for nd in s_nodes if nd.component.actuate is not None]
    act = [line for nd in actuated for line in _pulls(names, nd) + [f"    {names(nd.component.actuate, 'a')}(t)"]]
    advancing = [nd for nd in s_nodes if nd.component.advance is not None]
    tail = [line for nd in c_nodes + advancing for line in _pulls(names, nd)]
    tail += [f"    {names(nd.component.step, 's')}(t, {names(nd.step, 'd')})" for nd in c_nodes]
    tail += [f"    {names(nd.component.advance, 'v')}(t, {names(nd.step, 'd')})" for nd in advancing]
    return (_function(names, "publish_and_step", "t, k", head),
            _function(names, "actuate", "t", act) if actuated else None,
            _function(names, "integrate", "t", tail))
