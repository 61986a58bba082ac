"""Data flows one way: a layer never imports a layer above it."""

from __future__ import annotations

import ast

import pytest

from .conftest import REPO

ORDER = [
    "pattern",
    "exchange",
    "design",
    "mechanics",
    "verify",
    "fabricate",
    "render",
    "api",
    "sweep",
    "cli",
]


def imported_layers(path):
    tree = ast.parse(path.read_text())
    package = path.relative_to(REPO).parent.parts  # ("fabkiri", layer, ...)
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:  # from ..x import y: resolve against the file's own package
                base = package[: len(package) - node.level + 1]
                mod = ".".join([*base, *filter(None, [node.module])])
            else:
                mod = node.module or ""
            if mod.startswith("fabkiri."):
                yield mod.split(".")[1]
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("fabkiri."):
                    yield alias.name.split(".")[1]


@pytest.mark.parametrize("layer", ORDER)
def test_layer_imports_only_lower_layers(layer):
    above = set(ORDER[ORDER.index(layer) + 1 :])
    for path in sorted((REPO / "fabkiri" / layer).rglob("*.py")):
        bad = above & set(imported_layers(path))
        assert not bad, f"{path.relative_to(REPO)} imports {sorted(bad)}"
