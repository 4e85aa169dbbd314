"""The signal table of a result folder, read back by column.

A run streams its signals to disk (``results.SignalWriter``); what analyses it afterwards reads
only the columns it asks for, when it asks (a Parquet column chunk by chunk, or one column of a
CSV file), so the memory an analysis needs grows with the columns it uses, never with the width
of the table. ``SignalTable`` answers the parts of a pandas DataFrame an analysis uses:
``table["name"]`` (a Series), ``"name" in table``, ``len(table)``, ``table.columns``,
``table.iloc[a:b:c]`` (a view, nothing read), ``reset_index(drop=True)``; ``to_pandas()`` reads
the whole table when it is really wanted. The units the file stores (orchestrator.atomic_files) come
back in ``table.units``, a column's in its Series' ``attrs["unit"]`` and a DataFrame's in
``attrs["units"]``.

Imported where used: pyarrow.parquet (start-up: 0.03 s on every command, which loads this module).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.csv as pacsv

from .atomic_files import read_units


class _Columns:
    """The file and the columns read from it so far (shared by every view of one table)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.read: dict[str, np.ndarray] = {}
        if self.path.suffix == ".parquet":
            import pyarrow.parquet as pq

            self._parquet = pq.ParquetFile(self.path)
            self.names = list(self._parquet.schema_arrow.names)
            self.rows = self._parquet.metadata.num_rows
            self.units = read_units(self.path, self._parquet.schema_arrow)
        else:
            self._parquet = None
            self.names = list(pd.read_csv(self.path, nrows=0).columns)
            self.rows = len(self.column(self.names[0])) if self.names else 0
            self.units = read_units(self.path)

    def column(self, name: str) -> np.ndarray:
        if name not in self.read:
            if self._parquet is not None:
                values = self._parquet.read(columns=[name]).column(0).to_numpy()
            else:
                options = pacsv.ConvertOptions(include_columns=[name])
                values = pacsv.read_csv(self.path, convert_options=options).column(0).to_numpy()
            self.read[name] = values
        return self.read[name]


class _Rows:
    def __init__(self, table: "SignalTable") -> None:
        self._table = table

    def __getitem__(self, rows):
        if not isinstance(rows, slice):
            raise TypeError("SignalTable.iloc takes a slice of rows (a:b:c); read a column first for more")
        return self._table._view(rows)


class SignalTable:
    """A result file's signal table (``signals.parquet`` or ``signals.csv``), read by column."""

    def __init__(self, path: Path | str, *, _columns: _Columns | None = None, _rows: range | None = None,
                 _from_zero: bool = False) -> None:
        self._columns = _columns if _columns is not None else _Columns(Path(path))
        self._rows = _rows if _rows is not None else range(self._columns.rows)
        self._from_zero = _from_zero

    @property
    def path(self) -> Path:
        return self._columns.path

    @property
    def columns(self) -> pd.Index:
        return pd.Index(self._columns.names)

    @property
    def units(self) -> dict[str, str]:
        """Column -> unit, as the file stores them (empty for a file that stores none)."""
        return dict(self._columns.units)

    def __contains__(self, name: object) -> bool:
        return name in self._columns.names

    def __len__(self) -> int:
        return len(self._rows)

    def __getitem__(self, name):
        if isinstance(name, (list, tuple)):
            frame = pd.DataFrame({n: self[n] for n in name})
            frame.attrs["units"] = {n: self._columns.units[n] for n in name if n in self._columns.units}
            return frame
        if name not in self._columns.names:
            raise KeyError(name)
        rows = self._rows
        values = self._columns.column(name)[rows.start:rows.stop if rows.stop >= 0 else None:rows.step]
        index = pd.RangeIndex(len(rows)) if self._from_zero else pd.RangeIndex(rows.start, rows.stop, rows.step)
        series = pd.Series(values, index=index, name=name, copy=False)
        if name in self._columns.units:
            series.attrs["unit"] = self._columns.units[name]
        return series

    @property
    def iloc(self) -> _Rows:
        return _Rows(self)

    def _view(self, rows: slice) -> "SignalTable":
        return SignalTable(self.path, _columns=self._columns, _rows=self._rows[rows], _from_zero=self._from_zero)

    def reset_index(self, drop: bool = False) -> "SignalTable":
        if not drop:
            raise TypeError("SignalTable.reset_index keeps no old index: call it with drop=True")
        return SignalTable(self.path, _columns=self._columns, _rows=self._rows, _from_zero=True)

    def to_pandas(self, columns: list[str] | None = None) -> pd.DataFrame:
        """The rows of this view as a DataFrame (every column, or ``columns``)."""
        return self[list(columns if columns is not None else self._columns.names)]

    def __repr__(self) -> str:
        return f"SignalTable({str(self.path)!r}, {len(self)} rows x {len(self._columns.names)} columns)"
