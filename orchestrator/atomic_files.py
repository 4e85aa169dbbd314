"""Writing results so that nothing is left half-written: each file goes to a temporary name in
the same folder and is renamed over the target in one step.

Tables carry their columns' units: a DataFrame in ``attrs["units"]`` (column -> unit), a Parquet
file in its schema metadata under the key ``units`` (JSON), a CSV file in ``NAME.units.json``
beside it; ``read_units`` and ``read_table`` take them back.

Imported where used: pyarrow.parquet (start-up: 0.03 s on every command, which loads this module).
"""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable

import pandas as pd
import pyarrow as pa


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


UMASK = _umask()


def atomic_write(path: Path, write: Callable[[Path], None]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        write(tmp_path)
        os.chmod(tmp_path, 0o666 & ~UMASK)      # mkstemp makes 0600; results are for everyone who may read the folder
        os.replace(tmp_path, path)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()
    return path


def write_json(path: Path, data: dict[str, Any]) -> Path:
    return atomic_write(path, lambda p: p.write_text(json.dumps(data, indent=2, sort_keys=False) + "\n"))


UNITS_KEY = b"units"          # the Parquet schema metadata key of the columns' units


def units_metadata(units: dict[str, str]) -> dict[bytes, bytes]:
    """Parquet schema metadata holding ``units`` (column -> unit)."""
    return {UNITS_KEY: json.dumps(dict(units)).encode()}


def frame_metadata(schema: pa.Schema) -> dict[bytes, bytes]:
    """An Arrow schema's metadata without the frame's attrs that pyarrow keeps in its pandas
    metadata ("attributes"): a written table holds what it declares (an import's own samples
    would grow a log several times over, and every read-back frame would copy them)."""
    meta = dict(schema.metadata or {})
    if b"pandas" in meta:
        pandas_meta = json.loads(meta[b"pandas"])
        pandas_meta.pop("attributes", None)
        meta[b"pandas"] = json.dumps(pandas_meta).encode()
    return meta


def units_file(path: Path) -> Path:
    """Where a CSV table's units are kept: ``NAME.units.json`` beside ``NAME.csv``."""
    return Path(path).with_name(Path(path).stem + ".units.json")


def schema_units(schema: pa.Schema) -> dict[str, str]:
    """The units an Arrow schema's metadata holds (column -> unit; empty when it holds none)."""
    raw = (schema.metadata or {}).get(UNITS_KEY)
    return json.loads(raw) if raw else {}


def read_units(path: Path, schema=None) -> dict[str, str]:
    """The units a table file stores (column -> unit; empty when it stores none)."""
    path = Path(path)
    if path.suffix == ".parquet":
        if schema is None:
            import pyarrow.parquet as pq

            schema = pq.read_schema(path)
        return schema_units(schema)
    side = units_file(path)
    return json.loads(side.read_text()) if side.is_file() else {}


def write_frame(path: Path, frame: pd.DataFrame, **csv_options) -> Path:
    """``frame`` to ``path`` (.parquet, else CSV), with its ``attrs["units"]`` and none of its
    other attrs (a CSV holds none; a parquet's pandas metadata would: frame_metadata)."""
    path = Path(path)
    units = dict(frame.attrs.get("units", {}))
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        def write(p: Path) -> None:
            table = pa.Table.from_pandas(frame, preserve_index=False)
            pq.write_table(table.replace_schema_metadata({**frame_metadata(table.schema), **units_metadata(units)}), p)

        return atomic_write(path, write)
    if units:
        atomic_write(units_file(path), lambda p: p.write_text(json.dumps(units, indent=1) + "\n"))
    return atomic_write(path, lambda p: frame.to_csv(p, index=False, **csv_options))


def write_table(path_stem: Path, frame: pd.DataFrame, fmt: str) -> Path:
    return write_frame(path_stem.with_suffix(".parquet" if fmt == "parquet" else ".csv"), frame)


def read_table(path: Path) -> pd.DataFrame:
    path = Path(path)
    frame = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    units = read_units(path)
    if units:
        frame.attrs["units"] = units
    return frame


class SignalWriter:
    """The signal table written while the run goes: blocks of rows are appended (Parquet row groups
    through pyarrow, or CSV lines), so a long run keeps flat memory and an interrupted one keeps
    every row up to its last block. ``close`` returns the file's path."""

    def __init__(self, path_stem: Path, columns: list[str], fmt: str, units: dict[str, str] | None = None) -> None:
        self.columns = ["t"] + list(columns)
        self.units = dict(units or {})
        self.path = path_stem.with_suffix(".parquet" if fmt == "parquet" else ".csv")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.rows = 0
        self._parquet = None
        self._spill = None
        if fmt == "parquet":
            import pyarrow.parquet as pq

            self._schema = pa.schema([(c, pa.float64()) for c in self.columns], metadata=units_metadata(self.units))
            self._parquet = pq.ParquetWriter(self.path, self._schema)
        else:
            atomic_write(units_file(self.path), lambda p: p.write_text(json.dumps(self.units, indent=1) + "\n"))
            self._csv = open(self.path, "w", newline="")
            pd.DataFrame(columns=self.columns).to_csv(self._csv, index=False)

    @property
    def partial(self) -> Path:
        """Where the rows written so far can be read should the process die (``spill``): a CSV table
        is that file itself (its lines flushed at each block), a Parquet one (readable only once
        closed) an Arrow IPC stream beside it, ``NAME.partial.arrows`` (read_partial)."""
        return self.path if self._parquet is None else self.path.with_name(self.path.stem + ".partial.arrows")

    def spill(self) -> Path:
        """From now on every block also goes to ``partial``, written through to the file, so that
        a process killed by a fatal signal (an FMU's C code crashing) leaves every block appended
        before it readable; removed by ``close``. Returns ``partial``."""
        if self._parquet is not None and self._spill is None:
            self._spill = pa.ipc.new_stream(pa.OSFile(str(self.partial), "wb"), self._schema)
        return self.partial

    def append(self, block) -> None:
        if len(block) == 0:
            return
        frame = pd.DataFrame(block, columns=self.columns)
        if self._parquet is not None:
            table = pa.Table.from_pandas(frame, schema=self._schema, preserve_index=False)
            self._parquet.write_table(table)
            if self._spill is not None:
                self._spill.write_table(table)
        else:
            frame.to_csv(self._csv, header=False, index=False)
            self._csv.flush()
        self.rows += len(block)

    def close(self) -> Path:
        if self._spill is not None:
            self._spill.close()
            self._spill = None
            self.partial.unlink(missing_ok=True)
        if self._parquet is not None:
            self._parquet.close()
            self._parquet = None
        elif not self._csv.closed:
            self._csv.close()
        os.chmod(self.path, 0o666 & ~UMASK)
        return self.path


def read_partial(path: Path) -> pd.DataFrame:
    """The rows of an Arrow IPC stream left by a run that died (SignalWriter.spill): every complete
    block, up to the first one cut short; the columns' units in ``attrs["units"]``."""
    batches = []
    with pa.ipc.open_stream(pa.OSFile(str(path), "rb")) as reader:
        schema = reader.schema
        try:
            for batch in reader:
                batches.append(batch)
        except (OSError, pa.ArrowInvalid):      # the block being written when the process died
            pass
    frame = pa.Table.from_batches(batches, schema=schema).to_pandas()
    frame.attrs["units"] = schema_units(schema)
    return frame
