"""fabkiri: compact reconfigurable kirigami from a target shape to fabrication files.

One door per task, each taking plain values and returning one result type (``ok``, ``summary()``,
``write(folder)`` and a picture in a notebook)::

    import fabkiri

    design = fabkiri.design("circle", tiles="8x8", rigid=True)
    cut = fabkiri.cut(design.pattern, material="acrylic-3", scale="auto")
    cut.write("outputs/circle")

``standard``, ``load``/``save``, ``design``, ``contract``, ``deploy``, ``verify``, ``cut``,
``print_pattern`` (:mod:`fabkiri.api.front`, :mod:`fabkiri.api.front_fabricate`), and from a target
outline to cut or print files in one call::

    result = fabkiri.make("star", size=150, material="acrylic-3", output="outputs/star")

``fabkiri.design`` and ``fabkiri.verify`` are also the subpackages of those layers: calling one calls
the door. The layers below (``fabkiri.pattern``, ``fabkiri.mechanics``, ...) stay importable as before.
"""

__version__ = "0.1.0"

import sys as _sys

from .lazy import DoorPackage as _DoorPackage

# loaded on first use (PEP 562), so `import fabkiri` stays cheap: the doors need numpy and more
_FRONT, _FAB, _RESULTS = "fabkiri.api.front", "fabkiri.api.front_fabricate", "fabkiri.api.results"
_LAZY = {
    "standard": _FRONT,
    "load": _FRONT,
    "save": _FRONT,
    "contract": _FRONT,
    "deploy": _FRONT,
    "cut": _FAB,
    "print_pattern": _FAB,
    "make": _FAB,
    "MakeResult": "fabkiri.api.maker_result",
    "Pattern": "fabkiri.pattern.model",
    "Material": "fabkiri.fabricate.cut.materials",
    **{
        name: _RESULTS
        for name in (
            "DesignResult",
            "ContractResult",
            "VerifyResult",
            "CutResult",
            "PrintResult",
            "DeployResult",
        )
    },
}
# doors that share their name with a subpackage: the subpackage, once imported, is callable as the door
__doors__ = {"design": (_FRONT, "design"), "verify": (_FRONT, "verify")}
_sys.modules[__name__].__class__ = _DoorPackage


def __getattr__(name: str):
    import importlib

    if name in __doors__:  # the subpackage itself, callable as its door
        return importlib.import_module(f"{__name__}.{name}")
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'fabkiri' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY, *__doors__])
