"""The house in layers: no import cycle in rbhyst (imports inside functions counted), and no
module importing from a layer above its own. The layers, lowest first, are the folders in the
order the data goes: files, model, solve, results, analyses, report; then the top (api, cli,
and the documented import paths rbhyst.response and rbhyst.sweep)."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "rbhyst"

#: module prefix -> layer (lowest 0); a module belongs to its longest matching prefix
LAYERS = {"rbhyst._version": 0, "rbhyst.errors": 0, "rbhyst.allocator": 0, "rbhyst.cores": 0, "rbhyst.files": 1, "rbhyst.model": 2, "rbhyst.solve": 3,
          "rbhyst.results": 4, "rbhyst.analyses": 5, "rbhyst.report": 6}
TOP = 7


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path, modules: set[str]) -> set[str]:
    """Every rbhyst module ``path`` imports, wherever the import stands (functions included)."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in modules else target)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return {m for m in found if m in modules and m != name}


def graph() -> dict[str, set[str]]:
    paths = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    modules = set(paths)
    return {m: imports_of(p, modules) for m, p in paths.items()}


def layer(module: str) -> int:
    best = max((k for k in LAYERS if module == k or module.startswith(k + ".")), key=len, default=None)
    return TOP if best is None else LAYERS[best]


def cycles(g: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(g[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(g):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle():
    assert cycles(graph()) == []


def test_no_module_imports_from_a_layer_above_its_own():
    g = graph()
    upward = sorted(f"{a} (layer {layer(a)}) imports {b} (layer {layer(b)})"
                    for a, deps in g.items() for b in deps if layer(b) > layer(a))
    assert upward == []


def test_every_module_says_what_it_holds():
    missing = [module_name(p) for p in PACKAGE.rglob("*.py") if ast.get_docstring(ast.parse(p.read_text())) is None]
    assert missing == []


def test_the_check_finds_a_cycle_and_an_upward_import():
    g = {"rbhyst.model.a": {"rbhyst.model.b"}, "rbhyst.model.b": {"rbhyst.model.a"}, "rbhyst.solve.c": set()}
    assert cycles(g) == [["rbhyst.model.a", "rbhyst.model.b"]]
    assert layer("rbhyst.solve.kernels.loop") == 3 > layer("rbhyst.model.deck") == 2
    assert layer("rbhyst.cli") == layer("rbhyst.sweep") == TOP


def test_the_kernels_build_with_numpy_and_numba_alone():
    """setup.py compiles the kernels where only the build's requirements are installed: the
    modules they come from must not import the deck's or the report's dependencies."""
    import subprocess
    import sys

    code = """
import builtins, importlib
real = builtins.__import__
def guard(name, *args, **kwargs):
    if name.split('.')[0] in ('yaml', 'pydantic', 'pydantic_core', 'scipy', 'matplotlib', 'typer', 'tomli_w', 'rich'):
        raise ImportError('not in the build environment: ' + name)
    return real(name, *args, **kwargs)
builtins.__import__ = guard
from rbhyst.solve.kernels.aot import EXPORTS, source_stamp
for module, _, _ in EXPORTS.values():
    importlib.import_module(module)
source_stamp()
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=PACKAGE.parent)
    assert done.returncode == 0, done.stderr


def test_a_long_function_says_why():
    """Over 80 lines, a function says in its docstring why it is long (or is split)."""
    long = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.end_lineno - node.lineno >= 80:
                if "long" not in (ast.get_docstring(node) or "").lower():
                    long.append(f"{module_name(path)}.{node.name}")
    assert long == []
