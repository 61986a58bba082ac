"""Named strategies whose built-in members are imported on first use.

Tessellation kinds, cut hinge kinds and print styles are each one module that registers itself;
a :class:`Registry` maps names to those members and imports a built-in member's module only when
it is first asked for (as trimesh loads its file-format handlers), so importing a registry costs
nothing and cannot form an import cycle with the members.
"""

from __future__ import annotations

import importlib
from typing import Generic, TypeVar

T = TypeVar("T")


class Registry(Generic[T]):
    """Members by name; ``builtin`` maps a built-in name to the module that registers it."""

    def __init__(self, builtin: dict[str, str]) -> None:
        self.builtin = dict(builtin)
        self.members: dict[str, T] = {}

    def add(self, name: str, member: T) -> T:
        """Register ``member`` under ``name`` (a member's module calls this when imported)."""
        self.members[name] = member
        return member

    def find(self, name: str) -> T | None:
        """The member named ``name``, importing its built-in module if needed; None if unknown."""
        found = self.members.get(name)
        if found is None and name in self.builtin:
            importlib.import_module(self.builtin[name])
            found = self.members.get(name)
        return found

    def names(self) -> tuple[str, ...]:
        """Every known name: the built-in ones first, then those registered from outside."""
        return tuple(dict.fromkeys((*self.builtin, *self.members)))
