"""The package layout keeps its import direction (read with :mod:`ast`, no
import executed):

- nothing in ``data/``, ``datasets/``, ``transforms/``, ``semantics/`` or
  ``pipelines/`` imports ``satagraph.nn``, ``satagraph.losses`` or
  ``satagraph.metrics``, at module level or inside a function;
- the module-level imports between the top-level parts of ``satagraph``
  (subpackages and top-level modules) form no cycle;
- every ``satagraph.*`` target of a docstring role (``:func:``,
  ``:class:``, ``:mod:`` ...) and every ``satagraph.*`` name README.md
  quotes is a module, or a name one defines (a renamed module left
  ``satagraph.quality`` behind).
"""
from __future__ import annotations

import ast
import gc
import re
from collections import defaultdict
from functools import lru_cache
from pathlib import Path
from typing import Dict, Iterator, List, Set, Tuple

PACKAGE = Path(__file__).resolve().parents[1] / "satagraph"
README = PACKAGE.parent / "README.md"
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


#: A docstring role's absolute target (``~`` and a call's ``()`` dropped).
ROLE_TARGET = re.compile(r":(?:func|class|meth|data|mod|attr|exc):`~?(satagraph(?:\.\w+)+)(?:\(\))?`")


def _members(body: List[ast.stmt]) -> Dict[str, ast.AST]:
    """The names a module or class body defines (in ``if`` / ``try`` blocks
    too)."""
    out: Dict[str, ast.AST] = {}
    for node in body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out[node.name] = node
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            out.update({n.id: node for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)})
        elif isinstance(node, ast.If):
            out.update(_members(node.body + node.orelse))
        elif isinstance(node, ast.Try):
            out.update(_members(node.body + node.orelse + [s for h in node.handlers for s in h.body]))
    return out


@lru_cache(maxsize=None)
def _aliases(module: str) -> Dict[str, str]:
    """Names a module imports (-> what they name), and a lazy package's
    exports (:mod:`satagraph._lazy`: names it lists that a submodule
    defines)."""
    tree = dict(_modules())[module]
    out: Dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            names = _imported(node, module)
            out.update({a.asname or a.name: full for a, full in zip(node.names, names[1:])})
        elif isinstance(node, ast.Import):
            out.update({a.asname or a.name.split(".")[0]: a.asname and a.name or a.name.split(".")[0]
                        for a in node.names})
    if "lazy_exports" in ast.unparse(tree):
        listed = {n.value for n in ast.walk(tree)
                  if isinstance(n, ast.Constant) and isinstance(n.value, str)}
        for sub, subtree in _modules():
            if sub.startswith(module + "."):
                for name in listed & set(_members(subtree.body)):
                    out.setdefault(name, f"{sub}.{name}")
    return out


def _resolves(dotted: str, hops: int = 0) -> bool:
    """Whether ``satagraph.x.y.Name.attr`` is a module of the package or a
    name defined there (imports and lazy exports followed; a class's
    attributes are its body's, ``self.attr`` assignments, or inherited
    where it has bases)."""
    trees = dict(_modules())
    parts = dotted.split(".")
    cut = next((i for i in range(len(parts), 0, -1) if ".".join(parts[:i]) in trees), 0)
    if not cut:
        return False
    module, rest = ".".join(parts[:cut]), parts[cut:]
    if not rest:
        return True
    node = _members(trees[module].body).get(rest[0])
    if node is None:
        alias = _aliases(module).get(rest[0])
        if alias is None or hops > 8:
            return False
        return not alias.startswith("satagraph") or _resolves(".".join([alias] + rest[1:]), hops + 1)
    for attr in rest[1:]:
        if not isinstance(node, ast.ClassDef):
            return False
        inner = _members(node.body)
        if attr not in inner:
            return bool(re.search(rf"\bself\.{attr}\b", ast.unparse(node)) or node.bases)
        node = inner[attr]
    return True


def test_docstring_targets_resolve():
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        bad += [f"{path.relative_to(PACKAGE.parent)}:{text.count(chr(10), 0, m.start()) + 1}: "
                f"{m.group(0)}" for m in ROLE_TARGET.finditer(text) if not _resolves(m.group(1))]
    readme = README.read_text(encoding="utf-8")
    names = {n for quoted in re.findall(r"`([^`\n]+)`", readme)
             for n in re.findall(r"\bsatagraph(?:\.\w+)+", quoted)}
    bad += [f"README.md: {name}" for name in sorted(names) if not _resolves(name)]
    assert not bad, "\n".join(bad)


def test_target_check_finds_a_missing_name():
    assert _resolves("satagraph.pipelines.quality.retarget_quality")
    assert _resolves("satagraph.data.FrameBatch")  # a lazy export
    assert not _resolves("satagraph.quality.retarget_quality")
    assert not _resolves("satagraph.pipelines.quality.no_such_function")
