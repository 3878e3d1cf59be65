"""The import graph of the package follows the stage order of docs/architecture.md: no module
imports a later stage, and no modules import each other in a cycle.

Every ``import`` and ``from ... import`` of every module under src/masonry_dem counts, those
inside functions included. Imports under ``if TYPE_CHECKING:`` (annotations only: they never
run) are exempt from the stage order but count for the cycles: two modules that name each
other's types are one module in two files. ``python tests/test_architecture.py`` prints the
upward imports and the cycles.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "masonry_dem"

# The stages in import order (docs/architecture.md): a module may import its own stage and the
# stages before it. A module belongs to the longest prefix listed.
STAGES: tuple[tuple[str, ...], ...] = (
    (
        "_arrays",
        "_docstrings",
        "_lazy",
        "_parameters",
        "_progress",
        "_signals",
        "_threads",
        "_toml",
        "_validation",
        "_version",
        "jit",
    ),
    ("geometry",),
    ("model",),
    ("assembly", "constitutive"),
    ("results", "streamed_history"),
    ("solvers",),
    ("mechanism",),
    ("assessment",),
    ("cases",),
    ("export",),
    ("analysis",),
    ("run_case",),
    ("studies",),
    ("cli", "_supervisor", "paraview_states", ""),
)


def modules(package: Path = PACKAGE) -> dict[str, Path]:
    """Every module by its dotted name below the package (the package itself is "")."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _type_checking_only(tree: ast.AST) -> set[int]:
    """The ids of the import nodes inside ``if TYPE_CHECKING:`` blocks."""
    ids: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If):
            test = node.test
            name = test.id if isinstance(test, ast.Name) else getattr(test, "attr", None)
            if name == "TYPE_CHECKING":
                for stmt in node.body:
                    ids.update(id(n) for n in ast.walk(stmt))
    return ids


def imports(package: Path = PACKAGE, annotations: bool = False) -> dict[str, set[str]]:
    """The package's modules each module imports (``from pkg import sub`` counts as the
    submodule; ``from module import name`` as the module); with ``annotations``, those under
    ``if TYPE_CHECKING:`` too."""
    mods = modules(package)

    def resolve(name: str) -> str | None:
        while name not in mods:
            if not name:
                return None
            name = name.rpartition(".")[0]
        return name

    graph: dict[str, set[str]] = {}
    for mod, path in mods.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        exempt = set() if annotations else _type_checking_only(tree)
        is_package = path.name == "__init__.py"
        here = mod if is_package else mod.rpartition(".")[0]
        found: set[str | None] = set()
        for node in ast.walk(tree):
            if id(node) in exempt:
                continue
            if isinstance(node, ast.Import):
                for alias in node.names:
                    top, _, rest = alias.name.partition(".")
                    if top == "masonry_dem":
                        found.add(resolve(rest))
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".") if here else []
                    base = base[: len(base) - (node.level - 1)]
                    full = ".".join(base + ([node.module] if node.module else []))
                else:
                    top, _, full = (node.module or "").partition(".")
                    if top != "masonry_dem":
                        continue
                for alias in node.names:
                    sub = f"{full}.{alias.name}" if full else alias.name
                    found.add(sub if sub in mods else resolve(full))
        found.discard(None)
        found.discard(mod)
        graph[mod] = {m for m in found if m is not None}
    return graph


def stage(module: str) -> int:
    """The index of the stage ``module`` belongs to."""
    best, rank = -1, -1
    for i, prefixes in enumerate(STAGES):
        for prefix in prefixes:
            if prefix == module or module.startswith(prefix + ".") or prefix == "":
                if len(prefix) > best:
                    best, rank = len(prefix), i
    return rank


def upward(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """The imports of a later stage, as (importer, imported)."""
    return sorted((a, b) for a, bs in graph.items() for b in bs if stage(b) > stage(a))


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    sys.setrecursionlimit(max(10_000, sys.getrecursionlimit()))

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def _name(module: str) -> str:
    return f"masonry_dem.{module}" if module else "masonry_dem"


def test_every_module_has_a_stage():
    assert all(stage(m) >= 0 for m in modules())


def test_no_module_imports_a_later_stage():
    found = [f"{_name(a)} -> {_name(b)}" for a, b in upward(imports())]
    assert not found, "imports against the stage order:\n" + "\n".join(found)


def test_no_import_cycle():
    """Not even through the imports of annotations."""
    found = [" <-> ".join(map(_name, c)) for c in cycles(imports(annotations=True))]
    assert not found, "import cycles:\n" + "\n".join(found)


def test_the_checks_find_an_upward_import_and_a_cycle(tmp_path):
    pkg = tmp_path / "masonry_dem"
    (pkg / "solvers").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "solvers" / "__init__.py").write_text("")
    (pkg / "results.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from masonry_dem.export import writer\n"
        "def f():\n    from .solvers import a\n"
    )
    (pkg / "solvers" / "a.py").write_text("from . import b\n")
    (pkg / "solvers" / "b.py").write_text("import masonry_dem.solvers.a\n")
    (pkg / "model.py").write_text("from masonry_dem import geometry\n")
    (pkg / "export").mkdir()
    (pkg / "export" / "__init__.py").write_text("")
    (pkg / "export" / "writer.py").write_text("from masonry_dem import results\n")
    graph = imports(pkg)
    assert graph["results"] == {"solvers.a"}  # the import in a function, not the exempt one
    # results comes before solvers; a name of the package is the package, the last stage
    assert upward(graph) == [("model", ""), ("results", "solvers.a")]
    assert cycles(graph) == [["solvers.a", "solvers.b"]]
    # the annotations' import closes a cycle of its own
    assert imports(pkg, annotations=True)["results"] == {"solvers.a", "export.writer"}
    assert cycles(imports(pkg, annotations=True)) == [
        ["export.writer", "results"],
        ["solvers.a", "solvers.b"],
    ]


if __name__ == "__main__":
    graph = imports()
    up, cyc = upward(graph), cycles(imports(annotations=True))
    print(f"{len(up)} upward imports:")
    for a, b in up:
        print(f"  {_name(a)} -> {_name(b)}")
    print(f"{len(cyc)} cycles (the imports of annotations counted):")
    for c in cyc:
        print("  " + " <-> ".join(map(_name, c)))
