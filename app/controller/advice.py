"""Running the advisor on the document's mesh (in a worker thread)."""

from __future__ import annotations

import time

from curv.advice.advisor import FIT_METHOD, advise
from curv.estimators import ESTIMATORS
from curv.core.jit import COMPILE_MESSAGE, compile_pending

from app.model import AdviceRecord

__all__ = ["advise_mesh", "advice_compile_note"]


def advise_mesh(mesh, *, mesh_serial: int, source_label: str) -> AdviceRecord:
    """``curv.advise(mesh)``, timed, as an :class:`AdviceRecord`; runs in a worker thread.

    Parameters
    ----------
    mesh : curv.Mesh
    mesh_serial : int
        The document's :attr:`~app.model.Document.mesh_serial` for ``mesh``.
    source_label : str
        What the mesh is, for the panel.

    Raises
    ------
    curv.MeshError
        When the advisor cannot measure the mesh (e.g. no vertex can be fitted).
    """
    t0 = time.perf_counter()
    advice = advise(mesh)
    return AdviceRecord(mesh_serial, source_label, advice, seconds=time.perf_counter() - t0)


def advice_compile_note() -> str:
    """The first-run compile message when the advisor's measuring fit will compile its kernels, else ``""``."""
    spec = ESTIMATORS.get(FIT_METHOD)
    return COMPILE_MESSAGE if spec is not None and compile_pending(spec.kernels) else ""
