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

from .table import COLUMNS, KEY_COLUMNS, Table

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
    def _read_rows(self) -> tuple[list[dict], bool]:
        """Parsed rows of complete blocks, and whether anything had to be dropped."""
        if not self.path.exists() or self.path.stat().st_size == 0:
            return [], False
        text = self.path.read_text()
        lines = text.splitlines(keepends=True)
        dropped = bool(lines) and not lines[-1].endswith("\n")
        if dropped:
            lines = lines[:-1]  # torn last line
        reader = csv.reader(io.StringIO("".join(lines)))
        header = next(reader, None)
        if header != self._names:
            raise ValueError(
                f"{self.path} has other columns than this version of curv writes; "
                "use a new --out directory (or move the old results away)"
            )
        rows = []
        for fields in reader:
            if len(fields) != len(self._names):
                dropped = True
                continue
            try:
                rows.append({n: _parse(f, COLUMNS[n]) for n, f in zip(self._names, fields)})
            except ValueError:
                dropped = True
        counts: dict[str, int] = {}
        for r in rows:
            counts[r["block"]] = counts.get(r["block"], 0) + 1
        complete = [r for r in rows if counts[r["block"]] == r["block_rows"]]
        return complete, dropped or len(complete) != len(rows)

    def load(self, *, repair: bool = True) -> Table:
        """All complete rows as a :class:`Table`.

        With ``repair``, a file holding torn or incomplete blocks is rewritten (atomically)
        without them, so that later appends start on a clean line.
        """
        rows, dirty = self._read_rows()
        if dirty and repair:
            tmp = self.path.with_suffix(self.path.suffix + ".tmp")
            tmp.write_text(self._header() + "".join(self._lines(rows)))
            os.replace(tmp, self.path)
        return Table.from_rows(rows)

    def done(self) -> dict[tuple, set[str]]:
        """``{task key: variant ids present}`` over the complete blocks (repairs the file)."""
        table = self.load()
        out: dict[tuple, set[str]] = {}
        for r in table.rows():
            key = tuple(r[k] for k in KEY_COLUMNS)
            key = (int(key[0]), key[1], int(key[2]), float(key[3]), float(key[4]), int(key[5]))
            out.setdefault(key, set()).add(r["variant"])
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

