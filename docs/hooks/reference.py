"""The reference pages, generated while MkDocs builds the site (a MkDocs hook: ``hooks:`` in
mkdocs.yml), so they always say what the installed code does:

- ``reference/commands.md``: every sub-command's ``--help``, from the argparse parser that
  ``python -m agrobot`` (and the ``agrobot`` script) builds, plugins' commands included;
- ``reference/study-file.md``: every table of a study file, from the pydantic schema
  (orchestrator/study_schema.py, orchestrator/study.py) and the tools' registered tables;
- ``reference/components.md``: every component type with its declared parameters, inputs and
  outputs (``Component.variables``).

Run alone (``python3 docs/hooks/reference.py DIR``) it writes the three pages into DIR.
"""
from __future__ import annotations

import contextlib
import inspect
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGES = {"reference/commands.md": "commands_markdown",
         "reference/study-file.md": "study_file_markdown",
         "reference/components.md": "components_markdown"}


def _project_on_path() -> None:
    """The checkout this file belongs to is imported first (not another installed copy)."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))


@contextlib.contextmanager
def _fixed_help_layout():
    """argparse wraps help to the terminal's width and names the program after argv[0]."""
    saved_argv0, saved_columns = sys.argv[0], os.environ.get("COLUMNS")
    sys.argv[0], os.environ["COLUMNS"] = "__main__.py", "100"
    try:
        yield
    finally:
        sys.argv[0] = saved_argv0
        if saved_columns is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = saved_columns


def command_parsers() -> dict:
    """Sub-command name -> its argparse parser, as the command line builds them."""
    _project_on_path()
    from agrobot.orchestrator.cli import build_parser

    with _fixed_help_layout():
        parser = build_parser()
    action = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return parser, dict(action.choices)


def commands_markdown() -> str:
    parser, subs = command_parsers()
    lines = ["# Commands", "",
             "Generated from the command line's own `--help` when the site is built "
             "(`docs/hooks/reference.py`). Every command is `python3 -m agrobot COMMAND ...`; the "
             "installed script `agrobot COMMAND ...` is the same program. Exit codes: 0 done, 1 a run or "
             "computation that failed part-way (what was computed is kept), 2 bad input (the message "
             "names the file, field and value), 130 Ctrl-C, 143 SIGTERM.", "",
             "| command | what it does |", "|---|---|"]
    helps = {a.dest: a.help for a in parser._subparsers._group_actions[0]._choices_actions}
    for name in subs:
        lines.append(f"| [`{name}`](#{name}) | {helps.get(name, '')} |")
    with _fixed_help_layout():
        for name, sub in subs.items():
            lines += ["", f"## {name}", "", "```text", sub.format_help().rstrip(), "```"]
    return "\n".join(lines) + "\n"


# --- the study file ------------------------------------------------------------------------------
def _type_name(annotation) -> str:
    text = annotation.__name__ if isinstance(annotation, type) else str(annotation)
    text = re.sub(r"\btyping\.", "", text).replace("NoneType", "None")
    text = re.sub(r"\b(?:orchestrator\.\w+|pathlib)\.", "", text)
    return text.replace("Literal", "one of ").replace("|", "or").replace("  ", " ")


def _constraints(field) -> str:
    words = {"gt": ">", "ge": ">=", "lt": "<", "le": "<=", "min_length": "at least", "max_length": "at most"}
    out = []
    for item in field.metadata:
        for key, sign in words.items():
            value = getattr(item, key, None)
            if value is not None:
                out.append(f"{sign} {value}" if "length" not in key else f"{sign} {value} items")
        if getattr(item, "allow_inf_nan", None) is False:
            out.append("finite")
    return ", ".join(out)


def _comments(model) -> dict[str, str]:
    """A field's ``# comment`` on its line of the class source (the schema's descriptions)."""
    try:
        source = inspect.getsource(model)
    except (OSError, TypeError):
        return {}
    found = {}
    for line in source.splitlines():
        match = re.match(r"\s+(\w+)\s*:[^#]*#\s*(.+)$", line)
        if match:
            found[match.group(1)] = match.group(2).strip()
    return found


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def model_table(model) -> list[str]:
    """One row per field of a pydantic model: name, type, default, constraints, description."""
    from pydantic_core import PydanticUndefined

    comments = _comments(model)
    rows = ["| field | type | default | constraint | description |", "|---|---|---|---|---|"]
    for name, field in model.model_fields.items():
        if name == "path":
            continue
        if field.default is PydanticUndefined and field.default_factory is None:
            default = "**required**"
        else:
            value = field.default_factory() if field.default_factory else field.default
            default = f"`{value!r}`" if value not in ({}, [], None) else "none"
        description = field.description or comments.get(name, "")
        rows.append(f"| `{name}` | {_cell(_type_name(field.annotation))} | {_cell(default)} | "
                    f"{_cell(_constraints(field))} | {_cell(description)} |")
    return rows


def _doc(obj) -> str:
    text = inspect.getdoc(obj) or ""
    base = inspect.getdoc(obj.__mro__[1]) if isinstance(obj, type) and len(obj.__mro__) > 1 else None
    return "" if text == base else " ".join(text.split("\n\n")[0].split())


