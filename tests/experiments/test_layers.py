"""The packages import each other in one direction only (DESIGN.md), never in a circle:
mover <- robots <- sim_hw <- experiments, and programs <- mover, robots."""

from __future__ import annotations

from tests.experiments._imports import PACKAGES, ROOT, imports, package_imports

#: Which packages each may import.
ALLOWED = {
    "mover": set(),
    "robots": {"mover"},
    "sim_hw": {"mover", "robots"},
    "programs": {"mover", "robots"},
    "experiments": {"mover", "robots", "sim_hw", "programs"},
}


def test_each_package_imports_only_the_layers_below_it() -> None:
    for package in PACKAGES:
        found = package_imports(package)
        extra = {k: sorted(v) for k, v in found.items() if k not in ALLOWED[package]}
        assert not extra, f"{package} imports {extra}"


def test_no_package_imports_in_a_circle() -> None:
    graph = {p: set(package_imports(p)) for p in PACKAGES}
    done: set[str] = set()

    def visit(p: str, path: tuple[str, ...]) -> None:
        assert p not in path, " -> ".join((*path, p))
        if p in done:
            return
        for q in sorted(graph[p]):
            visit(q, (*path, p))
        done.add(p)

    for p in PACKAGES:
        visit(p, ())


def test_relative_imports_are_resolved() -> None:
    maze_cli = ROOT / "experiments" / "maze" / "_cli.py"
    modules = {m for _, m in imports(maze_cli)}
    assert {"experiments._common", "experiments.maze._trial", "sim_hw.grid"} <= modules
