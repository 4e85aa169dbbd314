"""A maker's DBC, loaded as far as it can be decoded, with a report of what was repaired or left out.

Who does what: cantools parses and decodes (``cantools.database.load_string``); this module only
repairs the text before cantools sees it, and isolates what cannot be repaired. In order:

0. the files a DBC imports (``CM_ "IMPORT name";``, opendbc's convention) are read in;
1. cantools in its strict mode;
2. cantools with ``strict=False`` (overlapping signals, value tables for signals that do not exist:
   the checks it relaxes are named);
3. a textual pre-pass, each repair counted: an identifier above 0x7FF written without the DBC's
   extended bit (0x80000000) is a 29-bit one; numbers written ``.25`` get their ``0``; message and
   signal names that begin with a digit get a leading ``_`` for the parser and their own name back
   once loaded; comments in forms the grammar does not have (no ``;``, a signal comment without
   the signal's name, ``CM_ 145 "..."``) are dropped;
4. statements that only describe (comments, attributes, value tables: never needed to decode)
   dropped one at a time where cantools names them (a syntax error on that line, a value table
   for a signal that does not exist), each counted;
5. message by message: each ``BO_`` block with its signals loaded alone, and the ones that still
   fail left out and named with cantools' reason (the whole file is never refused when one
   message of it can be read).

Imported where used: cantools (the hardware extra).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from agrobot.orchestrator.source_files import regular_file

from .log import LogError

EXTENDED_BIT = 0x80000000
MAX_DROPPED = 50             # auxiliary statements dropped one by one before going message by message
AUXILIARY = ("CM_", "BA_", "BA_DEF_", "BA_DEF_DEF_", "VAL_", "VAL_TABLE_", "SIG_VALTYPE_", "SIG_GROUP_",
             "SG_MUL_VAL_", "BO_TX_BU_", "EV_", "ENVVAR_DATA_", "CAT_", "FILTER", "SGTYPE_", "BA_DEF_REL_",
             "BA_REL_", "BU_SG_REL_", "BU_EV_REL_", "BU_BO_REL_")
STATEMENTS = ("VERSION", "NS_", "BS_", "BU_", "BO_", "SG_", "CM_", "BA_", "VAL_", "EV_", "BO_TX_BU_", "SIG_",
              "SG_MUL_VAL_", "VAL_TABLE_", "CAT_", "FILTER", "ENVVAR_DATA_", "SGTYPE_")
_ID_REFERENCE = re.compile(r"^(\s*(?:BO_|CM_ BO_|CM_ SG_|BA_ \"[^\"]*\" BO_|BA_ \"[^\"]*\" SG_|VAL_|BO_TX_BU_|"
                           r"SIG_VALTYPE_|SIG_GROUP_|SG_MUL_VAL_)\s+)(\d+)\b", re.M)
_DIGIT_NAME = re.compile(r"^(\s*(?:BO_\s+\d+|SG_))\s+(\d\w*)", re.M)
_BARE_DECIMAL = re.compile(r"(?<=[(\[,|\s])(-?)\.(\d)")
_COMMENT_HEAD = re.compile(r"^CM_\s*(?:(?:BU_|EV_)\s+\w+\s*|BO_\s+\d+\s*|SG_\s+\d+\s+\w+\s*)?\"")


@dataclass
class DBCReport:
    """How a DBC was loaded: by which path, what the pre-pass changed, what was left out."""

    path: str
    loader: str = "cantools (strict)"
    repairs: dict = field(default_factory=dict)      # what -> count
    skipped: dict = field(default_factory=dict)      # message -> why
    renamed: dict = field(default_factory=dict)      # parser name -> the file's name

    def as_dict(self) -> dict:
        return {"path": self.path, "loader": self.loader, "repairs": dict(self.repairs),
                "messages_left_out": dict(self.skipped)}

    def lines(self) -> list[str]:
        out = [f"DBC {self.path}: {self.loader}"]
        out += [f"  repaired: {what} ({n})" for what, n in self.repairs.items()]
        out += [f"  left out: message {m}: {why}" for m, why in self.skipped.items()]
        return out


def load_dbc_file(path: str | Path):
    """(cantools database, DBCReport): every message of the DBC that can be decoded; a LogError
    names the file when nothing in it is a DBC message."""
    import cantools

    path = regular_file(path, LogError)
    try:
        text = path.read_bytes().decode("utf-8", errors="replace") if path.suffix.lower() != ".dbc" else \
            _read_text(path)
    except OSError as exc:
        raise LogError(f"{path}: cannot read the DBC: {exc}") from None
    report = DBCReport(str(path))
    text = _with_imports(path, text, report, {path.resolve()})
    try:
        return cantools.database.load_string(text, database_format="dbc"), report
    except Exception as strict_error:                       # noqa: BLE001 - cantools raises many kinds
        first = _reason(strict_error)
    try:
        db = cantools.database.load_string(text, database_format="dbc", strict=False)
        report.loader = f"cantools (strict=False: {first})"
        return db, report
    except Exception:                                        # noqa: BLE001
        pass
    repaired = _prepass(text, report)
    for _ in range(MAX_DROPPED):
        try:
            db = cantools.database.load_string(repaired, database_format="dbc", strict=False)
            report.loader = "cantools (strict=False) after the pre-pass"
            break
        except Exception as exc:                             # noqa: BLE001
            dropped = _drop_offending(repaired, str(exc), report)
            if dropped is None:
                db = _message_by_message(path, repaired, report, _reason(exc))
                break
            repaired = dropped
    else:
        db = _message_by_message(path, repaired, report, "too many statements the parser refuses")
    _restore_names(db, report)
    return db, report


_IMPORT = re.compile(r'^CM_\s+"IMPORT\s+([^"]+?)"\s*;\s*$', re.M)


def _with_imports(path: Path, text: str, report: DBCReport, seen: set) -> str:
    """The DBC with the files its ``CM_ "IMPORT name";`` lines name (opendbc's generator
    convention) put in their place, without their headers."""
    names = _IMPORT.findall(text)
    if not names:
        return text
    parts = []
    for name in names:
        other = (path.parent / name).resolve()
        if other in seen:
            continue
        if not other.is_file():
            report.skipped[f"IMPORT {name}"] = "no such file beside the DBC"
            continue
        seen.add(other)
        body = _with_imports(other, _read_text(other), report, seen)
        parts.append(_body(body))
        report.repairs["files it imports, read in"] = report.repairs.get("files it imports, read in", 0) + 1
    return _IMPORT.sub("", text) + "\n" + "\n".join(parts)


def _body(text: str) -> str:
    """A DBC without its header (VERSION, NS_ and its list, BS_, BU_)."""
    out, in_ns = [], False
    for line in text.replace("\r\n", "\n").split("\n"):
        if line.startswith("NS_"):
            in_ns = True
            continue
        if in_ns and (line.startswith((" ", "\t")) or not line.strip()):
            continue
        in_ns = False
        if line.startswith(("VERSION", "BS_", "BU_")):
            continue
        out.append(line)
    return "\n".join(out)


def _read_text(path: Path) -> str:
    data = path.read_bytes()
    for encoding in ("utf-8", "cp1252"):
        try:
            return data.decode(encoding)
        except UnicodeDecodeError:
            continue
    return data.decode("latin-1")


def _reason(exc: Exception) -> str:
    return " ".join(str(exc).split())[:200]


def _count(report: DBCReport, what: str, n: int = 1) -> None:
    if n:
        report.repairs[what] = report.repairs.get(what, 0) + n


def _prepass(text: str, report: DBCReport) -> str:
    """The repairs of step 3, each counted in the report."""
    text = text.replace("\r\n", "\n")

    def extended(m):
        ident = int(m.group(2))
        if 0x7FF < ident < 0x20000000:
            _count(report, "29-bit identifiers written without the extended bit")
            return f"{m.group(1)}{ident | EXTENDED_BIT}"
        return m.group(0)
    text = _ID_REFERENCE.sub(extended, text)
    names = sorted({m.group(2) for m in _DIGIT_NAME.finditer(text)}, key=len, reverse=True)
    for name in names:
        report.renamed["_" + name] = name
        text = re.sub(rf"(?<![\w.]){re.escape(name)}\b", "_" + name, text)
    _count(report, "message or signal names beginning with a digit", len(names))
    lines = text.split("\n")
    for i, line in enumerate(lines):
        if line.lstrip().startswith("SG_"):
            lines[i], n = _BARE_DECIMAL.subn(r"\g<1>0.\2", line)
            _count(report, "numbers written without a leading 0 ('.25')", n)
    out, i = [], 0
    while i < len(lines):
        line = lines[i]
        if not line.startswith("CM_"):
            out.append(line)
            i += 1
            continue
        statement = [line]
        while not statement[-1].rstrip().endswith(";") and i + 1 < len(lines) and \
                lines[i + 1].split(" ", 1)[0].rstrip(":") not in STATEMENTS:
            i += 1
            statement.append(lines[i])
        i += 1
        whole = "\n".join(statement)
        if whole.rstrip().endswith(";") and _COMMENT_HEAD.match(whole):
            out.extend(statement)
        else:
            _count(report, "comments in a form the DBC grammar does not have (dropped)")
    return "\n".join(out)


def _drop_offending(text: str, error: str, report: DBCReport) -> str | None:
    """The text without the auxiliary statement cantools refused (None: the error is elsewhere)."""
    lines = text.split("\n")
    unused = re.findall(r"(VAL_ \d+ \w+)", error.partition("unused VAL_")[2])
    if "unused VAL_" in error and unused:
        keep = [ln for ln in lines if not any(ln.startswith(u + " ") or ln.strip() == u for u in unused)]
        _count(report, "value tables for signals the message does not have (dropped)", len(lines) - len(keep))
        return "\n".join(keep) if len(keep) < len(lines) else None
    m = re.search(r"Invalid syntax at line (\d+)", error)
    if not m:
        return None
    k = int(m.group(1)) - 1
    while 0 < k < len(lines) and not lines[k].strip():
        k -= 1
    start = k
    while start > 0 and lines[start].split(" ", 1)[0] not in STATEMENTS + AUXILIARY:
        start -= 1
    keyword = lines[start].split(" ", 1)[0] if 0 <= start < len(lines) else ""
    if keyword not in AUXILIARY:
        return None
    end = start
    while end + 1 < len(lines) and not lines[end].rstrip().endswith(";") and \
            lines[end + 1].split(" ", 1)[0].rstrip(":") not in STATEMENTS + AUXILIARY:
        end += 1
    _count(report, f"{keyword} statements the parser refuses (dropped)")
    return "\n".join(lines[:start] + lines[end + 1:])


def _message_by_message(path: Path, text: str, report: DBCReport, why: str):
    """Step 4: each BO_ block loaded alone; the ones cantools refuses are named."""
    import cantools
    from cantools.database.can import Database

    lines = text.split("\n")
    starts = [i for i, ln in enumerate(lines) if ln.startswith("BO_ ")]
    if not starts:
        raise LogError(f"{path}: not a DBC: no message (BO_) in it; cantools says: {why}")
    head = "\n".join(ln for ln in lines[:starts[0]] if ln.split(" ", 1)[0].rstrip(":") in ("VERSION", "BU_")) or \
        'VERSION ""'
    messages = []
    for k, a in enumerate(starts):
        b = a + 1
        while b < len(lines) and lines[b].startswith((" ", "\t")) and lines[b].strip().startswith("SG_"):
            b += 1
        block = "\n".join(lines[a:b])
        name = lines[a].split()[2].rstrip(":") if len(lines[a].split()) > 2 else f"#{k + 1}"
        try:
            one = cantools.database.load_string(f"{head}\nNS_ :\nBS_:\n{block}\n", database_format="dbc", strict=False)
            messages += one.messages
        except Exception as exc:                              # noqa: BLE001
            report.skipped[report.renamed.get(name, name)] = _reason(exc)
    if not messages:
        raise LogError(f"{path}: no message of it can be read as a DBC; cantools says: {why}")
    report.loader = ("cantools, message by message after the pre-pass (the file as a whole: " + why[:120] + ")")
    return Database(messages=messages, strict=False)


def _restore_names(db, report: DBCReport) -> None:
    """The file's own names for what the pre-pass renamed."""
    for m in db.messages:
        if m.name in report.renamed:
            m.name = report.renamed[m.name]
        for s in m.signals:
            if s.name in report.renamed:
                s.name = report.renamed[s.name]
    if report.renamed:
        db.refresh()
