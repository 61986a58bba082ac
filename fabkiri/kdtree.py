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

import importlib.machinery
import importlib.util
import os
import sys

_NAME = "scipy.spatial._ckdtree"
_classes: dict[str, type] = {}


def _load_extension(name: str = _NAME):
    """``name`` (a compiled module of ``scipy.spatial``) loaded from its file, its package's
    ``__init__`` not run."""
    import scipy

    loader = (importlib.machinery.ExtensionFileLoader, importlib.machinery.EXTENSION_SUFFIXES)
    finder = importlib.machinery.FileFinder(os.path.join(scipy.__path__[0], "spatial"), loader)
    spec = finder.find_spec(name)
    if spec is None or spec.loader is None:
        raise ImportError(name)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # before running it, as the import system does
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def _scipy_class(module: str, name: str):
    """``scipy.spatial.<name>``, from the compiled ``module`` alone while ``scipy.spatial`` is unloaded."""
    cls = _classes.get(name)
    if cls is None:
        if module in sys.modules or "scipy.spatial" in sys.modules:
            cls = getattr(importlib.import_module("scipy.spatial"), name)
        else:
            try:
                cls = getattr(_load_extension(module), name)
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
    return _scipy_class("scipy.spatial._qhull", "ConvexHull")


def ConvexHull(points):  # noqa: N802  (stands for the class it builds)
    """``scipy.spatial.ConvexHull(points)``."""
    return hull_class()(points)
