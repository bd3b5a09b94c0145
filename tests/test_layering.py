"""The package's import graph follows the one-way flow of the design: a stage imports only itself and earlier
stages, and the packages form no cycle.

Every module of ``slax_drake`` is parsed (ast) and every import statement counts, including those inside
functions and under ``if TYPE_CHECKING``: a deferred import is still a dependency.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1] / "slax_drake"

# The stages, lowest first (a module of slax_drake/<name>.py or slax_drake/<name>/ belongs to stage <name>).
STAGES = (
    # foundations shared by every stage
    "errors", "lazy_exports", "arguments", "resources", "io", "backends", "caches", "config",
    # the pipeline, in the order data flows
    "scene", "occupancy", "station", "dataset", "perception", "shelf", "policies", "planning", "systems", "evaluation",
    "hardware", "cli",
)

# Known violations, each (importing module, imported module) with the issue that removes it. An entry that no
# longer occurs fails test_known_violations_still_occur, so the list only shrinks.
KNOWN_VIOLATIONS: dict[tuple[str, str], str] = {}


def module_name(path: Path, package_dir: Path = PACKAGE_DIR) -> str:
    parts = path.relative_to(package_dir.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def stage_of(module: str) -> str | None:
    """The stage of a module of slax_drake (None for the package root ``slax_drake`` itself)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def imports_of(path: Path, package_dir: Path = PACKAGE_DIR) -> set[str]:
    """The slax_drake modules a file imports (absolute and relative imports; ``from X import name`` counts as X.name
    when X.name is a module of the package, else as X)."""
    this = module_name(path, package_dir)
    is_package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = this.split(".") if is_package else this.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            found.add(target)
            found.update(f"{target}.{alias.name}" for alias in node.names if _is_module(f"{target}.{alias.name}", package_dir))
    return {m for m in found if m == "slax_drake" or m.startswith("slax_drake.")}


def _is_module(name: str, package_dir: Path) -> bool:
    path = package_dir.parent.joinpath(*name.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


@functools.lru_cache(maxsize=1)
def import_graph() -> dict[str, set[str]]:
    """{module: the slax_drake modules it imports} for every module of the package (read once per session)."""
    return {module_name(p): imports_of(p) for p in sorted(PACKAGE_DIR.rglob("*.py"))}


def violations(graph) -> list[tuple[str, str]]:
    """(importer, imported) pairs where a stage imports a later stage."""
    bad = []
    for module, targets in graph.items():
        for target in sorted(targets):
            source_stage, target_stage = stage_of(module), stage_of(target)
            if source_stage is None or target_stage is None:
                continue
            if STAGES.index(target_stage) > STAGES.index(source_stage):
                bad.append((module, target))
    return bad


def package_cycles(graph) -> list[list[str]]:
    """The cycles of the stage-level graph (edges between different stages), each as a list of stages."""
    edges: dict[str, set[str]] = {}
    for module, targets in graph.items():
        for target in targets:
            a, b = stage_of(module), stage_of(target)
            if a is not None and b is not None and a != b:
                edges.setdefault(a, set()).add(b)
    cycles, state = [], {}

    def visit(node, stack):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == "open":
                cycles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, stack)
        stack.pop()
        state[node] = "done"

    for node in sorted(edges):
        if node not in state:
            visit(node, [])
    return cycles


def test_every_module_belongs_to_a_stage():
    graph = import_graph()
    assert len(graph) > 50  # the walk found the package
    unplaced = sorted(m for m in graph if stage_of(m) is not None and stage_of(m) not in STAGES)
    assert not unplaced, f"modules outside every stage (add their package to STAGES): {unplaced}"


def test_no_stage_imports_a_later_stage():
    bad = [pair for pair in violations(import_graph()) if pair not in KNOWN_VIOLATIONS]
    assert not bad, "a stage imports a later stage (order: " + " < ".join(STAGES) + "):\n" + "\n".join(
        f"  {a} ({stage_of(a)}) imports {b} ({stage_of(b)})" for a, b in bad)


def test_no_package_cycle():
    graph = {m: {t for t in targets if (m, t) not in KNOWN_VIOLATIONS} for m, targets in import_graph().items()}
    assert package_cycles(graph) == []


def test_known_violations_still_occur():
    stale = set(KNOWN_VIOLATIONS) - set(violations(import_graph()))
    assert not stale, f"fixed: remove from KNOWN_VIOLATIONS: {sorted(stale)}"


def test_the_checks_catch_a_violation_and_a_cycle():
    graph = {"slax_drake.planning.world": {"slax_drake.systems.station", "slax_drake.station.plant"},
             "slax_drake.systems.station": {"slax_drake.planning.world"},
             "slax_drake.station.plant": {"slax_drake.scene.model"}}
    assert violations(graph) == [("slax_drake.planning.world", "slax_drake.systems.station")]
    assert package_cycles(graph) == [["planning", "systems", "planning"]]


def test_relative_and_deferred_imports_are_seen(tmp_path):
    package = tmp_path / "slax_drake"
    (package / "planning").mkdir(parents=True)
    (package / "systems").mkdir()
    for p in (package / "__init__.py", package / "planning" / "__init__.py", package / "systems" / "__init__.py",
              package / "systems" / "station.py"):
        p.write_text("")
    source = package / "planning" / "world.py"
    source.write_text("def f():\n    from ..systems import station\n    from . import other\n")
    assert imports_of(source, package) == {"slax_drake.systems", "slax_drake.systems.station", "slax_drake.planning"}
