"""The package layout keeps its import direction (read with :mod:`ast`, no
import executed):

- nothing in ``data/``, ``datasets/``, ``transforms/``, ``semantics/`` or
  ``pipelines/`` imports ``satagraph.nn``, ``satagraph.losses`` or
  ``satagraph.metrics``, at module level or inside a function;
- the module-level imports between the top-level parts of ``satagraph``
  (subpackages and top-level modules) form no cycle.
"""
from __future__ import annotations

import ast
import gc
from collections import defaultdict
from functools import lru_cache
from pathlib import Path
from typing import Dict, Iterator, List, Set, Tuple

PACKAGE = Path(__file__).resolve().parents[1] / "satagraph"
#: Parts that describe and move motion; they know nothing of models.
LOWER = ("data", "datasets", "transforms", "semantics", "pipelines")
#: What they must not import.
MODEL = ("satagraph.nn", "satagraph.losses", "satagraph.metrics")


@lru_cache(maxsize=None)
def _modules() -> Tuple[Tuple[str, ast.Module], ...]:
    """Every module of the package, parsed once (the tests only read the
    trees). The collector waits: the trees' million nodes hold no cycle,
    and walking the worker's whole heap each time they pass its thresholds
    took longer than the parse."""
    out = []
    enabled = gc.isenabled()
    gc.disable()
    try:
        for path in sorted(PACKAGE.rglob("*.py")):
            parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out.append((".".join(parts), ast.parse(path.read_text(encoding="utf-8"))))
    finally:
        if enabled:
            gc.enable()
    return tuple(out)


def _imported(node: ast.AST, module: str) -> List[str]:
    """The satagraph modules (or names) an import statement names."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if isinstance(node, ast.ImportFrom):
        if node.level:  # relative: resolve against the importing package
            base = module.split(".")[:-node.level]
            name = ".".join(base + ([node.module] if node.module else []))
        else:
            name = node.module or ""
        return [name] + [f"{name}.{a.name}" for a in node.names]
    return []


def _part(module: str) -> str:
    """``satagraph.data.features`` -> ``data``; ``satagraph`` -> ``satagraph``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def _module_level(tree: ast.Module) -> Iterator[ast.AST]:
    """Imports executed on import: the module body, including ``if`` / ``try``
    blocks, but not functions, classes or ``if TYPE_CHECKING:``."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, ast.If):
            if "TYPE_CHECKING" not in ast.unparse(node.test):
                stack += node.body + node.orelse
        elif isinstance(node, ast.Try):
            stack += node.body + node.orelse + node.finalbody
            for handler in node.handlers:
                stack += handler.body


def test_lower_parts_import_no_model_code():
    bad = []
    for module, tree in _modules():
        if _part(module) not in LOWER:
            continue
        for node in ast.walk(tree):
            for name in _imported(node, module):
                if any(name == m or name.startswith(m + ".") for m in MODEL):
                    bad.append(f"{module}:{node.lineno} imports {name}")
    assert not bad, "\n".join(bad)


def _part_graph() -> Dict[str, Set[str]]:
    graph: Dict[str, Set[str]] = defaultdict(set)
    for module, tree in _modules():
        for node in _module_level(tree):
            for name in _imported(node, module):
                if name.startswith("satagraph.") and _part(name) != _part(module):
                    graph[_part(module)].add(_part(name))
    return graph


def _cycles(graph: Dict[str, Set[str]]) -> List[List[str]]:
    """Strongly connected components of more than one node (Tarjan)."""
    index: Dict[str, int] = {}
    low: Dict[str, int] = {}
    stack: List[str] = []
    found: List[List[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in graph.get(node, ()):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_import_cycle_between_parts():
    assert _cycles(_part_graph()) == []


def test_cycle_check_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_layout_has_its_parts():
    parts = {_part(module) for module, _ in _modules()}
    assert set(LOWER) | {"nn", "losses", "metrics", "cli", "experiment", "utils"} <= parts


def test_models_and_losses_read_layouts_from_typing_not_data():
    """Networks and losses know the feature layout from satagraph.typing,
    not from the module that computes features."""
    bad = []
    for module, tree in _modules():
        if _part(module) not in ("nn", "losses"):
            continue
        for node in ast.walk(tree):
            for name in _imported(node, module):
                if name.startswith("satagraph.data"):
                    bad.append(f"{module}:{node.lineno} imports {name}")
    assert not bad, "\n".join(bad)
