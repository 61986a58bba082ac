"""SciPy's sparse LU and graph routines without ``scipy.sparse.linalg`` and ``scipy.linalg``.

fabkiri calls SuperLU (``splu``, ``spsolve``) and three graph routines (``connected_components``,
``breadth_first_order``, ``dijkstra``), all compiled code. Their public packages load far more:
``import scipy.sparse.linalg`` runs the iterative solvers, ARPACK, the matrix functions and all of
``scipy.linalg`` (whose import parses the docstrings of its batched routines); ``scipy.sparse.csgraph``
loads its Laplacian module, which imports ``scipy.sparse.linalg``. Together about a tenth of the
start-up of a small design, a cut or a print.

Here the compiled modules (``scipy.sparse.linalg._dsolve._superlu``, ``scipy.sparse.csgraph._traversal``
and ``._shortest_path``, with the two modules they import, ``._tools`` and ``._validation``) are loaded
alone on first use and registered under their own names, so a later import of the public package reuses
them (as :mod:`fabkiri.kdtree` does for the KD-tree). :func:`splu` and :func:`spsolve` call SuperLU with
the arguments SciPy's wrappers give it, for the inputs fabkiri passes (float64 CSC/CSR, a dense right-hand
side); any other input, an exactly singular system, an installed UMFPACK (which SciPy's ``spsolve``
would use), a public package already loaded or another SciPy layout go through SciPy's own functions.
Same compiled code, same arguments: the results are SciPy's to the bit. One difference remains, as for
the KD-tree: a module loaded here is not bound as an attribute of its package when the package loads
later (``sys.modules`` and ``from``-imports find it; ``scipy.sparse.csgraph._traversal`` spelt as an
attribute does not; SciPy itself never spells its private modules that way).
"""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import os
import sys

_LU = "scipy.sparse.linalg._dsolve._superlu"
_GRAPH = "scipy.sparse.csgraph"
# what each routine's compiled module needs loaded first (in order), then the module itself
_GRAPH_MODULES = {
    "connected_components": ("_tools", "_validation", "_traversal"),
    "breadth_first_order": ("_tools", "_validation", "_traversal"),
    "dijkstra": ("_tools", "_validation", "_shortest_path"),
}


def _load_alone(name: str):
    """SciPy's module ``name`` (compiled or Python) loaded from its file, its packages' ``__init__``
    not run; the one in ``sys.modules`` if there is one."""
    if name in sys.modules:
        return sys.modules[name]
    import scipy

    folder = os.path.join(scipy.__path__[0], *name.split(".")[1:-1])
    loaders = [
        (importlib.machinery.ExtensionFileLoader, importlib.machinery.EXTENSION_SUFFIXES),
        (importlib.machinery.SourceFileLoader, importlib.machinery.SOURCE_SUFFIXES),
    ]
    spec = importlib.machinery.FileFinder(folder, *loaders).find_spec(name)
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


def _graph_function(name: str):
    """``scipy.sparse.csgraph.<name>``, from its compiled module alone while the package is unloaded."""
    if _GRAPH not in sys.modules and name in _GRAPH_MODULES:
        try:
            for part in _GRAPH_MODULES[name]:
                module = _load_alone(f"{_GRAPH}.{part}")
            return getattr(module, name)
        except (ImportError, AttributeError):
            pass
    return getattr(importlib.import_module(_GRAPH), name)


class _Graphs:
    """Stands for ``scipy.sparse.csgraph``: each routine is resolved on first use."""

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        function = _graph_function(name)
        setattr(self, name, function)
        return function


csgraph = _Graphs()


_umfpack: list[bool] = []  # whether scikits (UMFPACK's package) is installed, asked once


def _superlu():
    """The compiled SuperLU module alone, or None where SciPy's wrappers must answer: its package
    already loaded, UMFPACK installed (``spsolve`` would use it) or another SciPy layout."""
    if not _umfpack:
        _umfpack.append(importlib.util.find_spec("scikits") is not None)
    if "scipy.sparse.linalg" in sys.modules or _umfpack[0]:
        return None
    try:
        return _load_alone(_LU)
    except ImportError:
        return None


def _plain(A) -> bool:
    """A square float64 CSC or CSR matrix (SciPy's wrappers then convert nothing)."""
    from scipy import sparse

    return (
        sparse.issparse(A)
        and A.format in ("csc", "csr")
        and A.dtype == "float64"
        and A.ndim == 2
        and A.shape[0] == A.shape[1]
    )


def splu(A, permc_spec=None, diag_pivot_thresh=None, options=None):
    """``scipy.sparse.linalg.splu`` with these arguments."""
    lu = _superlu()
    if lu is None or not _plain(A) or A.format != "csc":
        from scipy.sparse.linalg import splu as scipy_splu

        return scipy_splu(
            A, permc_spec=permc_spec, diag_pivot_thresh=diag_pivot_thresh, options=options
        )
    import numpy as np
    from scipy.sparse import csc_array
    from scipy.sparse._sputils import safely_cast_index_arrays

    A.sum_duplicates()
    indices, indptr = safely_cast_index_arrays(A, np.intc, "SuperLU")
    opts = dict(DiagPivotThresh=diag_pivot_thresh, ColPerm=permc_spec, PanelSize=None, Relax=None)
    opts.update(options or {})
    if opts["ColPerm"] == "NATURAL":
        opts["SymmetricMode"] = True
    return lu.gstrf(
        A.shape[0],
        A.nnz,
        A.data,
        indices,
        indptr,
        csc_construct_func=csc_array,
        ilu=False,
        options=opts,
    )


def spsolve(A, b):
    """``scipy.sparse.linalg.spsolve(A, b)`` for a dense ``b``."""
    import numpy as np

    lu = _superlu()
    if lu is not None and _plain(A):
        from scipy import sparse

        dense = not sparse.issparse(b)
        if dense:
            b = np.asarray(b)
        if dense and b.dtype == np.float64 and b.ndim in (1, 2) and b.shape[0] == A.shape[0]:
            A.sum_duplicates()
            x, info = lu.gssv(
                A.shape[0],
                A.nnz,
                A.data,
                A.indices.astype(np.intc, copy=False),
                A.indptr.astype(np.intc, copy=False),
                b,
                1 if A.format == "csc" else 0,
                options=dict(ColPerm=None),
            )
            if info == 0:
                return x.ravel() if b.ndim == 1 or b.shape[1] == 1 else x
            # exactly singular: SciPy's own call warns and answers NaN
    from scipy.sparse.linalg import spsolve as scipy_spsolve

    return scipy_spsolve(A, b)
