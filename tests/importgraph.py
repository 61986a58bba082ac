"""The package's own imports read from its source (no module is imported): the privacy and the
import-cycle tests build on these."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

from .conftest import REPO


def module_name(path: Path) -> str:
    """``fabkiri/design/quad/solve.py`` -> ``fabkiri.design.quad.solve`` (a package: its folder's name)."""
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def module_file(module: str) -> Path | None:
    """The file of a dotted module name in this repository, or None (not a module of ours)."""
    base = REPO.joinpath(*module.split("."))
    for path in (base / "__init__.py", base.with_suffix(".py")):
        if path.is_file():
            return path
    return None


def ours(module: str) -> bool:
    return module == "fabkiri" or module.startswith("fabkiri.")


def absolute(path: Path, node: ast.ImportFrom) -> str:
    """The module an import-from names, relative levels resolved against ``path``."""
    if not node.level:
        return node.module or ""
    package = module_name(path).split(".")
    if path.name != "__init__.py":
        package.pop()
    base = package[: len(package) - node.level + 1]
    return ".".join([*base, *filter(None, [node.module])])


def type_checking(node: ast.AST) -> bool:
    """An ``if TYPE_CHECKING:`` block: read by the type checker, never run."""
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def runtime_imports(tree: ast.AST) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement that runs: at module level or inside a function, not under TYPE_CHECKING."""
    for child in ast.iter_child_nodes(tree):
        if isinstance(child, (ast.Import, ast.ImportFrom)):
            yield child
        elif not type_checking(child):
            yield from runtime_imports(child)
