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


_UMASK = _umask()


def atomic_write(path: Path, write: Callable[[Path], None]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        write(tmp_path)
        os.chmod(tmp_path, 0o666 & ~_UMASK)      # mkstemp makes 0600; results are for everyone who may read the folder
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
