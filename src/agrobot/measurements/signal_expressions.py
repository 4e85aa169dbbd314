"""``--signal 'COLUMN=EXPR[unit]'``: a log column from the signals of any source, with its unit.

EXPR is a sum or difference of terms, each a signal name times or divided by numbers:

    STEER_ANGLE_SENSOR.STEER_ANGLE + STEER_ANGLE_SENSOR.STEER_FRACTION     (a DBC's Message.Signal)
    /imu/data.angular_velocity.z                                          (a ROS topic's field)
    imuData.wz, speed_kmh, "Speed (km/h)"                                 (a table's column)
    -0.5*(WHEEL_SPEEDS.WHEEL_SPEED_FL + WHEEL_SPEEDS.WHEEL_SPEED_FR), x - 100

A name may be quoted ("...") when it holds spaces or operators. ``[unit]`` is any unit pint
knows (deg, deg/s, km/h, g, 1/km) and states the unit the expression's value is in; without it
each term's own unit (a DBC's, a table header's ``[unit]``, a standard ROS message's SI) is used,
converted to SI before summing. The result goes to the column's unit: the canonical columns'
(measurements.log.COLUMNS), degrees for lat/lon, metres for x/y, SI for any other. A value with
no unit at all is never silently taken as SI for an angle, a rate or a speed: the column must
declare it. A curvature [1/m] feeds a wheel angle through the wheelbase, delta = atan(L kappa).

The expression is linear (a sum of constant multiples of signals, plus a constant): the terms are
put on the first term's time stamps by linear interpolation, within the span they share.

A term may be ``rate(NAME)``: a counter (wheel ticks, an encoder) as its rate per second. Between
samples k and k+1 the counter steps d_k = c_{k+1} - c_k; a counter stored as an integer of a fixed
width wraps at M = 2^bits (2^16 for int16 and uint16, a file's column or a ROS message's field; a DBC
signal's 2^length x scale: Series.wrap, from the source's type), and the
step is taken as the smallest one modulo M, d_k - M round(d_k / M) (a counter that moves less than
M/2 between samples); the rate r_k = d_k / (t_{k+1} - t_k), placed mid-interval at
(t_k + t_{k+1}) / 2, in the counter's unit per second (``v=rate(odometry.Ticks[0])*0.000952[m/s]``:
ticks times metres per tick). A counter without a width (a float, a text table's integers) is
differenced as it is. A counter read in rows faster than it updates (a count held for k rows would
give k - 1 rates of 0 and one of k times the true rate) is differenced over its updates, the rows
where its count changes, with one row every update period in a stand
(measurements.channel_updates.counter_updates); the rate's label says which.
"""
from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass

import numpy as np

from agrobot.orchestrator.units import base_unit

from .channel_updates import counter_updates, term_share
from .log import COLUMNS, LogError
from .streams import Series

# the dimension a column must have, beyond the canonical ones (COLUMNS)
EXTRA_TARGETS = {"lat": "deg", "lon": "deg", "height": "m", "x": "m", "y": "m", "speed_cmd": "m/s",
                 "heading": "rad", "gnss_speed": "m/s"}
ALIASES = {"g": "standard_gravity"}          # a declared [g] is an acceleration (standard gravity), not a gram
MUST_DECLARE = ("rad", "rad/s", "m/s")        # an angle, a rate, a speed: never taken as SI unannounced
_COLUMN = re.compile(r"^[a-z_][a-z0-9_]*$")
_NUMBER = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_OPERATORS = "+-*/()"


@dataclass(frozen=True)
class SignalSpec:
    """``column = sum(coef * name) + constant``, in ``unit`` when declared."""

    column: str
    terms: tuple[tuple[str, float], ...]
    constant: float = 0.0
    unit: str | None = None
    text: str = ""

    @property
    def names(self) -> list[str]:
        """The signals the expression reads (a rate(NAME) term's NAME), once each."""
        return list(dict.fromkeys(operand(n) for n, _ in self.terms))

    def __str__(self) -> str:
        return self.text or f"{self.column}=" + "+".join(f"{c:g}*{n}" for n, c in self.terms)


