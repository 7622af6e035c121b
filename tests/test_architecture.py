"""The package's shape: imports run one way (the pipeline's layers), no module imports itself
through others, and no code outside ``groupoid/`` asks which factor it holds."""

from __future__ import annotations

import ast
from pathlib import Path

import grimp
import pytest
from importlinter.cli import EXIT_STATUS_SUCCESS, lint_imports

PACKAGE = Path(__file__).resolve().parent.parent / "ocgroupoid"
FACTOR_CLASSES = {"Factor", "LieGroupFactor", "Pair", "SphereAction"}


def test_layers_contract_is_kept() -> None:
    """The import-linter contract of pyproject.toml (cli > sweep | bench | mpc > files |
    export | plotting > systems > solve | simulation > verify > nlp > model > groupoid >
    lie)."""
    status = lint_imports(config_filename=str(PACKAGE.parent / "pyproject.toml"), no_cache=True,
                          no_logo=True)
    assert status == EXIT_STATUS_SUCCESS


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
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
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_cycle_finder_finds_a_cycle() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycles() -> None:
    g = grimp.build_graph("ocgroupoid", exclude_type_checking_imports=True)
    graph = {m: set(g.find_modules_directly_imported_by(m)) for m in g.modules}
    assert cycles(graph) == []


def factor_isinstance_calls(source: str) -> list[int]:
    """Lines of ``isinstance``/``issubclass`` calls whose class argument names a factor class."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and \
                node.func.id in ("isinstance", "issubclass") and len(node.args) == 2:
            names = {n.id if isinstance(n, ast.Name) else n.attr
                     for n in ast.walk(node.args[1]) if isinstance(n, (ast.Name, ast.Attribute))}
            if names & FACTOR_CLASSES:
                lines.append(node.lineno)
    return lines


def test_the_check_sees_a_factor_dispatch() -> None:
    assert factor_isinstance_calls("if isinstance(f, (Pair, og.SphereAction)):\n    pass") == [1]
    assert factor_isinstance_calls("isinstance(g, Groupoid)") == []


@pytest.mark.parametrize("path", sorted(p for p in PACKAGE.rglob("*.py")
                                        if "groupoid" not in p.relative_to(PACKAGE).parts[:1]),
                         ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_factor_dispatch_outside_groupoid(path: Path) -> None:
    """Factors own what differs between them (guesses, rminus, samples, packing, display)."""
    assert factor_isinstance_calls(path.read_text()) == []
