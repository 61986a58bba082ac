"""Data flows one way: a layer never imports a layer above it."""

from __future__ import annotations

import ast

import pytest

from .conftest import REPO

ORDER = ["pattern", "design", "mechanics", "verify", "fabricate", "render", "api", "sweep", "cli"]


def imported_layers(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if node.level >= 2:  # from ..x import y
                yield mod.split(".")[0]
            elif mod.startswith("fabkiri."):
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
