"""The layout of the package: no import cycles, the bench wing out of the product, files of readable size.

The import graph is read from the sources (``ast``), every import counted, also those inside
functions: a lazy import that closes a cycle is still a cycle a reader must untangle.
"""

from __future__ import annotations

import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PKG = ROOT / "python" / "tribosweep"

#: Longest file outside the tests, in lines (the house rule is "about 700"; the scipy reference
#: oracle is one model written out once and stays whole).
MAX_LINES = 750


def module_name(path: pathlib.Path) -> str:
    rel = path.relative_to(PKG.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports_of(path: pathlib.Path) -> list[tuple[str, int]]:
    """Modules of the package that ``path`` imports, with the line, relative imports resolved."""
    me = module_name(path)
    package = me if path.name == "__init__.py" else me.rsplit(".", 1)[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("tribosweep"):
                continue
            for alias in node.names:  # "from . import x" imports the submodule x
                sub = f"{target}.{alias.name}"
                out.append((sub if _is_module(sub) else target, node.lineno))
        elif isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names if a.name.startswith("tribosweep")]
    return out


def _is_module(name: str) -> bool:
    rel = pathlib.Path(*name.split("."))
    return (PKG.parent / rel).with_suffix(".py").exists() or (PKG.parent / rel / "__init__.py").exists()


def graph() -> dict[str, set[str]]:
    g: dict[str, set[str]] = {}
    for path in PKG.rglob("*.py"):
        me = module_name(path)
        g.setdefault(me, set())
        for target, _ in imports_of(path):
            if target != me and _is_module(target):
                # Importing a.b.c runs the package a.b first: the edge to the package is the
                # one that can close a cycle through an __init__.
                g[me].add(target)
    return g


def find_cycle(g: dict[str, set[str]]) -> list[str] | None:
    """One cycle of the directed graph ``g`` (a list of nodes, first repeated last), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(n: str) -> list[str] | None:
        state[n] = 1
        stack.append(n)
        for m in sorted(g.get(n, ())):
            if state.get(m) == 1:
                return stack[stack.index(m) :] + [m]
            if m not in state:
                found = visit(m)
                if found:
                    return found
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(g):
        if n not in state:
            found = visit(n)
            if found:
                return found
    return None


def test_the_cycle_finder_finds_a_cycle_and_accepts_a_tree():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None


def test_the_package_has_no_import_cycle():
    g = graph()
    # The package __init__ re-exports names; that it imports its submodules is its job, and every
    # submodule "imports" it implicitly, so its edges are left out of the cycle check.
    g = {k: {m for m in v if m != "tribosweep"} for k, v in g.items() if k != "tribosweep"}
    assert len(g) > 30, "the package was not found"
    assert find_cycle(g) is None, f"import cycle: {' -> '.join(find_cycle(g))}"


def test_no_product_module_imports_the_bench_wing():
    """Only ``tribosweep bench`` (cli's bench handler) reaches tribosweep.bench."""
    offenders = []
    for path in PKG.rglob("*.py"):
        me = module_name(path)
        if me.startswith("tribosweep.bench"):
            continue
        for target, line in imports_of(path):
            if target.startswith("tribosweep.bench"):
                where = f"{path.relative_to(ROOT)}:{line}"
                if me == "tribosweep.cli" and _inside_function(path, line, "_run_bench"):
                    continue
                offenders.append(where)
    assert offenders == []


def _inside_function(path: pathlib.Path, line: int, name: str) -> bool:
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.FunctionDef) and node.name == name:
            return node.lineno <= line <= node.end_lineno
    return False


def test_import_tribosweep_loads_neither_the_bench_wing_nor_optional_dependencies():
    code = ("import sys, tribosweep, tribosweep.cli; "
            "print(sorted(m for m in sys.modules if m.startswith(('tribosweep.bench', 'matplotlib', 'dask', "
            "'scipy', 'numba', 'tqdm'))))")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("folder", ["python", "rust_core", "benches"])
def test_no_file_outside_the_tests_is_longer_than_the_limit(folder):
    long = []
    for path in (ROOT / folder).rglob("*"):
        if path.suffix not in (".py", ".rs") or "tests" in path.parts or path.name == "tests.rs":
            continue
        n = len(path.read_text().splitlines())
        if n > MAX_LINES:
            long.append(f"{path.relative_to(ROOT)}: {n}")
    assert long == []
