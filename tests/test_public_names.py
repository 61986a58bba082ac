"""Every name a package lists in ``__all__`` resolves: its lazy map (PEP 562) points at a real module."""

from __future__ import annotations

import importlib
import pkgutil

import fabkiri
import pytest

PACKAGES = sorted(
    m.name for m in pkgutil.walk_packages(fabkiri.__path__, "fabkiri.") if m.ispkg
) + ["fabkiri"]


@pytest.mark.parametrize("package", PACKAGES)
def test_every_listed_name_resolves(package):
    module = importlib.import_module(package)
    missing = []
    for name in getattr(module, "__all__", []):
        try:
            getattr(module, name)
        except (AttributeError, ImportError) as e:
            missing.append(f"{name}: {e}")
    assert not missing, f"{package}: {missing}"
