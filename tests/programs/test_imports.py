"""Programs use ``mover`` and the ``robots`` library only: never the simulated hardware nor
the experiment runners (docs/architecture.md, its packages table), not even inside a function."""

from __future__ import annotations

from pathlib import Path

from tests.experiments._imports import imports, package_imports


def test_programs_never_import_sim_hw_or_experiments() -> None:
    found = package_imports("programs")
    assert set(found) <= {"mover", "robots"}, {k: sorted(v) for k, v in found.items()}


def test_the_check_sees_imports_inside_functions_and_relative_ones(tmp_path: Path) -> None:
    (tmp_path / "programs" / "sub").mkdir(parents=True)
    probe = tmp_path / "programs" / "sub" / "probe.py"
    probe.write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    import mover\n"
        "def f():\n    from sim_hw import grid\n    import experiments.maze\n"
        "from ..explore_maze import TOPIC\n"
    )
    assert {m for _, m in imports(probe, tmp_path)} == {
        "typing",
        "mover",
        "sim_hw",
        "experiments.maze",
        "programs.explore_maze",
    }
    assert set(package_imports("programs", tmp_path)) == {"mover", "sim_hw", "experiments"}
