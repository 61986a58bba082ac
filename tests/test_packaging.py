"""The wheel must carry every subpackage and the templates."""

from __future__ import annotations

import tomllib

from fabkiri.templates import template_dir

from .conftest import REPO


def test_every_subpackage_is_listed_in_pyproject():
    listed = set(
        tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    )
    found = {
        ".".join(p.parent.relative_to(REPO).parts) for p in (REPO / "fabkiri").rglob("__init__.py")
    }
    assert found <= listed, f"add to [tool.setuptools] packages: {sorted(found - listed)}"


def test_templates_are_found():
    for kind in ("materials", "printers", "targets", "patterns"):
        assert any(template_dir(kind).glob("*.json")), kind
