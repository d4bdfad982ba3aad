"""Each layering sentence of docs/architecture.md, enforced by reading the imports with ``ast``
(imports inside functions and ``TYPE_CHECKING`` blocks included), importing nothing.

The packages import each other in one direction only, never in a circle: mover <- robots <-
sim_hw <- experiments, and programs <- mover, robots. Each package's third-party imports are the
ones its row of the packages table names. ``sim_hw`` takes from ``robots`` only the interface a
world needs to simulate a robot, never a behaviour. The packages above ``mover`` use only the
private modules of it that the page's table names (read from the page). The node's parts never
import the node, and one module of mover turns zenoh's threads into asyncio.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

from tests.experiments._imports import PACKAGES, ROOT, imports, package_imports

#: Which packages each may import.
ALLOWED = {
    "mover": set(),
    "robots": {"mover"},
    "sim_hw": {"mover", "robots"},
    "programs": {"mover", "robots"},
    "experiments": {"mover", "robots", "sim_hw", "programs"},
}

#: The third-party packages each may import (the packages table's last column), and the files
#: where one is allowed that the rest of the package must not use.
THIRD_PARTY = {
    "mover": {"zenoh", "msgpack", "numpy", "cryptography", "pytest", "pytest_asyncio"},
    "robots": {"numpy", "typing_extensions"},
    "sim_hw": {"pymunk", "numpy", "matplotlib", "rerun", "mcap", "mcap_ros2"},
    "programs": {"numpy"},
    "experiments": {"numpy", "matplotlib", "msgpack", "distributed"},
}
ONLY_IN = {
    "pytest": "mover/pytest_plugin.py",  # the pytest11 plugin
    "pytest_asyncio": "mover/pytest_plugin.py",
    "rerun": "sim_hw/view/",  # the optional viewer
    "mcap": "sim_hw/continuous/_mcap.py",  # the optional MCAP recording (the `mcap` extra)
    "mcap_ros2": "sim_hw/continuous/_mcap.py",
    "distributed": "experiments/_saved.py",  # the optional Dask executor
}

#: What of ``robots`` a world may use: the hardware interfaces, the backend protocol, the
#: procedures each hardware offers, and each behaviour family's contract with its world.
ROBOTS_INTERFACE = {
    "robots.hal",
    "robots.grid_hal",
    "robots.backend",
    "robots.procedures",
    "robots.foraging._types",  # what a foraging agent perceives and does
    "robots.stigmergic._hal",  # the eye-bot's and foot-bot's devices
    "robots.stigmergic._leds",  # the foot-bot's LED status: one codec for both sides
}
#: Message types of the stigmergic swarm, defined beside the behaviour that sends them.
ROBOTS_MESSAGES = {
    "robots.stigmergic._eyebot": {"Goal", "Instruction"},
    "robots.stigmergic._footbot": {"Heard"},
}

#: The page whose table names the private modules of mover that the packages above it use.
ARCHITECTURE = ROOT / "docs" / "architecture.md"
INTERNALS_HEADER = "| internal | used by | why |"


def mover_internals(page: str) -> dict[str, set[str]]:
    """The internals table's ``internal | used by`` columns of docs/architecture.md, read: for
    each package above mover, the private modules of mover it may use."""
    lines = page.splitlines()
    assert INTERNALS_HEADER in lines, f"{ARCHITECTURE.name} has no table {INTERNALS_HEADER!r}"
    internals: dict[str, set[str]] = {p: set() for p in PACKAGES if p != "mover"}
    for line in lines[lines.index(INTERNALS_HEADER) + 2 :]:
        if not line.startswith("|"):
            break
        modules, users = (re.findall(r"`([^`]+)`", cell) for cell in line.split("|")[1:3])
        assert modules and users, f"{ARCHITECTURE.name}: a row without names: {line[:60]}"
        for package in users:
            assert package in internals, (
                f"{ARCHITECTURE.name}: {package!r} is no package above mover"
            )
            internals[package].update(modules)
    return internals


#: The parts a node is made of (``mover._node`` gives each its SessionState).
NODE_PARTS = ("_session", "_membership", "_rpc", "_radio", "_bridge", "_wire", "_keys")


def _files(package: str) -> list[Path]:
    return sorted((ROOT / package).rglob("*.py"))


def _where(path: Path) -> str:
    return str(path.relative_to(ROOT))


def _module_path(module: str) -> Path | None:
    """The source file of ``module`` in this repository (a package's ``__init__``), or None."""
    base = ROOT.joinpath(*module.split("."))
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _defined_in(module: str, name: str) -> tuple[str, str]:
    """Where ``name`` imported from ``module`` is defined: ``(module, name)``, following the
    re-exports of packages (``from robots.stigmergic._leds import read as read_leds``)."""
    path = _module_path(module)
    if path is None:
        return module, name
    if _module_path(f"{module}.{name}") is not None:
        return f"{module}.{name}", ""  # a submodule
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for alias in node.names:
                if (alias.asname or alias.name) == name:
                    return _defined_in(node.module, alias.name)
    return module, name


def _is_behaviour(module: str, name: str) -> bool:
    """Whether ``module.name`` is a class with a ``step`` method or a ``*_loop`` function."""
    path = _module_path(module)
    if path is None or not name:
        return False
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.ClassDef) and node.name == name:
            return any(
                isinstance(f, ast.FunctionDef | ast.AsyncFunctionDef) and f.name == "step"
                for f in node.body
            )
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.name == name:
            return name.endswith("_loop")
    return False


