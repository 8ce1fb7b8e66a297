"""Running the advisor on the document's mesh or point cloud (in a worker thread, step by step)."""

from __future__ import annotations

import time

from curv.advice.advisor import FIT_METHOD
from curv.advice.advising import iter_advise
from curv.core.jit import COMPILE_MESSAGE, Progress, compile_pending
from curv.estimators import ESTIMATORS

from app.model import AdviceRecord

__all__ = ["advise_mesh", "advise_steps", "advice_compile_note"]


def advise_steps(mesh, *, mesh_serial: int, source_label: str):
    """``curv.iter_advise(mesh)`` as a generator worker: yields :class:`curv.core.jit.Progress`
    (fraction done and what runs; every yield is where a cancel takes effect) and returns an
    :class:`AdviceRecord`.

    Parameters
    ----------
    mesh : curv.Mesh or curv.PointCloud
    mesh_serial : int
        The document's :attr:`~app.model.Document.mesh_serial` for ``mesh``.
    source_label : str
        What the input is, for the panel.

    Raises
    ------
    curv.MeshError
        When the advisor cannot measure the input (e.g. no vertex can be fitted).
    """
    t0 = time.perf_counter()
    advice = yield from iter_advise(mesh)
    yield Progress(1.0, "done")
    return AdviceRecord(mesh_serial, source_label, advice, seconds=time.perf_counter() - t0)


def advise_mesh(mesh, *, mesh_serial: int, source_label: str) -> AdviceRecord:
    """:func:`advise_steps` run to its end (no progress, no cancel)."""
    from curv.core.jit import run_to_end

    return run_to_end(advise_steps(mesh, mesh_serial=mesh_serial, source_label=source_label))


def advice_compile_note() -> str:
    """The first-run compile message when the advisor's measuring fit will compile its kernels, else ``""``."""
    spec = ESTIMATORS.get(FIT_METHOD)
    return COMPILE_MESSAGE if spec is not None and compile_pending(spec.kernels) else ""