def parse_signal(text: str) -> SignalSpec:
    """A ``--signal`` option; a LogError says what is wrong and what was expected."""
    column, eq, rest = text.partition("=")
    column = column.strip()
    usage = (f"--signal {text!r}: expected COLUMN=EXPR[unit], e.g. yaw_rate=imuData.wz[deg/s], "
             f"delta=STEER.ANGLE+STEER.FRACTION[deg], v=/odom.twist.twist.linear.x")
    if not eq or not _COLUMN.match(column) or column == "t":
        raise LogError(f"{usage}; COLUMN is a lower-case name: {', '.join(c for c in COLUMNS if c != 't')}, lat, lon "
                       f"or another (an extra column), not t")
    rest = rest.strip()
    unit = None
    m = re.match(r"^(.*?)\[([^\[\]]*)\]\s*$", rest, re.S)
    if m and not m.group(2).strip().isdigit():
        rest, unit = m.group(1).strip(), m.group(2).strip()
        check_unit(unit, f"--signal {text!r}")
    if not rest:
        raise LogError(f"{usage}: no expression after '='")
    tokens = _tokens(rest, text)
    parser = _Parser(tokens, text)
    linear = parser.expression()
    if parser.i != len(tokens):
        raise LogError(f"--signal {text!r}: unexpected {tokens[parser.i][1]!r}; {usage[len(text) + 12:]}")
    terms = tuple((n, c) for n, c in linear.items() if n is not None and c != 0.0)
    if not terms:
        raise LogError(f"--signal {text!r}: the expression names no signal")
    return SignalSpec(column, terms, float(linear.get(None, 0.0)), unit, text)


def check_unit(unit: str, where: str):
    """The unit as orchestrator.units reads it (pint); a LogError when pint does not know it."""
    unit = ALIASES.get(unit.strip(), unit)
    try:
        found = base_unit(unit)
    except Exception:                                # noqa: BLE001 - pint raises several kinds
        found = None
    if found is None:
        raise LogError(f"{where}: unit {unit!r} is not one pint knows; expected e.g. deg, rad, deg/s, rad/s, km/h, "
                       f"m/s, g, m, 1/km")
    return found


def _tokens(text: str, whole: str) -> list[tuple[str, str]]:
    out, i = [], 0
    while i < len(text):
        ch = text[i]
        if ch.isspace():
            i += 1
        elif ch == '"':
            j = text.find('"', i + 1)
            if j < 0:
                raise LogError(f"--signal {whole!r}: a quoted name is not closed")
            out.append(("name", text[i + 1:j]))
            i = j + 1
        elif ch in _OPERATORS and not _slash_name(text, i):
            out.append(("op", ch))
            i += 1
        else:
            m = _NUMBER.match(text, i)
            if m and (m.end() == len(text) or text[m.end()] in _OPERATORS or text[m.end()].isspace()):
                out.append(("number", m.group()))
                i = m.end()
                continue
            j = i
            while j < len(text) and not text[j].isspace() and (text[j] not in _OPERATORS + '"' or _slash_name(text, j)):
                j += 1
            out.append(("name", text[i:j]))
            i = j
    return out


def _slash_name(text: str, i: int) -> bool:
    """A '/' that begins or continues a ROS name (followed by a letter), not a division."""
    return text[i] == "/" and i + 1 < len(text) and (text[i + 1].isalpha() or text[i + 1] == "_")


class _Parser:
    """expr := term (('+'|'-') term)*; term := factor (('*'|'/') factor)*;
    factor := '-' factor | number | name | '(' expr ')'. A value is {name or None: coefficient}."""

    def __init__(self, tokens, text):
        self.tokens, self.i, self.text = tokens, 0, text

    def peek(self):
        return self.tokens[self.i] if self.i < len(self.tokens) else ("end", "")

    def expression(self) -> dict:
        value = self.term()
        while self.peek() in (("op", "+"), ("op", "-")):
            sign = 1.0 if self.tokens[self.i][1] == "+" else -1.0
            self.i += 1
            for k, c in self.term().items():
                value[k] = value.get(k, 0.0) + sign * c
        return value

    def term(self) -> dict:
        value = self.factor()
        while self.peek() in (("op", "*"), ("op", "/")):
            op = self.tokens[self.i][1]
            self.i += 1
            other = self.factor()
            if op == "/" or set(value) != {None}:
                if set(other) != {None}:
                    raise LogError(f"--signal {self.text!r}: a signal can be multiplied or divided by a number only "
                                   f"(the expression must be a sum of signals times numbers)")
                k = other[None] if op == "*" else 1.0 / other[None] if other[None] != 0 else math.nan
                if not math.isfinite(k):
                    raise LogError(f"--signal {self.text!r}: division by zero")
                value = {n: c * k for n, c in value.items()}
            else:
                value = {n: c * value[None] for n, c in other.items()}
        return value

    def factor(self) -> dict:
        kind, text = self.peek()
        self.i += 1
        if (kind, text) == ("op", "-"):
            return {n: -c for n, c in self.factor().items()}
        if (kind, text) == ("op", "+"):
            return self.factor()
        if kind == "number":
            return {None: float(text)}
        if kind == "name" and text in FUNCTIONS and self.peek() == ("op", "("):
            inner, close = self.tokens[self.i + 1:self.i + 3] if self.i + 3 <= len(self.tokens) else (("end", ""),) * 2
            if inner[0] != "name" or close != ("op", ")"):
                raise LogError(f"--signal {self.text!r}: {text}(...) takes one signal name, e.g. {text}(wheel.ticks)")
            self.i += 3
            return {f"{text}({inner[1]})": 1.0}
        if kind == "name":
            return {text: 1.0}
        if (kind, text) == ("op", "("):
            value = self.expression()
            if self.peek() != ("op", ")"):
                raise LogError(f"--signal {self.text!r}: a '(' is not closed")
            self.i += 1
            return value
        raise LogError(f"--signal {self.text!r}: expected a signal name or a number, found "
                       f"{text or 'the end of the expression'!r}")