def _robots_used_by(package: str) -> dict[tuple[str, str], set[str]]:
    """Each ``(module, name)`` of ``robots`` that ``package`` imports (where it is defined),
    with the places that import it."""
    used: dict[tuple[str, str], set[str]] = {}
    for path in _files(package):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            found: list[tuple[str, str]] = []
            if isinstance(node, ast.Import):
                found = [(a.name, "") for a in node.names if a.name.split(".")[0] == "robots"]
            elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
                top = node.module.split(".")[0]
                found = [_defined_in(node.module, a.name) for a in node.names if top == "robots"]
            else:
                continue
            for key in found:
                used.setdefault(key, set()).add(f"{_where(path)}:{node.lineno}")
    return used


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


def test_each_package_imports_only_the_third_party_packages_its_row_names() -> None:
    for package in PACKAGES:
        for path in _files(package):
            where = _where(path)
            for line, module in imports(path):
                top = module.split(".")[0]
                if top in sys.stdlib_module_names or top in PACKAGES or top == "__future__":
                    continue
                assert top in THIRD_PARTY[package], f"{where}:{line} imports {module}"
                assert where.startswith(ONLY_IN.get(top, "")), f"{where}:{line} imports {top}"


def test_sim_hw_takes_only_the_robots_interface_never_a_behaviour() -> None:
    used = _robots_used_by("sim_hw")
    assert used, "the check sees sim_hw's imports of robots"
    for (module, name), places in sorted(used.items()):
        if module.split(".")[0] != "robots":
            continue  # re-exported from mover: the layers test above judges that
        allowed = module in ROBOTS_INTERFACE or name in ROBOTS_MESSAGES.get(module, set())
        assert allowed, f"{sorted(places)}: {module}.{name} is not robots' interface"
        assert not _is_behaviour(module, name), f"{sorted(places)}: {module}.{name}"


def test_the_packages_above_mover_use_only_the_internals_the_page_names() -> None:
    named = mover_internals(ARCHITECTURE.read_text())
    used: dict[str, set[str]] = {p: set() for p in named}
    for package, internals in named.items():
        for path in _files(package):
            for line, module in imports(path):
                parts = module.split(".")
                if parts[0] == "mover" and any(p.startswith("_") for p in parts[1:]):
                    top = ".".join(parts[:2])
                    assert top in internals, f"{_where(path)}:{line} imports {module}"
                    used[package].add(top)
    assert "mover._tables" in used["sim_hw"], "the check sees the imports of mover's internals"
    for package, internals in named.items():  # and the page names none that is not used
        assert internals <= used[package], (
            f"{package} uses none of {sorted(internals - used[package])}"
        )


def test_the_internals_table_is_read_row_by_row() -> None:
    page = f"""text
{INTERNALS_HEADER}
|---|---|---|
| `mover._a`, `mover._b` | `sim_hw` | why |
| `mover._c` | `robots`, `experiments` | why, with `code` |

after"""
    assert mover_internals(page) == {
        "robots": {"mover._c"},
        "sim_hw": {"mover._a", "mover._b"},
        "programs": set(),
        "experiments": {"mover._c"},
    }


def test_the_behaviour_check_sees_through_re_exports() -> None:
    assert _defined_in("robots.stigmergic", "read_leds") == ("robots.stigmergic._leds", "read")
    assert _defined_in("robots.foraging", "Perception") == ("robots.foraging._types", "Perception")
    assert _is_behaviour(*_defined_in("robots.foraging", "MarkingAgent"))
    assert _is_behaviour(*_defined_in("robots.stigmergic", "footbot_loop"))
    assert not _is_behaviour(*_defined_in("robots.stigmergic", "Goal"))


def test_the_parts_of_a_node_never_import_the_node() -> None:
    for part in NODE_PARTS:
        path = ROOT / "mover" / f"{part}.py"
        found = [line for line, m in imports(path) if m == "mover._node"]
        assert not found, f"{_where(path)}:{found} imports mover._node"


def test_one_module_turns_zenoh_threads_into_asyncio() -> None:
    doors = set()
    for package in PACKAGES:
        for path in _files(package):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Attribute) and node.attr == "call_soon_threadsafe":
                    doors.add(_where(path))
    assert doors == {"mover/_bridge.py"}
