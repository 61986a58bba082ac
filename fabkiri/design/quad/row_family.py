"""An inequality family built from a row function of :class:`~..core.dual.Dual` values.

The fabrication rows (``fabrication.py``) and the printed strips' pad rows (``print_rows.py``) both build
their families here: values without gradients on every row, gradients only on the rows a solver asks.
"""

from __future__ import annotations

from typing import TypeVar, cast

import numpy as np

from ..core.dual import values_only
from .constraints import Family

_Args = TypeVar("_Args", bound=tuple)


def pick(args: _Args, sel: np.ndarray | None) -> _Args:
    """Per-row index arrays, of rows ``sel`` only if given."""
    return args if sel is None else cast(_Args, tuple(a[sel] for a in args))


def ineq_family(name: str, quads: np.ndarray, rows_of, nv: int, meta: dict) -> Family:
    """An inequality family from ``rows_of(x, sel) -> Dual`` (rows ``sel`` only, or all for None) over the quads
    named by ``meta['quad_of_row']``. Its values are computed without gradients (``res``) and its gradients
    only on the rows asked (``active``): the solvers need them only where a row is inside its margin."""
    owner = meta["quad_of_row"]
    k = quads.shape[1]

    def fn(x):
        r = rows_of(x, None)
        return r.v, (quads[owner], r.g.reshape(len(owner), k, 2))

    def active(x, act):
        grads = np.zeros((len(owner), k, 2))
        sel = np.flatnonzero(act)
        if len(sel):
            grads[sel] = rows_of(x, sel).g.reshape(len(sel), k, 2)
        return quads[owner], grads

    return Family(
        name,
        "ineq",
        fn,
        1,
        meta=meta,
        nv=nv,
        res=_recent(lambda x: np.asarray(rows_of(values_only(x), None).v)),
        active=active,
    )


RECENT = 4  # the residual-only calls a family remembers (a solver re-checks a point it checked a few calls ago)


def _recent(res):
    """``res`` remembering its last ``RECENT`` points: the solvers ask the inequalities' values at the same
    nodes again (about a quarter of a fabrication-aware design's residual-only calls), and these rows are the
    costly ones. The same values, as copies."""
    memo: list[tuple[tuple, np.ndarray]] = []

    def cached(x):
        x = np.asarray(x)
        key = (x.shape, x.dtype.str, x.tobytes())  # bits, not ==: -0.0 is not 0.0 here
        for i, (k, v) in enumerate(memo):
            if k == key:
                memo.insert(0, memo.pop(i))
                return v.copy()
        v = res(x)
        memo.insert(0, (key, v.copy()))
        del memo[RECENT:]
        return v

    return cached
