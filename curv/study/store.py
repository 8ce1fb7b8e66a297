"""The results file: a CSV appended to after every finished task, so nothing finished is lost.

Each task's rows are written with one ``write`` call, flushed and synced. The rows of one write
form a *block*; every row carries its block id and the number of rows in the block, so a file cut
short by a crash is repaired on the next open: a torn last line and the rest of its block are
dropped (and recomputed), everything complete is kept and skipped.
Floats are written with ``repr`` and read back bit-identically.
"""

from __future__ import annotations

import csv
import io
import os
import zlib
from pathlib import Path
from typing import Iterable

import numpy as np

from .table import _DTYPES, COLUMNS, Table

__all__ = ["ResultsFile", "block_id"]


def block_id(key: tuple, variant_ids: Iterable[str]) -> str:
    """A deterministic id of the block of rows one task writes."""
    text = "|".join(map(str, key)) + "#" + ",".join(variant_ids)
    return f"{zlib.crc32(text.encode()):08x}"


def _format(value, typ) -> str:
    if typ is float:
        return repr(float(value))
    if typ is int:
        return str(int(value))
    return str(value)


def _parse(text: str, typ):
    if typ is str:
        return text
    return typ(float(text)) if typ is int else float(text)


def _parse_column(texts: tuple[str, ...], typ) -> np.ndarray:
    """One column's fields as an array of the column's type (ints are written as ints but read
    through float, like :func:`_parse`). Raises ValueError on a field that does not parse."""
    if typ is str:
        return np.array(texts, dtype=object)
    values = np.array(texts, dtype=np.float64)
    return values.astype(np.int64) if typ is int else values


def _row_parses(fields: list[str], names: list[str]) -> bool:
    try:
        for n, f in zip(names, fields):
            _parse(f, COLUMNS[n])
    except ValueError:
        return False
    return True


class ResultsFile:
    """The tidy results of a study run, as a CSV file that only grows.

    Parameters
    ----------
    path : path-like
        The CSV file; created with a header on the first append.
    """

    def __init__(self, path):
        self.path = Path(path)
        self._names = list(COLUMNS)

    # ------------------------------------------------------------------ reading
    def _read_columns(self) -> tuple[dict[str, np.ndarray], bool]:
        """Columns of the complete blocks, and whether anything had to be dropped.

        Parsed column by column (a 400k-row file in seconds, not minutes); a column that numpy
        cannot convert (a damaged field) falls back to parsing row by row and drops those rows.
        """
        empty = {n: np.zeros(0, _DTYPES[t]) for n, t in COLUMNS.items()}
        if not self.path.exists() or self.path.stat().st_size == 0:
            return empty, False
        text = self.path.read_text()
        torn = bool(text) and not text.endswith("\n")
        if torn:
            text = text[: text.rfind("\n") + 1]  # torn last line
        reader = csv.reader(io.StringIO(text))
        header = next(reader, None)
        if header != self._names:
            raise ValueError(
                f"{self.path} has other columns than this version of curv writes; "
                "use a new --out directory (or move the old results away)"
            )
        fields = list(reader)
        whole = [f for f in fields if len(f) == len(self._names)]
        dropped = torn or len(whole) != len(fields)
        if not whole:
            return empty, dropped
        raw = list(zip(*whole))
        try:
            cols = {n: _parse_column(raw[i], COLUMNS[n]) for i, n in enumerate(self._names)}
        except ValueError:
            keep = [f for f in whole if _row_parses(f, self._names)]
            dropped = True
            if not keep:
                return empty, dropped
            raw = list(zip(*keep))
            cols = {n: _parse_column(raw[i], COLUMNS[n]) for i, n in enumerate(self._names)}
        _, inverse, counts = np.unique(cols["block"].astype(str), return_inverse=True, return_counts=True)
        complete = counts[inverse] == cols["block_rows"]
        if not complete.all():
            cols = {n: c[complete] for n, c in cols.items()}
            dropped = True
        return cols, dropped

    def load(self, *, repair: bool = True) -> Table:
        """All complete rows as a :class:`Table`.

        With ``repair``, a file holding torn or incomplete blocks is rewritten (atomically)
        without them, so that later appends start on a clean line.
        """
        cols, dirty = self._read_columns()
        table = Table(cols)
        if dirty and repair:
            tmp = self.path.with_suffix(self.path.suffix + ".tmp")
            tmp.write_text(self._header() + "".join(self._lines(table.rows())))
            os.replace(tmp, self.path)
        return table

    def done(self) -> dict[tuple, set[str]]:
        """``{task key: variant ids present}`` over the complete blocks (repairs the file)."""
        table = self.load()
        keys = zip(table["seed"].tolist(), table["function"].tolist(), table["density"].tolist(),
                   table["irregularity"].tolist(), table["noise"].tolist(), table["sample"].tolist())
        out: dict[tuple, set[str]] = {}
        for key, variant in zip(keys, table["variant"].tolist()):
            out.setdefault(key, set()).add(variant)
        return out

    # ------------------------------------------------------------------ writing
    def _header(self) -> str:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(self._names)
        return buf.getvalue()

    def _lines(self, rows: Iterable[dict]) -> list[str]:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        for r in rows:
            w.writerow([_format(r[n], COLUMNS[n]) for n in self._names])
        return [buf.getvalue()]

    def append(self, rows: list[dict]) -> None:
        """Append one task's rows (one block) and make them durable before returning."""
        if not rows:
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        new = not self.path.exists() or self.path.stat().st_size == 0
        data = (self._header() if new else "") + "".join(self._lines(rows))
        with open(self.path, "a", encoding="utf-8") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())

