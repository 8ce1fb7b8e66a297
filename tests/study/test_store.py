"""The results file: exact round trip, repair of a file cut short, and what counts as done."""

from __future__ import annotations

import numpy as np

from curv.study.store import ResultsFile, block_id
from curv.study.table import COLUMNS, Table


def _rows(key, variants, value=0.1):
    bid = block_id(key, variants)
    base = dict(zip(("seed", "function", "density", "irregularity", "noise", "sample"), key))
    out = []
    for i, v in enumerate(variants):
        r = {name: (0 if typ is int else 0.0 if typ is float else "") for name, typ in COLUMNS.items()}
        r.update(base, variant=v, method=v.split(":")[0], range=int(v[-1]), smooth="none",
                 rms_erel=value / 3 + i, median_erel=float("nan"), block=bid, block_rows=len(variants))
        out.append(r)
    return out


KEY_A = (0, "quadratic", 217, 0.0, 0.0, 0)
KEY_B = (0, "quadratic", 217, 0.0, 1.0, 0)


def test_round_trip_is_bit_exact(tmp_path):
    f = ResultsFile(tmp_path / "r.csv")
    f.append(_rows(KEY_A, ["nc:R1", "mru:R2"]))
    t = f.load()
    assert len(t) == 2
    assert t["rms_erel"][0] == 0.1 / 3 and t["rms_erel"][1] == 0.1 / 3 + 1  # repr round trip
    assert np.isnan(t["median_erel"]).all()
    assert f.done() == {KEY_A: {"nc:R1", "mru:R2"}}


def test_torn_last_line_and_incomplete_block_are_dropped(tmp_path):
    path = tmp_path / "r.csv"
    f = ResultsFile(path)
    f.append(_rows(KEY_A, ["nc:R1", "mru:R2"]))
    f.append(_rows(KEY_B, ["nc:R1", "mru:R2"]))
    text = path.read_text()
    path.write_text(text[: len(text) - 40])  # a crash in the middle of the last block's last row
    assert f.done() == {KEY_A: {"nc:R1", "mru:R2"}}
    # the file was repaired: it ends on a complete line, and appending works again
    assert path.read_text().endswith("\n")
    f.append(_rows(KEY_B, ["nc:R1", "mru:R2"]))
    assert set(f.done()) == {KEY_A, KEY_B}
    assert len(f.load()) == 4


def test_a_damaged_field_drops_its_block_and_keeps_the_rest(tmp_path):
    path = tmp_path / "r.csv"
    f = ResultsFile(path)
    f.append(_rows(KEY_A, ["nc:R1", "mru:R2"]))
    f.append(_rows(KEY_B, ["nc:R1", "mru:R2"]))
    lines = path.read_text().splitlines(keepends=True)
    names = list(COLUMNS)
    fields = lines[1].split(",")
    fields[names.index("rms_erel")] = "0.0x3"  # a corrupted number in the first row of block A
    lines[1] = ",".join(fields)
    path.write_text("".join(lines))
    t = f.load()
    assert len(t) == 2 and set(t["noise"].tolist()) == {1.0}
    assert f.done() == {KEY_B: {"nc:R1", "mru:R2"}}
    assert t["rms_erel"][0] == 0.1 / 3  # the kept rows are still bit-exact


def test_table_grouping_and_selection():
    t = Table.from_rows([
        {"variant": "a", "density": 1, "rms_erel": 1.0}, {"variant": "a", "density": 1, "rms_erel": 3.0},
        {"variant": "a", "density": 2, "rms_erel": np.nan}, {"variant": "b", "density": 1, "rms_erel": 5.0},
    ])
    g = t.group(["variant", "density"], "rms_erel")
    assert g[("a", 1)] == 2.0 and np.isnan(g[("a", 2)]) and g[("b", 1)] == 5.0
    assert len(t.where(variant="a", density=(1, 2))) == 3
    assert len(t.where(rms_erel=np.isfinite)) == 3