FUNCTIONS = ("rate",)
_CALL = re.compile(rf"^({'|'.join(FUNCTIONS)})\((.+)\)$")


def operand(name: str) -> str:
    """The signal a term reads: NAME of ``rate(NAME)``, else the term's name."""
    m = _CALL.match(name)
    return m.group(2) if m else name


def counter_rate(s: Series) -> Series:
    """A counter's rate per second (the module docstring gives the equation): the steps between
    samples, unwrapped modulo ``s.wrap`` where the counter has a width, over their intervals,
    mid-interval."""
    keep, held = counter_updates(s.t, s.values)
    d = np.diff(np.asarray(s.values, float)[keep])
    if s.wrap:
        d = d - s.wrap * np.round(d / s.wrap)
    t = np.asarray(s.t, float)[keep]
    unit = f"({s.unit})/s" if s.unit else None
    how = f"unwrapped modulo {s.wrap:.6g}" if s.wrap else "no width: not unwrapped"
    return Series(0.5 * (t[1:] + t[:-1]), d / np.diff(t), unit, f"{s.label} as a rate per second ({how}; {held})")


def _applied(name: str, series: dict[str, Series]) -> Series:
    """The series of a term: the signal, or the rate of it for ``rate(NAME)``."""
    return counter_rate(series[operand(name)]) if _CALL.match(name) else series[name]


def unknown_name(where: str, spec: SignalSpec, name: str, known: list[str], what: str = "signal") -> LogError:
    """The error for a name no source holds, with the near names."""
    near = difflib.get_close_matches(name, known, n=5, cutoff=0.6)
    if not near:
        tail = name.rsplit(".", 1)[-1].lower()
        near = [k for k in known if k.rsplit(".", 1)[-1].lower() == tail][:5]
    return LogError(f"{where}: --signal {spec}: no {what} {name!r}"
                    + (f"; near names: {', '.join(near)}" if near else
                       f"; {len(known)} {what}s, e.g. {', '.join(known[:8])}" if known else "")
                    + " (convert SOURCE --list shows them all)")


def target_unit(column: str) -> str | None:
    """The unit a column holds: the canonical ones', lat/lon's, x/y's; None: SI of whatever it is."""
    if column in COLUMNS:
        return COLUMNS[column][0]
    return EXTRA_TARGETS.get(column)


