"""The package's layers (docs/design.md, "Data flow"): a module imports only from its own
room (sub-package) or from rooms below it, and no two modules import each other, directly
or round a longer loop. Read from the source (every import statement, those inside
functions included), so a new arrow against the layers or a new cycle fails here."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "gait_planner"

# low to high: a room may import the rooms of lower rank (and its own)
RANK = {
    "atomic": 0, "buffered": 0, "lazy": 0,  # file writing, buffers, lazily loaded names
    "memory": 0,  # the process's and the machine's memory
    "gait_planner": 1,  # the package's own __init__: the environment, the API's names
    "model": 1, "request": 1,  # scenes, URDFs, grounds; a request's fields
    "result": 2,  # the plain result every adapter converts
    "dynamics": 3,  # the variational integrator
    "ocp": 4,  # the transcription and the planner
    "io": 5, "problem": 5,  # formats and messages; a request resolved once
    "verify": 6,  # the independent verifier
    "parameter_path": 6,  # a request continued from a kept plan along its parameters
    "strategies": 7,  # how a request is planned: start, continuation, restarts, refinement
    "transitions": 7.5,  # a transition from a given state onto a planned gait
    "walk": 8,  # MuJoCo
    "viz": 9,  # pictures: rerun, figures
    "pipeline": 10,  # plan, join, record: what the adapters call
    "gaitlib": 11, "api": 11,  # gait libraries on Ray; the Python API
    "ros": 12,  # the node
    "cli": 13,  # the commands (`gait-planner node` and the service clients run the node's code)
}


def _modules() -> dict[str, Path]:
    return {".".join(f.relative_to(PACKAGE.parent).with_suffix("").parts)
            .removesuffix(".__init__"): f for f in PACKAGE.rglob("*.py")}


def _imports(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
    return {name for name in out if name.split(".")[0] == "gait_planner"}


def _room(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


MODULES = _modules()
GRAPH = {m: {n for n in _imports(f) if n in MODULES and n != m and n != "gait_planner"}
         for m, f in MODULES.items()}


def test_every_room_has_a_rank():
    assert {_room(m) for m in MODULES} <= set(RANK)


def _against(graph: dict[str, set[str]]) -> list[str]:
    """Every import of a room of higher (or equal, other) rank."""
    return sorted(f"{m} imports {n}" for m, deps in graph.items() for n in deps
                  if RANK[_room(n)] > RANK[_room(m)]
                  or (RANK[_room(n)] == RANK[_room(m)] and _room(n) != _room(m)))


def test_no_module_imports_a_higher_room():
    against = _against(GRAPH)
    assert not against, "\n".join(against)


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while not component or component[-1] != v:
                component.append(stack.pop())
                on.discard(component[-1])
            if len(component) > 1:
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_no_import_cycle():
    assert not _cycles(GRAPH)


def test_the_check_finds_what_it_looks_for():
    """A cycle and an arrow against the layers, made up, are found."""
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == [["a", "b", "c"]]
    assert _against({"gait_planner.model.scene": {"gait_planner.ocp.solve"},
                     "gait_planner.io.urdf": {"gait_planner.problem"},
                     "gait_planner.ocp.solve": {"gait_planner.model.scene"}}) == [
        "gait_planner.io.urdf imports gait_planner.problem",
        "gait_planner.model.scene imports gait_planner.ocp.solve"]
