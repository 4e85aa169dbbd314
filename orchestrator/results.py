"""Writing results so that nothing is left half-written: each file goes to a temporary name in
the same folder and is renamed over the target in one step."""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable

import pandas as pd


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


def write_table(path_stem: Path, frame: pd.DataFrame, fmt: str) -> Path:
    if fmt == "parquet":
        return atomic_write(path_stem.with_suffix(".parquet"), lambda p: frame.to_parquet(p, index=False))
    return atomic_write(path_stem.with_suffix(".csv"), lambda p: frame.to_csv(p, index=False))


def read_table(path: Path) -> pd.DataFrame:
    path = Path(path)
    if path.suffix == ".parquet":
        return pd.read_parquet(path)
    return pd.read_csv(path)


class SignalWriter:
    """The signal table written while the run goes: blocks of rows are appended (Parquet row groups
    through pyarrow, or CSV lines), so a long run keeps flat memory and an interrupted one keeps
    every row up to its last block. ``close`` returns the file's path."""

    def __init__(self, path_stem: Path, columns: list[str], fmt: str) -> None:
        self.columns = ["t"] + list(columns)
        self.path = path_stem.with_suffix(".parquet" if fmt == "parquet" else ".csv")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.rows = 0
        self._parquet = None
        if fmt == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            self._schema = pa.schema([(c, pa.float64()) for c in self.columns])
            self._parquet = pq.ParquetWriter(self.path, self._schema)
        else:
            self._csv = open(self.path, "w", newline="")
            pd.DataFrame(columns=self.columns).to_csv(self._csv, index=False)

    def append(self, block) -> None:
        if len(block) == 0:
            return
        frame = pd.DataFrame(block, columns=self.columns)
        if self._parquet is not None:
            import pyarrow as pa

            self._parquet.write_table(pa.Table.from_pandas(frame, schema=self._schema, preserve_index=False))
        else:
            frame.to_csv(self._csv, header=False, index=False)
            self._csv.flush()
        self.rows += len(block)

    def close(self) -> Path:
        if self._parquet is not None:
            self._parquet.close()
            self._parquet = None
        elif not self._csv.closed:
            self._csv.close()
        os.chmod(self.path, 0o666 & ~UMASK)
        return self.path
