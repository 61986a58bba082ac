"""The design front door of each tessellation kind, chosen by the kind's name.

``fabkiri design --lattice KIND`` and a sweep call :func:`design_by_kind`, which hands the
:class:`~.design.PatternRequest` to the front door registered for ``request.kind``: the quad
kind's :func:`~.design.design_pattern` or the kagome prototype's
:func:`~.kagome.design_kagome_pattern`. Every front door returns an outcome with ``pattern``,
``report``, ``valid``, ``exit_code``, ``write(path, preview=...)`` and ``summary(path)`` (the lines
the CLI prints). A new kind's front door is one module that calls :func:`register_designer`,
plus one line in the built-in table :data:`_DESIGNERS`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..errors import InputError
from ..pattern.tilecount import TakesTiles  # noqa: F401 (the requests' base, for api/design.py)
from ..registry import Registry

if TYPE_CHECKING:
    from .design import PatternRequest

Designer = Callable[
    ..., Any
]  # (PatternRequest, notify=None) -> an outcome (see the module docstring)

# built-in front doors, imported when first asked for (their modules call register_designer())
_DESIGNERS: Registry[Designer] = Registry(
    {"quad": "fabkiri.api.design", "kagome": "fabkiri.api.kagome"}
)


def register_designer(kind: str, front_door: Designer) -> Designer:
    """Make ``front_door`` the design front door of the tessellation kind ``kind``."""
    return _DESIGNERS.add(kind, front_door)


def design_kinds() -> tuple[str, ...]:
    """The tessellation kinds that can be designed (``design --lattice`` choices)."""
    return _DESIGNERS.names()


def designer(kind: str) -> Designer:
    """The design front door of ``kind``, or :class:`InputError` naming the kinds there are."""
    found = _DESIGNERS.find(kind)
    if found is None:
        raise InputError(
            f"no design front door for {kind!r} patterns; choose one of {', '.join(design_kinds())}"
        )
    return found


def design_by_kind(request: PatternRequest, notify: Callable[[str], None] | None = None):
    """Design ``request`` with the front door of its tessellation kind (``request.kind``); a design for a
    material or printer whose outline's arms cannot hold its tiles is warned of first (make's rule)."""
    front_door = designer(request.kind)
    if notify is not None:
        _warn_arms(request, notify)
    return front_door(request, notify=notify)


def _warn_arms(request: PatternRequest, notify: Callable[[str], None]) -> None:
    """make's arm rule (api/maker_arms.py) said before the solve; the user's tiles are designed as
    given. Loaded only for a material or printer (a plain design never loads make's modules)."""
    if request.tiles is None or not (request.printer or request.material):
        return
    from .maker_arms import request_arms

    arms = request_arms(request)
    if arms is not None:
        notify(arms.warning(request.tiles))
