"""The package's import graph, drawn from the source (every import, function-local and
type-only ones included): no module or room (``retarget.X``) imports one that imports it
back, and the named lower floors know nothing of the upper ones."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CORE, PLUGINS = ROOT / "core", ROOT / "plugins"

FORBIDDEN = {
    "motion": {"registry", "kinds", "render", "env", "train", "cli", "plugins"},
    "kinds": {"registry", "train", "cli", "env", "eval", "plugins"},
    "recipe": {"env", "sim", "train", "cli", "plugins"},
    "settings": {"env", "sim", "recipe", "registry", "train", "cli", "plugins"},
    "registry": {"motion", "env", "train", "cli", "plugins"},
    "commands": {"cli"},
    "train": {"cli", "plugins"},
    "env": {"cli", "train", "plugins"},
    "plugins": {"cli"},
}
"""Room -> rooms it must never import (the arrows that would point up)."""


def _modules(base: Path, prefix: str) -> dict[str, Path]:
    out = {}
    for f in base.rglob("*.py"):
        if "build" in f.relative_to(base).parts:
            continue
        parts = list(f.relative_to(base).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join([prefix, *parts])] = f
    return out


MODULES = {**_modules(CORE, "retarget"), **_modules(PLUGINS, "retarget.plugins")}


def _imports(file: Path) -> list[tuple[int, str]]:
    found = []
    for node in ast.walk(ast.parse(file.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("retarget"):
            found.append((node.lineno, node.module))
            found += [(node.lineno, f"{node.module}.{a.name}") for a in node.names]
        elif isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names if a.name.startswith("retarget")]
    return found


def _graph() -> dict[str, set[str]]:
    edges: dict[str, set[str]] = defaultdict(set)
    for name, file in MODULES.items():
        for _, target in _imports(file):
            if target in MODULES and target != name and not name.startswith(target + "."):
                edges[name].add(target)
    return edges


def _room(module: str) -> str:
    parts = module.split(".")
    return "plugins" if parts[1:2] == ["plugins"] else parts[1] if len(parts) > 1 else ""


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one node (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []
    nodes = set(edges) | {w for ws in edges.values() for w in ws}
    for root in sorted(nodes):
        if root in index:
            continue
        work = [(root, iter(sorted(edges.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    x = stack.pop()
                    on.discard(x)
                    comp.append(x)
                    if x == v:
                        break
                if len(comp) > 1:
                    found.append(sorted(comp))
    return found


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_module_imports_one_that_imports_it_back() -> None:
    assert _cycles(_graph()) == []


def test_no_room_imports_one_that_imports_it_back() -> None:
    rooms: dict[str, set[str]] = defaultdict(set)
    for src, targets in _graph().items():
        for t in targets:
            if _room(src) != _room(t) and _room(t):
                rooms[_room(src)].add(_room(t))
    assert _cycles(rooms) == []


@pytest.mark.parametrize("room", sorted(FORBIDDEN))
def test_lower_floors_know_nothing_of_upper_ones(room: str) -> None:
    arrows = [
        f"{MODULES[name].relative_to(ROOT)}:{line} imports {target}"
        for name in MODULES if _room(name) == room
        for line, target in _imports(MODULES[name])
        if _room(target) in FORBIDDEN[room]
    ]  # fmt: skip
    assert arrows == []
