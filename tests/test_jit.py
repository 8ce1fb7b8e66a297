"""How kernels are launched: compile detection, chunked progress, threads."""

import importlib
import sys

import numpy as np
import pytest

from curv.core import jit as J


def test_compile_pending_until_the_kernel_is_compiled_and_cached(tmp_path, monkeypatch):
    (tmp_path / "fresh_kernel_module.py").write_text(
        "from curv.core.jit import jit\n\n@jit\ndef twice(x):\n    return 2 * x\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module("fresh_kernel_module")
    try:
        assert J.compile_pending([module.twice])
        assert module.twice(3) == 6
        assert not J.compile_pending([module.twice])
        # a new process would find it in the on-disk cache
        module.twice.overloads.clear()
        assert not J.compile_pending([module.twice])
    finally:
        sys.modules.pop("fresh_kernel_module", None)


def test_iter_chunks_covers_everything_once_in_order():
    seen = []
    fractions = list(J.iter_chunks(10_000, lambda lo, hi: seen.append((lo, hi))))
    assert seen[0][0] == 0 and seen[-1][1] == 10_000
    assert all(a[1] == b[0] for a, b in zip(seen, seen[1:]))
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    fixed = []
    list(J.iter_chunks(10, lambda lo, hi: fixed.append((lo, hi)), chunk=4))
    assert fixed == [(0, 4), (4, 8), (8, 10)]


def test_curv_threads_caps_the_kernel_threads(monkeypatch):
    monkeypatch.setenv("CURV_THREADS", "1")
    assert J.threads() == 1
    monkeypatch.setenv("CURV_THREADS", "999")
    assert 1 <= J.threads() <= J.numba.config.NUMBA_NUM_THREADS
    monkeypatch.setenv("CURV_THREADS", "x")
    assert J.threads() >= 1


def test_progress_is_a_float_with_a_message():
    p = J.Progress(0.25, J.COMPILE_MESSAGE)
    assert p == 0.25 and isinstance(p, float) and "first run only" in p.message
    assert J.Progress(0.5).message == ""
    assert np.isclose(float(p) + 0.25, 0.5)


def test_each_state_of_the_sources_has_its_own_kernel_cache(tmp_path):
    """A kernel's cache entry knows only its own file: a changed helper in another module must not
    let it load old machine code, so the cache folder follows every source file's contents."""
    from pathlib import Path

    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    (package / "kernel.py").write_text("from .sub.helper import h\n")
    (package / "sub" / "helper.py").write_text("def h(x):\n    return x\n")
    before = J.source_fingerprint(package)
    assert J.source_fingerprint(package) == before
    (package / "sub" / "helper.py").write_text("def h(x):\n    return 2 * x\n")  # the helper alone
    assert J.source_fingerprint(package) != before
    curv_sources = Path(J.__file__).resolve().parents[1]
    if not J.os.environ.get("NUMBA_CACHE_DIR"):
        assert Path(J.numba.config.CACHE_DIR).name == f"numba-{J.source_fingerprint(curv_sources)}"


def test_rescaled_maps_a_parts_fractions_keeps_messages_and_returns_its_value():
    from curv.core.jit import Progress, rescaled, run_to_end

    closed = []

    def part():
        try:
            yield 0.5
            yield Progress(1.0, "compiling")
            return "result"
        finally:
            closed.append(True)

    def whole():
        first = yield from rescaled(part(), 0.2, 0.6)
        second = yield from rescaled(part(), 0.6, 1.0)
        return first, second

    steps = []
    gen = whole()
    while True:
        try:
            steps.append(next(gen))
        except StopIteration as stop:
            assert stop.value == ("result", "result")
            break
    assert steps == pytest.approx([0.4, 0.6, 0.8, 1.0])
    assert [getattr(s, "message", "") for s in steps] == ["", "compiling", "", "compiling"]
    assert run_to_end(whole()) == ("result", "result")
    # a cancelled caller (the viewer closes its generator) closes the part it was in
    closed.clear()
    gen = rescaled(part(), 0.0, 1.0)
    next(gen)
    gen.close()
    assert closed == [True]