def study_file_markdown() -> str:
    _project_on_path()
    from agrobot.orchestrator import study_schema as s
    from agrobot.orchestrator.registry import registry

    parts = [("`[study]`", s.StudySettings, "Times, seed and run settings (required)."),
             ("`[components.NAME]`", s.ComponentSpec,
              "One table per component; NAME is an identifier. `type` is a component type (see "
              "[Components](components.md)), `package.module:Class`, a path to an `.fmu`, or a path to "
              "a study file used as a subsystem. `parameters` are the type's declared parameters, a "
              "number in SI units or a string with a unit (`\"45 deg\"`, `\"2 cm\"`, `\"7.2 km/h\"`); "
              "`inputs` set an unconnected input to a constant."),
             ("`[exports]`", s.Exports, None), ("exported input as a table", s.ExportedInput, None),
             ("`[subsystems.NAME]`", s.SubsystemSpec, None), ("`[sweep]`", s.Sweep, None),
             ("a range in `[sweep.parameters]`", s.SweepRange, None),
             ("a draw in `[sweep.parameters]`", s.Uniform, None)]
    lines = ["# Study file reference", "",
             "Generated from the schema (`orchestrator/study_schema.py`) when the site is built "
             "(`docs/hooks/reference.py`). A study file is TOML (or YAML) with these top-level tables: "
             + ", ".join(f"`{t}`" for t in s.TABLES) + ", and the tables of the installed tools "
             "(below). Any other table or field is refused by name.", "",
             "## Top level", "",
             "| key | meaning |", "|---|---|",
             "| `extends = \"other.toml\"` | start from another study file (relative to this one) and "
             "merge this file's tables over it |",
             "| `connections = [\"a.out -> b.in\", ...]` | wiring: a component's output to another's input "
             "(units are checked) |",
             "| `connections_remove = [...]`, `connections_add = [...]` | with `extends`: edit the "
             "parent's connections |", ""]
    for title, model, intro in parts:
        lines += [f"## {title}", "", intro or _doc(model), ""] + model_table(model) + [""]
    reg = registry()
    lines += ["## Tool tables", "",
              "Tables that an installed tool reads; a study may hold them only when that tool is installed.", "",
              "| table | read by |", "|---|---|"]
    lines += [f"| `[{name}]` | {_cell(reader)} |" for name, reader in sorted(reg.sections.items())]
    for name, schema in sorted(reg.section_schemas.items()):
        lines += ["", f"### `[{name}]`", "", _doc(schema), ""] + model_table(schema)
    lines += ["", "## `--set` overrides", "",
              "Every study-taking command accepts `--set COMP.PARAM=VALUE` (a component parameter, "
              "`COMP.inputs.PORT=VALUE` for a constant input, `study.FIELD=VALUE` for a `[study]` field; "
              "a subsystem's inner parameter is `SUB.COMP.PARAM`), repeatable; the value is read as TOML "
              "(`--set tractor.psi0='\"30 deg\"'` or `--set 'tractor.psi0=\"30 deg\"'`)."]
    return "\n".join(lines) + "\n"


def component_types() -> dict[str, type]:
    """Every registered component type name -> its class."""
    _project_on_path()
    from agrobot.orchestrator.python_types import _known_types, resolve_type
    from agrobot.orchestrator.registry import registry
    from agrobot.orchestrator.study import StudyError

    found = {}
    for name in sorted(set(_known_types(registry().component_packages))):
        try:
            found[name] = resolve_type(name, None, "docs")
        except StudyError:
            continue
    return found


def _value(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _summary(cls) -> str:
    """The class's docstring, else its module's (one component per module)."""
    return _doc(cls) or " ".join((inspect.getdoc(sys.modules[cls.__module__]) or "").split("\n\n")[0].split())


def components_markdown() -> str:
    lines = ["# Components", "",
             "Generated from each component's declarations (`Component.variables`) when the site is built "
             "(`docs/hooks/reference.py`). A study names a type by its module name "
             "(`type = \"tractor_yaw_plant\"`). Defaults are in the unit shown (SI, radians); a study may "
             "give any value with a unit string (`\"30 deg\"`). *Sampled* components hold their outputs "
             "over a step; *continuous* ones integrate over it.", "",
             "| type | what it is |", "|---|---|"]
    types = component_types()
    lines += [f"| [`{name}`](#{name}) | {_cell(_summary(cls))} |" for name, cls in types.items()]
    for name, cls in types.items():
        kind = "sampled" if cls.sampled else "continuous"
        roles = ", ".join(f"`{r}`" for r in cls.roles) or "none"
        lines += ["", f"## {name}", "", _summary(cls), "",
                  f"`{cls.__module__}.{cls.__name__}`: {kind}; roles: {roles}.", ""]
        for causality, title in (("parameter", "Parameters"), ("input", "Inputs"), ("output", "Outputs")):
            declared = cls.declared(causality)
            if not declared:
                continue
            lines += [f"**{title}**", "", "| name | unit | default | description |", "|---|---|---|---|"]
            lines += [f"| `{v.name}` | {_cell(v.unit)} | {_cell(_value(v.start))} | {_cell(v.description)} |"
                      for v in declared.values()]
            lines.append("")
    return "\n".join(lines) + "\n"


def generated_pages() -> dict[str, str]:
    return {path: globals()[function]() for path, function in PAGES.items()}


def on_files(files, config):
    """MkDocs hook: add the generated pages to the site."""
    from mkdocs.structure.files import File

    for path, content in generated_pages().items():
        files.append(File.generated(config, path, content=content))
    return files


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "site-reference")
    for path, content in generated_pages().items():
        (out / path).parent.mkdir(parents=True, exist_ok=True)
        (out / path).write_text(content)
        print(out / path)
