"""The code's shape: no import cycle, and the image side's stages import only what lies
before them in the data flow (photo -> camera -> floor -> room -> render -> draw ->
pipeline -> app). Every import counts, those inside functions too."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("augment", "layout")
# Stages of the image side, in data-flow order; a module may import its own stage and
# earlier ones. The synthetic photographer renders with the camera and render stages.
ORDER = ("errors", "photo", "camera", "floor", "room", "render", "draw", "synth", "pipeline", "app")


def _modules() -> dict[str, Path]:
    out = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path) -> set[str]:
    """The Stager modules ``name`` imports (a package's submodule when one is named)."""
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [(a.name, None) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(package[:len(package) - node.level + 1] + [node.module or ""]).strip(".") \
                if node.level else node.module
            targets = [(base, a.name) for a in node.names]
        else:
            continue
        for module, member in targets:
            if member is not None and f"{module}.{member}" in MODULES:
                found.add(f"{module}.{member}")
            elif module in MODULES:
                found.add(module)
    return found - {name}


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
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
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle():
    assert _cycles(GRAPH) == []


def _stage(name: str) -> str | None:
    parts = name.split(".")
    return parts[1] if parts[0] == "augment" and len(parts) > 1 else None


@pytest.mark.parametrize("name", sorted(n for n in MODULES if _stage(n) is not None))
def test_a_stage_imports_only_what_lies_before_it(name):
    stage = _stage(name)
    later = {other for other in GRAPH[name]
             if _stage(other) is not None and ORDER.index(_stage(other)) > ORDER.index(stage)}
    assert not later, f"{name} ({stage}) imports later stages: {sorted(later)}"


def test_the_solver_knows_nothing_of_images():
    assert not any(other.startswith("augment") for name in MODULES if name.startswith("layout")
                   for other in GRAPH[name])
