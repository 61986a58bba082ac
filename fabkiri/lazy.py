"""A package's names loaded on first use (PEP 562): the start-up of a command that needs one submodule
does not pay for its siblings."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from types import ModuleType

# imported by `import fabkiri`: typing stays out of the start-up (mypy reads the block below)
TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any


def lazy_getattr(package: str, where: dict[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package``: ``where`` maps each name to its relative submodule."""

    def __getattr__(name: str) -> Any:
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name], package), name)
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__


class NamesOverSubmodules(ModuleType):
    """A lazy package with a name that is also one of its submodules' (``mechanics.contract``, the function
    in ``mechanics/contract.py``). Loading a submodule makes the import system set it as the package's
    attribute of that name; the name in ``__over__`` is kept instead, as an eager ``from .contract import
    contract`` left it, whichever loads first."""

    def __setattr__(self, name: str, value: Any) -> None:
        if (
            isinstance(value, ModuleType)
            and name in self.__dict__.get("__over__", ())
            and value.__name__ == f"{self.__name__}.{name}"
        ):
            value = getattr(value, name)
        super().__setattr__(name, value)


def names_over_submodules(package: str, names: tuple[str, ...]) -> None:
    """Let each of ``names`` (loaded lazily) win over the submodule of that name of ``package``."""
    module = sys.modules[package]
    module.__dict__["__over__"] = frozenset(names)
    module.__class__ = NamesOverSubmodules


class CallablePackage(ModuleType):
    """A subpackage whose name is also a top-level door (``fabkiri.design``, ``fabkiri.verify``):
    calling the package calls the door, and its submodules stay where they are."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        module, name = self.__dict__["__door__"]
        return getattr(importlib.import_module(module), name)(*args, **kwargs)


def make_callable(package: ModuleType, module: str, name: str) -> None:
    """Let ``package`` be called as the function ``name`` of ``module`` (imported on the first call)."""
    package.__dict__["__door__"] = (module, name)
    package.__class__ = CallablePackage


class DoorPackage(ModuleType):
    """The top package: a subpackage named in ``__doors__`` becomes callable as it is imported (the
    import system sets it as an attribute here), whoever imports it first."""

    def __setattr__(self, name: str, value: Any) -> None:
        door = self.__dict__.get("__doors__", {}).get(name)
        if door is not None and isinstance(value, ModuleType):
            make_callable(value, *door)
        super().__setattr__(name, value)