def evaluate(spec: SignalSpec, series: dict[str, Series], where: str, wheelbase: float = 1.4,
             sums: dict | None = None) -> tuple[np.ndarray, np.ndarray, str]:
    """(times, values in the column's unit, how) of ``spec`` from the named series (by
    SignalSpec.names; a rate(NAME) term's rate taken here); ``sums``: where the expression has
    several terms, sums[column] = its fastest term's changes per sample
    (measurements.channel_updates.term_share: a sum's rate is its fastest term's)."""
    for n, _ in spec.terms:
        if _CALL.match(n) and len(series[operand(n)].t) < 2:
            raise LogError(f"{where}: --signal {spec}: {n}: {series[operand(n)].label} holds "
                           f"{len(series[operand(n)].t)} sample(s); a rate needs two or more")
    series = {n: _applied(n, series) for n, _ in spec.terms}
    first = series[spec.terms[0][0]]
    t = np.asarray(first.t, float)
    lo = max(float(series[n].t[0]) for n, _ in spec.terms)
    hi = min(float(series[n].t[-1]) for n, _ in spec.terms)
    if len(spec.terms) > 1:
        if hi <= lo:
            spans = ", ".join(f"{n} {series[n].t[0]:.3f}-{series[n].t[-1]:.3f} s" for n, _ in spec.terms)
            raise LogError(f"{where}: --signal {spec}: its signals do not overlap in time ({spans})")
        t = t[(t >= lo) & (t <= hi)]
    parts = []
    for name, coef in spec.terms:
        s = series[name]
        values = np.asarray(s.values, float) if s is first else np.interp(t, s.t, np.asarray(s.values, float))
        if s is first and len(spec.terms) > 1:
            values = values[(first.t >= lo) & (first.t <= hi)]
        parts.append((name, coef, values, s.unit))
    if sums is not None and len(spec.terms) > 1:
        own = [np.asarray(series[n].values, float)[(series[n].t >= lo) & (series[n].t <= hi)] for n, _ in spec.terms]
        sums[spec.column] = term_share(own, len(t))
    notes = [s.label for n, s in series.items() if _CALL.match(n)]
    if spec.unit is not None:
        value = sum(c * v for _, c, v, _ in parts) + spec.constant
        have = check_unit(spec.unit, f"{where}: --signal {spec}")
        said = {u for _, _, _, u in parts if u}
        if said and any(base_unit(u).factor != have.factor or base_unit(u).exponents != have.exponents
                        for u in said if _known(u)):
            notes.append(f"declared [{spec.unit}] overrides the source's {', '.join(sorted(said))}")
        unit_text = spec.unit
    else:
        unitless = [n for n, _, _, u in parts if not u]
        with_unit = [(n, u) for n, _, _, u in parts if u]
        if unitless and with_unit:
            raise LogError(f"{where}: --signal {spec}: {', '.join(unitless)} have no unit while "
                           f"{', '.join(f'{n} [{u}]' for n, u in with_unit)} have one; declare the expression's unit: "
                           f"--signal '{spec.column}=...[unit]'")
        if unitless:
            want = target_unit(spec.column)
            if want in MUST_DECLARE:
                kind = {"rad": "an angle", "rad/s": "a rate", "m/s": "a speed"}[want]
                example = {"rad": "deg", "rad/s": "deg/s", "m/s": "km/h"}[want]
                raise LogError(f"{where}: --signal {spec}: the source gives no unit for {', '.join(unitless)} and "
                               f"column {spec.column!r} is {kind}; declare it, e.g. --signal "
                               f"'{spec.column}={_bare(spec)}[{want}]' or [{example}]")
            value = sum(c * v for _, c, v, _ in parts) + spec.constant
            return t, value, f"{spec}: no unit in the source, taken as {want or 'logged'}" + "".join(f"; {n}" for n in notes)
        si = []
        dims = set()
        for name, coef, v, u in parts:
            if not _known(u):
                raise LogError(f"{where}: --signal {spec}: {name} is in {u!r}, a unit pint does not know; declare "
                               f"the unit: --signal '{spec.column}={_bare(spec)}[unit]'")
            b = base_unit(u)
            dims.add(b.exponents)
            si.append(coef * (b.factor * v + b.offset))
        if len(dims) > 1:
            raise LogError(f"{where}: --signal {spec}: its terms are in units of different kinds "
                           f"({', '.join(f'{n} [{u}]' for n, _, _, u in parts)}); they cannot be added")
        first_unit = parts[0][3]
        value = sum(si) + spec.constant * base_unit(first_unit).factor
        unit_text = first_unit
        have = base_unit(first_unit)
        have = type(have)(have.exponents, 1.0, 0.0)
        return _to_column(spec, t, value, have, unit_text, where, wheelbase, notes)
    return _to_column(spec, t, value, have, unit_text, where, wheelbase, notes)


def _known(unit: str) -> bool:
    try:
        return base_unit(unit) is not None
    except Exception:                                # noqa: BLE001
        return False


def _bare(spec: SignalSpec) -> str:
    text = spec.text.partition("=")[2].strip() if spec.text else "+".join(spec.names)
    return re.sub(r"\[[^\[\]]*\]\s*$", "", text) if spec.unit else text


def _to_column(spec, t, value, have, unit_text, where, wheelbase, notes):
    want_text = target_unit(spec.column)
    how = f"{spec} [{unit_text}]"
    if want_text is None:                        # an extra column: SI of its own unit
        out = have.factor * value + have.offset
        return t, out, how + " -> SI" + ("; " + "; ".join(notes) if notes else "")
    want = base_unit(want_text)
    if have.exponents == want.exponents:
        out = (have.factor * value + have.offset - want.offset) / want.factor
        return t, out, how + f" -> {want_text}" + ("; " + "; ".join(notes) if notes else "")
    curvature = have.exponents == tuple(-1 if i == 1 else 0 for i in range(len(want.exponents)))
    if curvature and want_text == "rad":
        out = np.arctan(wheelbase * have.factor * value)
        return t, out, how + f": curvature to wheel angle, atan({wheelbase:g} m x kappa) -> rad"
    raise LogError(f"{where}: --signal {spec}: the value is in {unit_text}; column {spec.column!r} needs {want_text} "
                   f"or a unit convertible to it" + (" (or a curvature, 1/m)" if want_text == "rad" else ""))
