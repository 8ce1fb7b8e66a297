"""Layering contracts: curv is pure numerics; the viewer's document model holds no Qt or VTK."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_import_linter_contracts_hold():
    lint = Path(sys.executable).with_name("lint-imports")
    if not lint.exists():
        pytest.skip("import-linter is not installed (install the 'test' extra)")
    out = subprocess.run([str(lint), "--config", str(ROOT / "pyproject.toml")], cwd=ROOT,
                         capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stdout + out.stderr
    assert "curv is pure numerics" in out.stdout and "KEPT" in out.stdout


def test_importing_every_curv_module_loads_no_gui_toolkit():
    code = (
        "import importlib, pkgutil, sys, curv\n"
        "for m in pkgutil.walk_packages(curv.__path__, 'curv.'):\n"
        "    importlib.import_module(m.name)\n"
        "bad = sorted(k for k in sys.modules if k.split('.')[0] in "
        "{'PySide6', 'PyQt5', 'PyQt6', 'vtk', 'vtkmodules', 'pyvista', 'pyvistaqt', 'superqt', 'app'})\n"
        "print(bad)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_every_package_folder_ships():
    """pyproject lists its packages by hand: a new folder of curv or app missing there would be left out of the wheel."""
    import tomllib

    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for top in ("curv", "app")
             for p in (ROOT / top).rglob("__init__.py") if "__pycache__" not in p.parts}
    assert found <= listed, sorted(found - listed)


def test_parallel_kernels_are_declared_and_launched_through_the_jit_owner():
    """numba's workqueue layer aborts the process when two threads launch parallel kernels at once
    (the viewer's workers do): every parallel kernel is ``@jit_parallel`` and every call of one goes
    through ``launch``, which takes the one lock (curv.core.jit)."""
    import re

    sources = {p: p.read_text() for p in (ROOT / "curv").rglob("*.py") if "__pycache__" not in p.parts}
    jit_module = ROOT / "curv" / "core" / "jit.py"
    raw = [str(p.relative_to(ROOT)) for p, s in sources.items() if p != jit_module and "parallel=True" in s]
    assert not raw, f"parallel kernels declared outside curv.core.jit: {raw}"
    kernels = {m.group(1) for s in sources.values()
               for m in re.finditer(r"^@jit_parallel\s*\ndef (\w+)", s, flags=re.MULTILINE)}
    assert len(kernels) > 10


    def seen(s: str) -> set:
        """The kernels a module's source can call: not those it shadows with a plain function."""
        plain = {m.group(1) for m in re.finditer(r"^(?!@jit_parallel\s*\n)[^\n]*\n\s*def (\w+)\(", s,
                                                 flags=re.MULTILINE)}
        own = {m.group(1) for m in re.finditer(r"^@jit_parallel\s*\ndef (\w+)", s, flags=re.MULTILINE)}
        return kernels - (plain - own)

    direct = [f"{p.relative_to(ROOT)}:{i}: {line.strip()}"
              for p, s in sources.items() for name in seen(s) for i, line in enumerate(s.splitlines(), 1)
              if re.search(rf"(?<![\w.]){name}\(", line) and not line.lstrip().startswith("def ")
              and f"launch({name}" not in line]
    assert not direct, "parallel kernels called without launch:\n" + "\n".join(direct)


def _shape():
    """benchmarks/code_shape.py, the one counter of the code's shape."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("code_shape", ROOT / "benchmarks" / "code_shape.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


WIDE_LEFT: set[str] = set()
"""Modules whose numba functions may still take more than 10 positional parameters: none is left;
a module put here must say why."""

LONG_LEFT: set[str] = set()
"""Modules that may still run over 500 lines (work under way); take one out when it is split."""


def test_numba_functions_take_at_most_ten_positional_parameters():
    """Arrays travel as a few bundles (tuples, namedtuples), not as long argument lists."""
    shape = _shape()
    wide = {f"{path}:{name} ({n})" for path, name, n in shape.numba_functions(ROOT / "curv")
            if n > shape.MAX_PARAMETERS and path not in WIDE_LEFT}
    assert not wide, sorted(wide)
    fits = [f for f in shape.numba_functions(ROOT / "curv") if f[0].startswith(("curv/estimators/_fit_driver",
                                                                               "curv/uncertainty/"))]
    assert len(fits) > 20  # the counter sees the fits' kernels and helpers


def test_modules_stay_short():
    shape = _shape()
    lines = {**shape.module_lines(ROOT / "curv"), **shape.module_lines(ROOT / "app")}
    long = {f"{path} ({n})" for path, n in lines.items() if n > shape.MAX_LINES and path not in LONG_LEFT}
    assert not long, sorted(long)


KIND_OWNERS = {"curv/core/support.py", "curv/convert.py"}
"""Where the input kinds may be told apart by their classes: the support provider (the one dispatch,
``support_of``) and the public boundary that turns other libraries' objects into a Mesh or a PointCloud."""

KIND_LEFT: dict[str, int] = {}
"""Modules other than the provider and the public boundary that may still tell the kinds apart
themselves, with how many places: none is left; a module put here must say why."""


def test_input_kinds_are_told_apart_by_the_support_provider():
    """A new input kind is one provider class (curv/core/support.py), not a search through the modules."""
    shape = _shape()
    sites = shape.kind_checks(ROOT / "curv")
    assert any(path == "curv/core/support.py" for path, _ in sites)  # the counter sees the one dispatch
    per_module: dict = {}
    for path, line in sites:
        if path not in KIND_OWNERS:
            per_module.setdefault(path, []).append(line)
    extra = {path: lines for path, lines in per_module.items() if len(lines) > KIND_LEFT.get(path, 0)}
    assert not extra, f"ask curv.core.support.support_of(shape) instead: {extra}"

