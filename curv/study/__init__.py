"""The paper's evaluation study (§5): test meshes, error measures, a resumable runner, the report.

>>> from curv.study import StudySettings, iter_study, write_report      # doctest: +SKIP
>>> settings = StudySettings(samples=2, densities=(217, 817))
>>> for progress in iter_study(settings, "out"):                        # one yield per finished mesh
...     print(f"{progress.done}/{progress.total}")
>>> table = run(settings, "out")              # the same, to the end; finished meshes are skipped
>>> write_report(table, settings, "out")      # table1.md, report.md, fig8-10.png

Modules: ``protocol`` (grid, variants, tasks and their random streams), ``testmesh`` (meshes of
§5.1), ``metrics`` (eq. 5.2 and companions), ``tasks`` (one mesh, all variants), ``store`` and
``table`` (the results file), ``executors`` (local pool or Dask), ``runner`` (``iter_study``),
``analysis``, ``claims``, ``figures``, ``report`` and ``cli``.
"""

from __future__ import annotations

from .protocol import Preset, StudySettings, Task, Variant, parse_variants, preset_settings, study_variants
from .runner import Progress, iter_study, run, select
from .table import Table

__all__ = [
    "Preset", "StudySettings", "Task", "Variant", "parse_variants", "preset_settings", "study_variants",
    "Progress", "iter_study", "run", "select", "Table", "write_report",
]


def __getattr__(name):
    if name == "write_report":  # matplotlib loads only when a report is written
        from .report import write_report

        return write_report
    raise AttributeError(f"module 'curv.study' has no attribute {name!r}")
