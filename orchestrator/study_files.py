"""Reading study files: TOML or YAML, an SSP archive or its SSD, ``extends`` (a file merged over
the study it names, with ``connections_remove``/``connections_add`` editing the parent's
connections), ``--set`` overrides and dotted keys into the file's tables. Plain dictionaries in,
plain dictionaries out: validation is the schema's (orchestrator.study_schema).

Imported where used: yaml (start-up: 0.03 s on every command, which loads this module; YAML
study files only), orchestrator.ssp (SSP archives and SSDs only: it loads the FMU and unit modules, 0.02 s,
which reading a study file otherwise does not)."""
from __future__ import annotations

import copy
import re
import tomllib
from pathlib import Path
from typing import Any

from .errors import InputError, did_you_mean
from .study_schema import NAME, parse_connections


class StudyError(InputError):
    """A study cannot be loaded or built; the message names the file and the field."""


def merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """Deep merge: tables merge key by key, anything else in ``over`` replaces."""
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def read_study_file(path: str | Path, _seen: tuple[Path, ...] = ()) -> dict[str, Any]:
    """Parse a study file; a top-level ``extends = "other.toml"`` (relative to this file) starts
    from that study and merges this file's tables over it (a component given another ``type``
    starts afresh: the parent's parameters of the old type do not carry over)."""
    path = Path(path)
    if path.suffix in (".ssp", ".ssd"):          # an SSP archive or its System Structure Description
        from .ssp import study_data

        return study_data(path)
    data = read_one(path)
    parent = data.pop("extends", None)
    edits = {k: data.pop(k) for k in ("connections_remove", "connections_add") if k in data}
    if parent is None:
        if edits:
            raise StudyError(f"{path}: field {next(iter(edits))}: only with extends (it edits the parent's connections)")
        return data
    if not isinstance(parent, str):
        raise StudyError(f"{path}: field extends: expected a file name")
    parent_path = (path.parent / parent).resolve()
    if not parent_path.is_file():
        raise StudyError(f"{path}: field extends: {parent!r} is not a file; it is read from this file's own folder "
                         f"({path.parent.resolve()}), so it names {parent_path}")
    if parent_path in _seen:
        raise StudyError(f"{path}: field extends: circular ({' -> '.join(map(str, _seen + (parent_path,)))})")
    base = read_study_file(parent_path, _seen + (path.resolve(),))
    for name, spec in (data.get("components") or {}).items():
        old = (base.get("components") or {}).get(name)
        if isinstance(spec, dict) and isinstance(old, dict) and "type" in spec and spec["type"] != old.get("type"):
            base["components"][name] = {}       # another type: its parameters and inputs start afresh
    merged = merge(base, data)
    if edits:
        merged["connections"] = _edited_connections(merged.get("connections") or [], edits, path)
    return merged


def _edited_connections(connections: list, edits: dict[str, Any], path: Path) -> list:
    """The parent's connections without ``connections_remove`` and with ``connections_add``
    (compared parsed, so spacing does not matter); removing one that is not there is an error."""
    def key(item):
        return tuple(parse_connections([item])[0].values())

    for field in edits:
        if not isinstance(edits[field], list) or not all(isinstance(x, str) for x in edits[field]):
            raise StudyError(f"{path}: field {field}: expected a list of strings 'component.output -> component.input'")
        try:
            [key(x) for x in edits[field]]
        except ValueError as exc:
            raise StudyError(f"{path}: field {field}: {exc}") from None
    present = {key(c): c for c in connections}
    drop = {key(x) for x in edits.get("connections_remove", [])}
    missing = [x for x in edits.get("connections_remove", []) if key(x) not in present]
    if missing:
        raise StudyError(f"{path}: field connections_remove: {missing[0]!r} is not a connection of the study it extends")
    return [c for c in connections if key(c) not in drop] + list(edits.get("connections_add", []))


def read_one(path: Path) -> dict[str, Any]:
    """Parse TOML (``.toml``) or YAML (``.yaml``/``.yml``) into a plain dict."""
    if not path.is_file():
        raise StudyError(f"{path}: study file not found")
    text = decoded(path, path.read_bytes())
    try:
        if path.suffix == ".toml":
            return tomllib.loads(text)
        if path.suffix in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
            if not isinstance(data, dict):
                raise StudyError(f"{path}: expected a mapping at the top level")
            expanded_size(data, path)
            return data
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{path}: not valid TOML: {exc}") from None
    except Exception as exc:  # yaml errors
        if isinstance(exc, StudyError):
            raise
        raise StudyError(f"{path}: not valid YAML: {exc}") from None
    raise StudyError(f"{path}: unknown study file type {path.suffix!r}; expected .toml, .yaml or .yml")



