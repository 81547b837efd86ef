"""House rules of GUIDE §2: no import cycles between pftrack's modules, layers import downward only."""

from __future__ import annotations

import ast
from pathlib import Path

import pftrack

ROOT = Path(pftrack.__file__).parent


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path, name: str) -> set[str]:
    """Every pftrack module imported anywhere in the file (module level or inside functions)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_pkg = path.name == "__init__.py"
    package = name if is_pkg else name.rsplit(".", 1)[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("pftrack"))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if not mod.startswith("pftrack"):
                continue
            out.add(mod)
            for a in node.names:  # "from . import builtin" names a module
                out.add(f"{mod}.{a.name}")
    return out


def _graph() -> dict[str, set[str]]:
    files = {_module_name(p): p for p in ROOT.rglob("*.py")}
    graph = {}
    for name, path in files.items():
        deps = {d for d in _imports(path, name) if d in files and d != name}
        # a package's __init__ re-exports; importing a submodule does not import its siblings
        graph[name] = deps
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
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
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles_between_modules():
    graph = _graph()
    # a package __init__ that re-exports its own submodules is not a cycle through those submodules
    for name in list(graph):
        graph[name] = {d for d in graph[name] if not (name.startswith(d + ".") and d in graph)}
    assert _cycles(graph) == []


def test_engine_has_no_images():
    """filtering/ is the engine: it imports neither OpenCV nor the image layers above it."""
    for path in (ROOT / "filtering").glob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "import cv2" not in text, path.name
        deps = _imports(path, _module_name(path))
        assert not any(d.startswith(("pftrack.cues", "pftrack.trackers", "pftrack.io", "pftrack.cli")) for d in deps), \
            (path.name, deps)


def test_cli_is_a_package_of_command_modules():
    assert (ROOT / "cli" / "__init__.py").exists() and not (ROOT / "cli.py").exists()
    for path in (ROOT / "cli").glob("*.py"):
        assert len(path.read_text(encoding="utf-8").splitlines()) < 300, path.name
