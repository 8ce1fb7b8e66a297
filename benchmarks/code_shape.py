"""The shape of curv's code: the positional parameters of its numba functions and the length of its
modules (the project's rules: at most 10 parameters, bundles for the rest; at most about 500 lines).

Run by hand::

    .venv/bin/python benchmarks/code_shape.py            # curv/ and app/
    .venv/bin/python benchmarks/code_shape.py curv/estimators

It prints the numba functions (``@jit``, ``@jit_parallel``, ``@jit_inlined``, ``@njit``), how many take
more than 10 positional parameters and which, the modules over 500 lines, and the places that tell the
input kinds apart themselves (``isinstance(..., PointCloud)`` or ``Mesh``, ``is_points``) instead of asking
the support provider (``curv/core/support.py``). ``tests/test_architecture.py`` reads the same counts.
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAX_PARAMETERS = 10
MAX_LINES = 500
_NUMBA = {"jit", "jit_parallel", "jit_inlined", "njit"}
_KINDS = {"PointCloud", "Mesh"}


def _is_numba(decorator: ast.expr) -> bool:
    target = decorator.func if isinstance(decorator, ast.Call) else decorator
    name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
    return name in _NUMBA


def numba_functions(folder: Path) -> list[tuple[str, str, int]]:
    """``(module path relative to the repository, function name, positional parameters)`` of every
    numba-compiled function below ``folder``."""
    out = []
    for path in sorted(folder.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and any(_is_numba(d) for d in node.decorator_list):
                count = len(node.args.posonlyargs) + len(node.args.args)
                out.append((str(path.relative_to(ROOT)), node.name, count))
    return out


def _names(node: ast.expr) -> set[str]:
    """The class names an ``isinstance`` second argument holds (a name, an attribute, a tuple of them)."""
    if isinstance(node, ast.Tuple):
        return set().union(*(_names(e) for e in node.elts))
    return {node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")}


def kind_checks(folder: Path) -> list[tuple[str, int]]:
    """``(module path relative to the repository, line)`` of every place below ``folder`` that tells the
    input kinds apart itself: ``isinstance(x, PointCloud)`` or ``Mesh`` (alone or in a tuple), or a name
    or attribute ``is_points``."""
    out = []
    for path in sorted(folder.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            checks = (isinstance(node, ast.Call) and getattr(node.func, "id", "") == "isinstance"
                      and len(node.args) == 2 and _names(node.args[1]) & _KINDS)
            named = (isinstance(node, ast.Name) and node.id == "is_points") or (
                isinstance(node, ast.Attribute) and node.attr == "is_points")
            if checks or named:
                out.append((str(path.relative_to(ROOT)), node.lineno))
    return sorted(set(out))


def module_lines(folder: Path) -> dict[str, int]:
    """Lines of every module below ``folder``, by path relative to the repository."""
    return {str(p.relative_to(ROOT)): len(p.read_text(encoding="utf-8").splitlines())
            for p in sorted(folder.rglob("*.py")) if "__pycache__" not in p.parts}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="*", default=["curv", "app"])
    args = parser.parse_args(argv)
    for folder in args.folders:
        functions = numba_functions(ROOT / folder)
        wide = sorted((n, f"{p}:{name}") for p, name, n in functions if n > MAX_PARAMETERS)
        long = {p: n for p, n in module_lines(ROOT / folder).items() if n > MAX_LINES}
        print(f"{folder}: {len(functions)} numba functions, {len(wide)} over {MAX_PARAMETERS} positional parameters"
              f"{' (widest ' + str(wide[-1][0]) + ')' if wide else ''}; {len(long)} modules over {MAX_LINES} lines")
        for n, where in reversed(wide):
            print(f"  {n:3d}  {where}")
        for path, n in sorted(long.items(), key=lambda kv: -kv[1]):
            print(f"  {n:5d} lines  {path}")
        kinds = kind_checks(ROOT / folder)
        print(f"{folder}: {len(kinds)} places tell the input kinds apart themselves")
        for path, line in kinds:
            print(f"  {path}:{line}")


if __name__ == "__main__":
    main()
