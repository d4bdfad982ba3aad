"""What a package's files import, read with ``ast`` (imports inside functions and
``TYPE_CHECKING`` blocks included), without importing anything."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("mover", "robots", "sim_hw", "programs", "experiments")


def imports(path: Path, root: Path = ROOT) -> Iterator[tuple[int, str]]:
    """``(line, absolute module)`` of every import in the file at ``path`` under ``root``
    (relative imports resolved against the file's package)."""
    package = path.relative_to(root).parts[:-1]  # the file's directory, as a package
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = ".".join([*base, *([node.module] if node.module else [])])
            else:
                module = node.module or ""
            yield node.lineno, module


def package_imports(package: str, root: Path = ROOT) -> dict[str, set[str]]:
    """For each other top-level package of the repository that ``package`` (a directory of
    ``root``) imports, the ``file:line`` places that do."""
    found: dict[str, set[str]] = {}
    for path in sorted((root / package).rglob("*.py")):
        for line, module in imports(path, root):
            top = module.split(".")[0]
            if top in PACKAGES and top != package:
                found.setdefault(top, set()).add(f"{path.relative_to(root)}:{line}")
    return found
