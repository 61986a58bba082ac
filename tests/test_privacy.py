"""Privacy by subpackage: a ``_name`` is used only inside the subpackage that defines it.

The rule, as this test reads it:

- A module's *subpackage* is its folder cut to two levels below ``fabkiri``: every module under
  ``fabkiri/design/quad/`` (``rigid/`` included) is in ``fabkiri.design.quad``, every one under
  ``fabkiri/design/core/`` in ``fabkiri.design.core``; a module directly in a layer's folder
  (``fabkiri/api/maker.py``, ``fabkiri/design/__init__.py``) is in the layer (``fabkiri.api``,
  ``fabkiri.design``), and one directly in ``fabkiri/`` in ``fabkiri``. A package's ``__init__`` lies in
  its own folder. The subpackages are disjoint: ``fabkiri.design`` does not contain ``fabkiri.design.quad``.
- A name is *private* when it starts with one underscore (``_rank``); dunders (``__version__``) are
  public.
- A private name is *owned* by the subpackage of the module it is looked up in, or, when the name is
  itself a module (``fabkiri/_lazy.py``), by that module's subpackage.
- Checked uses: ``from M import _x``; a private part of an imported module's path (``from .._lazy
  import f``, ``import fabkiri._lazy``); and ``m._x`` where ``m`` is a name an import bound to a fabkiri
  module (``from ..fabricate import fabricability as fb`` then ``fb._never``), relative imports
  resolved against the importing file, function-local imports included.
- A module of ``fabkiri`` fails when it uses a private name owned by another subpackage. Private
  attributes of objects (``self._x``, ``target._u``) are their class's business, not this test's.

A name another subpackage needs is shared: it is renamed public, with a docstring, where it is defined;
a name the importer should not need is replaced by the public function that answers its question.
"""

from __future__ import annotations

import ast
import functools
from collections.abc import Iterator
from pathlib import Path

from .conftest import REPO
from .importgraph import absolute, module_file, module_name, ours


def subpackage(module: str) -> str:
    """The subpackage of a fabkiri module, by the rule in this file's docstring."""
    path = module_file(module)
    folder = module.split(".")
    if path is None or path.name != "__init__.py":
        folder = folder[:-1]
    return ".".join(folder[:3])


def private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def path_uses(module: str) -> Iterator[tuple[str, str]]:
    """(private part, owner) for each private part of a module's dotted path."""
    parts = module.split(".")
    for i, part in enumerate(parts):
        if private(part):
            yield part, subpackage(".".join(parts[: i + 1]))


def name_owner(module: str, name: str) -> str:
    """The owner of ``name`` looked up in ``module``: the submodule's subpackage if it is one, else that of
    the module that defines it (a re-export, ``from .dual import _corners``, is followed to its source)."""
    sub = f"{module}.{name}"
    if module_file(sub) is not None:
        return subpackage(sub)
    seen = set()
    while (module, name) not in seen and (path := module_file(module)) is not None:
        seen.add((module, name))
        source = top_level_imports(path).get(name)
        if source is None:
            break
        module, name = source
    return subpackage(module)


@functools.cache
def top_level_imports(path: Path) -> dict[str, tuple[str, str]]:
    """The names a module's top level binds by import-from: local name -> (module, name there)."""
    bound = {}
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.ImportFrom) and ours(module := absolute(path, node)):
            for alias in node.names:
                bound[alias.asname or alias.name] = (module, alias.name)
    return bound


def import_uses(node: ast.Import, modules: dict[str, str]) -> Iterator[tuple[int, str, str]]:
    """The private parts of ``import fabkiri.a._b``; binds the module's local name in ``modules``."""
    for alias in node.names:
        if ours(alias.name):
            for part, owner in path_uses(alias.name):
                yield node.lineno, f"{alias.name} ({part})", owner
            local = alias.asname or alias.name.split(".")[0]
            modules[local] = alias.name if alias.asname else local


def import_from_uses(
    path: Path, node: ast.ImportFrom, modules: dict[str, str]
) -> Iterator[tuple[int, str, str]]:
    """The private module path and names of ``from M import ...``; binds the submodules it imports."""
    module = absolute(path, node)
    if not ours(module):
        return
    for part, owner in path_uses(module):
        yield node.lineno, f"{module} ({part})", owner
    for alias in node.names:
        if private(alias.name):
            yield node.lineno, f"{module}.{alias.name}", name_owner(module, alias.name)
        if module_file(f"{module}.{alias.name}") is not None:
            modules[alias.asname or alias.name] = f"{module}.{alias.name}"


def attribute_uses(tree: ast.AST, modules: dict[str, str]) -> Iterator[tuple[int, str, str]]:
    """``m._x`` (and ``m.sub._x``) where ``m`` is a local name bound to a fabkiri module."""
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Attribute) and private(node.attr)):
            continue
        chain = dotted(node.value)
        if chain is None or chain.split(".")[0] not in modules:
            continue
        head, *rest = chain.split(".")
        module = ".".join([modules[head], *rest])
        if module_file(module) is not None:
            yield node.lineno, f"{module}.{node.attr}", name_owner(module, node.attr)


def private_uses(path: Path, source: str | None = None) -> Iterator[tuple[int, str, str]]:
    """(line, the private name as written, its owner) for every private name ``path`` uses."""
    tree = ast.parse(path.read_text() if source is None else source)
    modules: dict[str, str] = {}  # a local name -> the fabkiri module an import bound to it
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from import_uses(node, modules)
        elif isinstance(node, ast.ImportFrom):
            yield from import_from_uses(path, node, modules)
    yield from attribute_uses(tree, modules)


def dotted(node: ast.expr) -> str | None:
    """``a.b.c`` for a chain of attribute lookups on a plain name, else None."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        head = dotted(node.value)
        return None if head is None else f"{head}.{node.attr}"
    return None


def violations(root: Path) -> list[str]:
    found = {}  # one line per file and name: its first use
    for path in sorted(root.rglob("*.py")):
        home = subpackage(module_name(path)) if path.is_relative_to(REPO / "fabkiri") else None
        for line, name, owner in sorted(private_uses(path)):
            if owner != home:
                found.setdefault(
                    (path, name), f"{path.relative_to(REPO)}:{line} uses {name} (owned by {owner})"
                )
    return list(found.values())


def test_no_private_name_crosses_a_subpackage():
    found = violations(REPO / "fabkiri")
    assert not found, f"{len(found)} private names used outside their subpackage:\n" + "\n".join(
        found
    )


def test_the_rule_reads_the_tree():
    # the cases the docstring names, so a change of layout that breaks the reading shows here
    assert subpackage("fabkiri.design.quad.rigid.reduced") == "fabkiri.design.quad"
    assert subpackage("fabkiri.design.quad") == "fabkiri.design.quad"
    assert subpackage("fabkiri.design") == "fabkiri.design"
    assert subpackage("fabkiri.api.maker") == "fabkiri.api"
    assert subpackage("fabkiri.errors") == "fabkiri"
    assert name_owner("fabkiri.design.quad", "solve") == "fabkiri.design.quad"
    code = "from ..fabricate import fabricability as fb\nx = fb._never\nfrom .design import _rank\n"
    uses = list(private_uses(REPO / "fabkiri" / "api" / "probe.py", code))
    assert [(line, name) for line, name, _ in uses] == [
        (3, "fabkiri.api.design._rank"),
        (2, "fabkiri.fabricate.fabricability._never"),
    ]
    assert [owner for *_, owner in uses] == ["fabkiri.api", "fabkiri.fabricate"]
