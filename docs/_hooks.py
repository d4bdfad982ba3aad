"""Hooks of the documentation build (mkdocs.yml): what mkdocstrings does not check itself.

* Every public name has a docstring: each module of ``PUBLIC``, each name of its ``__all__``,
  and each public method or property a class of it defines. mkdocstrings renders a name without
  a docstring as an empty entry; here the build fails instead, naming every one that lacks it.
* The docstrings' Sphinx roles (``:class:`Node```, ``:func:`~mover.launch```), which
  mkdocstrings leaves as text, are shown as the code they name.
* The CLI page (``reference/cli.md``) gets every verb's usage from the ``mover`` command's own
  parser, at the ``<!-- mover verbs -->`` mark: a verb added to the command is on the page
  without anyone writing it there, and one whose entry point does not load fails the build.

Plain stdlib, so that ``tests/docs`` can call :func:`undocumented` without mkdocs.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import os
import re
from collections.abc import Iterable
from importlib.metadata import entry_points
from typing import Any

PUBLIC = (
    "mover",
    "mover.cli",
    "mover.testing",
    "mover.pytest_plugin",
    "robots",
    "robots.hal",
    "robots.grid_hal",
    "robots.backend",
    "robots.procedures",
    "robots.library",
    "robots.testing",
    "sim_hw",
    "sim_hw.continuous",
)
"""The modules of the public API: the reference pages draw these."""

VERBS_MARK = "<!-- mover verbs -->"
ROLE = re.compile(r":(?:py:)?(?:class|func|meth|data|attr|mod|exc|obj):<code>~?")


def _own_members(cls: type) -> Iterable[tuple[str, Any]]:
    for name, value in vars(cls).items():
        if name.startswith("_"):
            continue
        func = value.fget if isinstance(value, property) else getattr(value, "__func__", value)
        if inspect.isfunction(func):
            yield name, func


def undocumented(modules: Iterable[str] = PUBLIC) -> list[str]:
    """The public names of ``modules`` with no docstring of their own, as ``module.name``."""
    missing: list[str] = []
    for modname in modules:
        module = importlib.import_module(modname)
        if not (module.__doc__ or "").strip():
            missing.append(modname)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue  # constants are documented by the attribute docstring beside them
            if not (obj.__doc__ or "").strip():
                missing.append(f"{modname}.{name}")
            if inspect.isclass(obj):
                missing += [
                    f"{modname}.{name}.{member}"
                    for member, func in _own_members(obj)
                    if not (func.__doc__ or "").strip()
                ]
    return missing


def verbs_markdown() -> str:
    """Every verb of the ``mover`` command, its ``--help`` in a text block, sorted by name."""
    from mover.cli._main import build_parser  # the command, when asked for

    names = sorted(ep.name for ep in entry_points(group="mover.commands"))
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps at the terminal's width: a fixed page
    try:
        parser = build_parser()
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        choices: dict[str, argparse.ArgumentParser] = sub.choices
        unloaded = sorted(set(names) - set(choices))
        if unloaded:
            raise RuntimeError(f"mover verbs that did not load: {', '.join(unloaded)}")
        parts = [
            f"### `mover {name}`\n\n```text\n{choices[name].format_help().rstrip()}\n```\n"
            for name in names
        ]
    finally:
        if old is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = old
    return "\n".join(parts)


def on_config(config: Any) -> Any:
    """Fail the build when a public name has no docstring."""
    missing = undocumented()
    if missing:
        from mkdocs.exceptions import PluginError  # only inside mkdocs

        raise PluginError("public names without a docstring: " + ", ".join(missing))
    return config


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    """Write every verb's usage into the CLI page."""
    if VERBS_MARK in markdown:
        return markdown.replace(VERBS_MARK, verbs_markdown())
    return markdown


def on_page_content(html: str, **_: Any) -> str:
    """Show a Sphinx role of a docstring as the code it names."""
    return ROLE.sub("<code>", html)
