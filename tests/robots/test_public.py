"""The library's public face: ``__all__`` documented, no simulator or physics inside, the
programs registered."""

from __future__ import annotations

import inspect
from pathlib import Path

import pytest

import programs
import robots.library as library
import robots.testing as testing
from mover import ExpectedFault
from mover._programs import _expected
from robots.hal import HardwareLost
from tests.helpers.faces import assert_documented, loaded_roots

pytestmark = pytest.mark.processes


def test_every_public_name_exists_and_is_documented() -> None:
    assert_documented(library)
    # (names starting with "@" are pytest's: installing mover installs its pytest plugin, and
    # pytest then rewrites the asserts of the whole distribution, adding globals like these)
    public = {n for n in dir(library) if not n.startswith(("_", "@"))}
    assert public <= set(library.__all__) | {"annotations"}


def test_the_library_needs_neither_pymunk_nor_sim_hw() -> None:
    loaded = loaded_roots("robots.library, robots.testing, programs", ("pymunk", "sim_hw"))
    assert loaded == "[]"


def test_the_programs_are_registered() -> None:
    found = programs.installed()  # the mover.programs entry points, the one list of programs
    assert set(found) == {
        "search_and_rescue",
        "follow_trainer",
        "hello_team",
        "foraging",
        "explore_maze",
        "levy_search",
        "stigmergic_navigation",
        "teleop",
    }
    assert all(inspect.iscoroutinefunction(p) for p in found.values())
    # every module of the package is a program, installed under the module's name
    modules = {p.stem for p in Path(programs.__file__).parent.glob("[!_]*.py")}
    assert {name: fn.__module__ for name, fn in found.items()} == {
        m: f"programs.{m}" for m in modules
    }


def test_the_hal_fakes_are_documented() -> None:
    assert testing.__doc__ and "fake_hardware" in testing.__doc__
    for name in testing.__all__:
        assert inspect.getdoc(getattr(testing, name)), f"robots.testing.{name} has no docstring"


def test_a_lost_hardware_is_an_expected_fault_not_a_bug() -> None:
    assert issubclass(HardwareLost, ExpectedFault)
    assert _expected(HardwareLost("the world stopped")) and not _expected(KeyError("bug"))
    assert not hasattr(HardwareLost, "expected")  # the mark is the class, not an attribute
