"""SciPy's KD-tree without the rest of ``scipy.spatial``.

Nearest-point queries (target projection, shape conformance, closest hinge pairs) need only
``cKDTree``, but ``import scipy.spatial`` also loads ``scipy.special``, ``scipy.spatial.distance`` and
``scipy.spatial.transform``: about a tenth of a CPU second, a sixth of a whole 8x8 design's process.
:func:`KDTree` loads the compiled ``scipy.spatial._ckdtree`` extension alone, on first use, and
registers it under its own name, so a later ``import scipy.spatial`` reuses it (one class either way).
Where that is not possible (``scipy.spatial`` already loaded, or another SciPy layout) it falls back to
the public import. Same class, same code: results are SciPy's to the bit.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import sys

_NAME = "scipy.spatial._ckdtree"
_tree_class = None


def _load_extension():
    """``scipy.spatial._ckdtree`` loaded from its file, its package's ``__init__`` not run."""
    import scipy

    loader = (importlib.machinery.ExtensionFileLoader, importlib.machinery.EXTENSION_SUFFIXES)
    finder = importlib.machinery.FileFinder(os.path.join(scipy.__path__[0], "spatial"), loader)
    spec = finder.find_spec(_NAME)
    if spec is None:
        raise ImportError(_NAME)
    module = importlib.util.module_from_spec(spec)
    sys.modules[_NAME] = module  # before running it, as the import system does
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[_NAME]
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