MAX_VALUES = 200_000         # values a study may expand to through YAML aliases (a large study: a few thousand)


def expanded_size(data: Any, path: Path, limit: int = MAX_VALUES) -> int:
    """The number of values ``data`` holds once every YAML alias is expanded, counted without
    expanding (each shared object once, memoised); refuses an alias that contains itself and data
    past ``limit`` (an alias bomb: nine lines of ``&a [*b, *b, ...]`` make 10^9 values)."""
    sizes: dict[int, int] = {}
    open_: set[int] = set()

    def size(node: Any, trail: str) -> int:
        if not isinstance(node, (dict, list)):
            return 1
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in open_:
            raise StudyError(f"{path}: field {trail or '(top level)'}: a YAML alias refers to a value that contains "
                             f"it (a cycle); write the value out")
        open_.add(key)
        items = node.items() if isinstance(node, dict) else enumerate(node)
        total = 1
        for k, v in items:
            total += size(v, f"{trail}.{k}" if trail else str(k))
            if total > limit:
                raise StudyError(f"{path}: field {trail or '(top level)'}: the YAML expands to more than {limit:,} "
                                 f"values through its aliases (&anchor / *alias): an alias bomb? refused")
        open_.discard(key)
        sizes[key] = total
        return total

    return size(data, "")


