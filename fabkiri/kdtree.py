"""SciPy's KD-tree without the rest of ``scipy.spatial``.

Nearest-point queries (target projection, shape conformance, closest hinge pairs) need only
``cKDTree``, but ``import scipy.spatial`` also loads ``scipy.special``, ``scipy.spatial.distance`` and
``scipy.spatial.transform``: about a tenth of a CPU second, a sixth of a whole 8x8 design's process.
:func:`KDTree` loads the compiled ``scipy.spatial._ckdtree`` extension alone, on first use, and
registers it under its own name, so a later ``import scipy.spatial`` reuses it (one class either way).
Where that is not possible (``scipy.spatial`` already loaded, or another SciPy layout) it falls back to
the public import. Same class, same code: results are SciPy's to the bit.

:func:`ConvexHull` does the same for ``scipy.spatial._qhull`` (the thinnest width of a cut piece, read
back from the written files, needs only the hull).
"""

from __future__ import annotations

import importlib
import sys

from .sparse_alone import load_alone

_NAME = "scipy.spatial._ckdtree"
_classes: dict[str, type] = {}


def _scipy_class(module: str, name: str):
    """``scipy.spatial.<name>``, from the compiled ``module`` alone while ``scipy.spatial`` is unloaded."""
    cls = _classes.get(name)
    if cls is None:
        if module in sys.modules or "scipy.spatial" in sys.modules:
            cls = getattr(importlib.import_module("scipy.spatial"), name)
        else:
            try:
                cls = getattr(load_alone(module), name)
            except ImportError:
                cls = getattr(importlib.import_module("scipy.spatial"), name)
        _classes[name] = cls
    return cls


def tree_class():
    """The ``cKDTree`` class, loaded on first call."""
    return _scipy_class(_NAME, "cKDTree")


def KDTree(points):  # noqa: N802  (stands for the class it builds)
    """``scipy.spatial.cKDTree(points)``."""
    return tree_class()(points)


def hull_class():
    """The ``ConvexHull`` class, loaded on first call (as :func:`tree_class`)."""
    if "ConvexHull" not in _classes and "scipy.linalg" not in sys.modules:
        # the compiled qhull module imports SciPy's LAPACK wrappers: those alone too, not scipy.linalg
        try:
            load_alone("scipy.linalg.cython_lapack")
        except ImportError:
            pass
    return _scipy_class("scipy.spatial._qhull", "ConvexHull")


def ConvexHull(points):  # noqa: N802  (stands for the class it builds)
    """``scipy.spatial.ConvexHull(points)``."""
    return hull_class()(points)
