"""The viewer gives freed buffers back to the system (app.heap; glibc's allocator only)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

_PROBE = """
import ctypes, sys
import numpy as np
from app.heap import MMAP_THRESHOLD, release_free_memory, tune_allocator

class Info(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in
                "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]

libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = Info
tuned = tune_allocator() if sys.argv[1] == "tuned" else None
big = np.ones(16 << 20, np.uint8)  # freed: glibc would now serve up to 16 MB from its heaps
del big
before = libc.mallinfo2().hblkhd
buffer = np.ones(4 * MMAP_THRESHOLD, np.uint8)
own_pages = libc.mallinfo2().hblkhd - before >= buffer.nbytes
del buffer
print(tuned, own_pages, release_free_memory() in (True, False))
"""


def _probe(mode: str) -> str:
    out = subprocess.run([sys.executable, "-c", _PROBE, mode], cwd=ROOT, capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


@pytest.mark.skipif(not sys.platform.startswith("linux") or not hasattr(__import__("ctypes").CDLL(None), "mallinfo2"),
                    reason="glibc's allocator (mallinfo2) only")
def test_after_tuning_a_buffer_above_the_threshold_gets_pages_of_its_own():
    # untuned, the 16-MB buffer freed first raises glibc's threshold and the 4-MB one comes from
    # the heap, whose pages stay with the process when it is freed; tuned it is mapped on its own
    assert _probe("default") == "None False True"
    assert _probe("tuned") == "True True True"
