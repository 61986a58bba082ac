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
_tree_class = None


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


def tree_class():
    """The ``cKDTree`` class, loaded on first call."""
    global _tree_class
    if _tree_class is None:
        if _NAME in sys.modules or "scipy.spatial" in sys.modules:
            from scipy.spatial import cKDTree as cls
        else:
            try:
                cls = _load_extension().cKDTree
            except ImportError:
                from scipy.spatial import cKDTree as cls
        _tree_class = cls
    return _tree_class


def KDTree(points):  # noqa: N802  (stands for the class it builds)
    """``scipy.spatial.cKDTree(points)``."""
    return tree_class()(points)


_HULL = "scipy.spatial._qhull"
_hull_class = None


def hull_class():
    """The ``ConvexHull`` class, loaded on first call (as :func:`tree_class`)."""
    global _hull_class
    if _hull_class is None:
        if _HULL in sys.modules or "scipy.spatial" in sys.modules:
            from scipy.spatial import ConvexHull as cls
        else:
            try:
                cls = _load_extension(_HULL).ConvexHull
            except ImportError:
                from scipy.spatial import ConvexHull as cls
        _hull_class = cls
    return _hull_class


def ConvexHull(points):  # noqa: N802  (stands for the class it builds)
    """``scipy.spatial.ConvexHull(points)``."""
    return hull_class()(points)
