"""mover's public faces: ``mover`` and ``mover.cli``. Every name in ``__all__`` exists and is
documented, and every public-looking name they define is listed."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys
from types import ModuleType

import pytest

import mover
import mover.cli

pytestmark = pytest.mark.processes

FACES = [mover, mover.cli]


@pytest.mark.parametrize("face", FACES, ids=lambda m: m.__name__)
def test_every_listed_name_exists_and_is_documented(face: ModuleType) -> None:
    assert len(set(face.__all__)) == len(face.__all__), "a name is listed twice"
    assert face.__all__ == sorted(face.__all__, key=lambda n: (not n.isupper(), n))
    for name in face.__all__:
        assert hasattr(face, name), f"{face.__name__}.{name} is listed but missing"
        obj = getattr(face, name)
        if inspect.isclass(obj) or inspect.isroutine(obj):
            assert inspect.getdoc(obj), f"{face.__name__}.{name} has no docstring"
        else:  # a constant documents itself in the face's docstring
            assert name in (face.__doc__ or ""), f"{face.__name__}.{name} is not in the docstring"


@pytest.mark.parametrize("face", FACES, ids=lambda m: m.__name__)
def test_every_public_name_is_listed(face: ModuleType) -> None:
    public = {
        n for n in dir(face) if not n.startswith("_") and not inspect.ismodule(getattr(face, n))
    }
    # A face may use the public names of mover's main face (mover.cli uses TeamCredentials).
    assert public <= set(face.__all__) | set(mover.__all__) | {"annotations"}


def test_the_listed_names_are_mover_s_own() -> None:
    for name in mover.__all__:
        home = getattr(getattr(mover, name), "__module__", "mover")
        assert home.split(".")[0] == "mover", f"mover.{name} comes from {home}"


def test_mover_imports_none_of_the_packages_above_it() -> None:
    code = "import sys, mover, mover.cli, mover._cli; print(sorted({m.split('.')[0] for m in "
    code += "sys.modules} & {'robots', 'sim_hw', 'programs', 'experiments', 'pymunk'}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


# The deprecated names: (the name, where it is now). Each goes in the next release.
DEPRECATED = {
    "Team": ("mover._config", "TeamCredentials"),
    "TaskTeam": ("mover._collective", "TaskTeam"),
    "Collectives": ("mover._collective", "Collectives"),
    "StepMetrics": ("mover._collective", "StepMetrics"),
    "free_port": ("mover._config", "free_port"),
}


@pytest.mark.parametrize("name", sorted(DEPRECATED))
def test_a_deprecated_name_warns_and_gives_what_it_gave(name: str) -> None:
    module, now = DEPRECATED[name]
    assert name not in mover.__all__ and name not in dir(mover)
    with pytest.warns(DeprecationWarning, match=f"mover.{name} is deprecated"):
        found = getattr(mover, name)
    assert found is getattr(importlib.import_module(module), now)


def test_every_deprecated_name_warns_none_is_served_silently() -> None:
    assert mover._DEPRECATED.keys() == DEPRECATED.keys()
    for name in DEPRECATED:
        with pytest.warns(DeprecationWarning, match=f"mover.{name} is deprecated"):
            getattr(mover, name)


def test_a_node_s_membership_was_its_team() -> None:
    node = mover.Node("ada", mover.TeamCredentials.generate("crew"))  # not started
    assert isinstance(node.membership, mover.Membership)
    with pytest.warns(DeprecationWarning, match="Node.team is deprecated"):
        assert node.team is node.membership
    with pytest.raises(AttributeError, match="no attribute 'Nothing'"):
        _ = mover.Nothing


def test_an_expected_fault_is_not_a_mover_error() -> None:
    # the faults of what mover runs (hardware that went away), reported like mover's own
    assert issubclass(mover.ExpectedFault, Exception)
    assert not issubclass(mover.ExpectedFault, mover.MoverError)