def decoded(path: Path, raw: bytes) -> str:
    """A study file's text: UTF-8 (TOML's encoding, and YAML's here); anything else is refused
    with the line, the column and the byte that is not UTF-8, since guessing an encoding could
    change a value silently."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        column = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        context = raw[raw.rfind(b"\n", 0, exc.start) + 1:exc.start].decode("utf-8", "replace")[-30:]
        raise StudyError(f"{path}: line {line}, column {column} (byte offset {exc.start}): byte "
                         f"0x{raw[exc.start]:02x} after {context!r} is not UTF-8; a study file must be UTF-8 text "
                         f"(saved as Latin-1 or Windows-1252? save it again as UTF-8)") from None


def parse_override(item: str, path: str | Path) -> tuple[str, Any]:
    """``comp.param=value`` -> (key, value), the value read as the study file would read it (TOML:
    ``3``, ``"text"``, ``[1, 10, 250]``, ``{start = 1, stop = 5, num = 3}``); ``1,10,250`` is the
    list ``[1, 10, 250]``; text without quotes (``csv``, ``100 ms``) is a string; anything else
    (brackets, braces or quotes that do not parse, ``a,b``) is refused."""
    if "=" not in item or "." not in item.split("=", 1)[0]:
        raise StudyError(f"{path}: override {item!r}: expected 'component.parameter=value' or 'study.field=value'")
    key, raw = item.split("=", 1)
    raw = raw.strip()
    for text in (raw, f"[{raw}]"):
        try:
            return key.strip(), tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            continue
    if re.fullmatch(r"[^\[\]{}\"',=]+", raw):            # a word, or a value with its unit: 100 ms
        return key.strip(), raw
    raise StudyError(f"--set {item}: {raw!r} is not a value a study file could hold; write a list as [1, 10, 250] "
                     f"or 1,10,250, a string in quotes ({key.strip()}='\"{raw}\"')")


ORCHESTRATOR_TABLES = ("sweep", "exports")       # tables --set may start when the study has none


def set_value(data: dict[str, Any], key: str, value: Any, where: str) -> str:
    """Set one dotted key in study data (see ``Study.with_values``); returns the field it set, as
    the schema names it (``components.tracker.parameters.lookahead``). ``COMP.step`` is the
    component's step (``COMP.parameters.NAME`` reaches any parameter by its full name);
    ``sweep.parameters.COMP.PARAM`` a swept parameter; ``TABLE.A.B`` a field of any table."""
    if key.startswith("sweep.parameters."):
        swept = key.removeprefix("sweep.parameters.").replace('"', "")
        data.setdefault("sweep", {}).setdefault("parameters", {})[swept] = value
        return f"sweep.parameters.{swept}"
    parts = key.split(".")
    if len(parts) < 2 or not all(re.fullmatch(NAME, p) for p in parts):
        raise StudyError(f"{where}: expected 'component.parameter', 'component.step', 'component.inputs.port', "
                         f"'study.field' or 'table.field'")
    head, rest = parts[0], parts[1:]
    if head == "study":
        if len(rest) == 2 and rest[0] == "bounds":
            data.setdefault("study", {}).setdefault("bounds", {})[rest[1]] = value
            return f"study.bounds.{rest[1]}"
        if len(rest) != 1:
            raise StudyError(f"{where}: expected 'study.field' (or 'study.bounds.FIGURE')")
        data.setdefault("study", {})[rest[0]] = value
        return f"study.{rest[0]}"
    comps = data.get("components", {})
    subs = data.get("subsystems", {})
    if head in comps:
        spec = comps[head]
        if len(rest) == 2 and rest[0] == "inputs":
            spec.setdefault("inputs", {})[rest[1]] = value
            return f"components.{head}.inputs.{rest[1]}"
        if rest == ["step"]:
            spec["step"] = value
            return f"components.{head}.step"
        name = ".".join(rest[1:] if rest[0] == "parameters" and len(rest) > 1 else rest)
        spec.setdefault("parameters", {})[name] = value
        return f"components.{head}.parameters.{name}"
    if head in subs and rest in (["step"], ["base_step"]):
        subs[head][rest[0]] = value
        return f"subsystems.{head}.{rest[0]}"
    if head in subs and len(rest) >= 2:
        return f"subsystems.{head}." + set_value(subs[head], ".".join(rest), value, where)
    if head not in ("components", "subsystems") and (isinstance(data.get(head), dict) or
                                                     (head in ORCHESTRATOR_TABLES and head not in data)):
        table = data.setdefault(head, {})
        for part in rest[:-1]:               # a table's field: sweep.mode, my_tool.period, my_tool.a.b
            if not isinstance(table.setdefault(part, {}), dict):
                raise StudyError(f"{where}: {head}.{part} is a value, not a table")
            table = table[part]
        table[rest[-1]] = value
        return f"{head}.{'.'.join(rest)}"
    known = sorted(comps) + sorted(subs)
    tables = sorted(k for k, v in data.items() if isinstance(v, dict) and k not in ("components", "subsystems", "study"))
    raise StudyError(f"{where}: no component {head!r}"
                     f"{did_you_mean(head, known + tables, form=' (did you mean {}?)')}; components: {', '.join(known)}"
                     + (f"; tables: {', '.join(tables)}" if tables else ""))


def lookup(data: dict[str, Any], field: str, missing: Any = None) -> Any:
    """The value at a field as ``set_value`` names it (``components.tracker.parameters.lookahead``),
    ``missing`` when absent; a parameter's name may hold dots."""
    node: Any = data
    parts = field.split(".")
    while parts:
        if not isinstance(node, dict):
            return missing
        for n in range(len(parts), 0, -1):       # the longest key first: parameter names with dots
            if ".".join(parts[:n]) in node:
                node, parts = node[".".join(parts[:n])], parts[n:]
                break
        else:
            return missing
    return node


def pruned(table: dict[str, Any]) -> dict[str, Any]:
    """The table without empty sub-tables (recursively)."""
    out = {}
    for key, value in table.items():
        if isinstance(value, dict):
            value = pruned(value)
            if not value:
                continue
        out[key] = value
    return out


def study_chain(path: str | Path | None) -> tuple[Path, ...]:
    """A study file and the files it extends, nearest first (resolved)."""
    out: list[Path] = []
    path = Path(path) if path is not None else None
    while path is not None and path.is_file() and path.resolve() not in out:
        out.append(path.resolve())
        if path.suffix not in (".toml", ".yaml", ".yml"):
            break
        parent = read_one(path).get("extends")
        path = path.parent / parent if isinstance(parent, str) else None
    return tuple(out)


def study_folders(path: str | Path | None) -> tuple[Path, ...]:
    """Where a relative file named in a study is looked for: the study file's folder, then the
    folders of the files it extends, nearest first."""
    return tuple(dict.fromkeys(p.parent for p in study_chain(path)))
