"""Matching recovered tiles to the design's tiles, and rebuilding closed states from cut shapes.

Any order; one rigid motion per sheet for in-place layouts, one per tile for separate ones; a
mirrored tile is an error.
"""

from __future__ import annotations

import numpy as np

from ..kdtree import KDTree
from ..pattern import geometry
from ..pattern.model import Pattern

# ------------------------------------------------------------------ matching


def _shift_fit(D: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Best cyclic corner shift of R onto D (per pair) and the max corner residual
    after a proper rigid fit. ``D``, ``R``: (n, k, 2), k the tile arity."""
    from .geom import tile_kabsch

    best = np.full(len(D), np.inf)
    shift = np.zeros(len(D), dtype=np.int64)
    for s in range(R.shape[1]):
        _, res = tile_kabsch(D, np.roll(R, -s, axis=1))
        better = res < best
        best[better], shift[better] = res[better], s
    return best, shift


def _mirror(R: np.ndarray) -> np.ndarray:
    M = R.copy()
    M[..., 0] *= -1
    return M[:, ::-1]


def _descriptor(C: np.ndarray, L: float) -> np.ndarray:
    """Rigid-motion and corner-shift invariant shape key of quads.

    Sorted edge lengths and angles, plus a chirality term Σ l_k (θ_{k+1} - θ_k)
    (each edge times the turn from its start to its end corner), which changes
    sign under a reflection, so mirror-image tiles get different keys.
    """
    lengths = geometry.edge_lengths(C)
    angles = geometry.corner_angles(C)
    chiral = (lengths * (np.roll(angles, -1, axis=1) - angles)).sum(axis=1, keepdims=True)
    return np.concatenate([np.sort(lengths, axis=1), np.sort(angles, axis=1) * L, chiral], axis=1)


def _shape_classes(D: np.ndarray, L: float) -> np.ndarray:
    """Class label of every design quad: tiles whose shape keys agree to 1e-6 of
    the tile size share one (a tile pair split across a rounding boundary just
    forms two neighbouring classes, both among a cut tile's candidates)."""
    key = np.round(_descriptor(D, L) / (1e-6 * L)).astype(np.int64)
    return np.unique(key, axis=0, return_inverse=True)[1].ravel()


def match_by_shape(
    D: np.ndarray, R: np.ndarray, L: float, k: int = 8
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Assign recovered quads ``R`` to design quads ``D`` one-to-one by shape.

    Returns ``assign`` (len R, design index or -1), residual and corner shift.
    Congruent design tiles form one class (a lattice of identical tiles is one
    class, matched in linear time); each recovered quad is fitted to the k
    nearest classes and classes are filled greedily by residual. The residual
    and corner shift are then recomputed against the member actually assigned.
    """
    n = len(R)
    assign = np.full(n, -1)
    resid = np.full(n, np.inf)
    shift = np.zeros(n, dtype=np.int64)
    if n == 0 or len(D) == 0:
        return assign, resid, shift
    label = _shape_classes(D, L)
    reps = np.unique(label, return_index=True)[1]  # first member of every class
    members = {c: list(np.flatnonzero(label == c)[::-1]) for c in range(len(reps))}
    kk = min(k, len(reps))
    _, cand = KDTree(_descriptor(D[reps], L)).query(_descriptor(R, L), k=kk)
    cand = cand.reshape(n, kk)
    ri = np.repeat(np.arange(n), kk)
    ci = cand.ravel()
    res, _ = _shift_fit(D[reps[ci]], R[ri])
    for m in np.argsort(res, kind="stable"):
        r, c = ri[m], ci[m]
        if assign[r] < 0 and members[c]:
            assign[r] = members[c].pop()
    # whatever is left (its nearest classes were full) pairs up by brute force
    used = np.zeros(len(D), dtype=bool)
    used[assign[assign >= 0]] = True
    left_r = np.flatnonzero(assign < 0)
    left_d = np.flatnonzero(~used)
    if len(left_r) and len(left_d):
        rr = np.repeat(left_r, len(left_d))
        dd = np.tile(left_d, len(left_r))
        res, _ = _shift_fit(D[dd], R[rr])
        for m in np.argsort(res, kind="stable"):
            r, d = rr[m], dd[m]
            if assign[r] < 0 and not used[d]:
                assign[r] = d
                used[d] = True
    got = np.flatnonzero(assign >= 0)
    if len(got):
        resid[got], shift[got] = _shift_fit(D[assign[got]], R[got])
    return assign, resid, shift


def match_in_place(
    Y: np.ndarray, R: np.ndarray, n_hyp: int = 6, alternatives: list | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
    """Match recovered quads ``R`` to design closed-state tiles ``Y`` under ONE rigid motion.

    Hypotheses pair the recovered tile nearest the layout's centre with design
    tiles nearest the design's centre (and each corner shift); the best by
    mean capped centre distance wins, then the motion is refit on all matched corners.
    Returns assign, per-tile residual, shift, rotation angle, translation. ``alternatives``: a list
    that receives every other hypothesis as good as the best within 1 µm (a symmetric sheet matches
    several ways), each refitted as (assign, residual, shift).
    """
    n = len(R)
    assign = np.full(n, -1)
    if n == 0 or len(Y) == 0:
        return assign, np.full(n, np.inf), np.zeros(n, dtype=np.int64), 0.0, np.zeros(2)
    cr, cy = R.mean(axis=1), Y.mean(axis=1)
    cap = geometry.mean_edge_length(Y)
    r0 = int(np.argmin(np.linalg.norm(cr - cr.mean(0), axis=1)))
    cands = np.argsort(np.linalg.norm(cy - cy.mean(0), axis=1))[:n_hyp]
    tree = KDTree(cr)
    k_ar = R.shape[1]  # the tile arity
    R4 = np.stack([np.roll(R, -k, axis=1) for k in range(k_ar)])  # every corner shift, once
    best: tuple[float, float, np.ndarray] | None = None  # (score, theta, t) of the best hypothesis
    hyps = []
    for d in cands:
        for s in range(k_ar):
            theta, t = geometry.kabsch(Y[d], np.roll(R[r0], -s, axis=0))
            moved = geometry.rotate(Y, theta) + t  # design tiles in the sheet frame
            # score: mean corner residual of the nearest tiles, capped at a tile
            # size (a hypothesis one tile off, or a near-symmetric one, loses)
            _, idx = tree.query(moved.mean(axis=1))
            err = np.linalg.norm(R4[:, idx] - moved[None], axis=-1).max(axis=2).min(axis=0)
            score = float(np.minimum(err, cap).mean())
            hyps.append((score, theta, t))
            if best is None or score < best[0]:
                best = (score, theta, t)
    assert best is not None  # n > 0 tiles and at least one candidate: a hypothesis was scored
    _, theta, t = best
    assign, resid, shift, theta, t = _refit(Y, R, theta, t, tree)
    if alternatives is not None:
        for score, th, tt in hyps:
            if score <= best[0] + 1e-3 and (
                abs(geometry.wrap_angle(th - theta)) > 1e-6 or np.linalg.norm(tt - t) > 1e-3
            ):
                alternatives.append(_refit(Y, R, th, tt, tree)[:3])
    return assign, resid, shift, float(theta), t


def _refit(Y, R, theta, t, tree):
    """Assignment under one motion, then the motion refitted on every matched corner and applied."""
    assign, resid, shift = _assign_positions(Y, R, theta, t, tree)
    ok = assign >= 0
    if ok.sum() >= 1:
        src = Y[assign[ok]]
        i = np.flatnonzero(ok)
        k = R.shape[1]  # the tile arity
        dst = R[i[:, None], (np.arange(k)[None, :] + shift[i][:, None]) % k]
        theta, t = geometry.kabsch(src, dst)
        assign, resid, shift = _assign_positions(Y, R, theta, t, tree)
    return assign, resid, shift, float(theta), t


def _assign_positions(Y, R, theta, t, tree):
    n = len(R)
    moved = geometry.rotate(Y, theta) + t
    dist, idx = tree.query(moved.mean(axis=1))  # design tile -> nearest recovered tile
    assign = np.full(n, -1)
    resid = np.full(n, np.inf)
    shift = np.zeros(n, dtype=np.int64)
    # one design tile per recovered tile: the nearest claims it
    order = np.lexsort((dist, idx))
    first = np.ones(len(order), dtype=bool)
    first[1:] = idx[order[1:]] != idx[order[:-1]]
    d = order[first]
    r = idx[d]
    diff = np.stack(
        [
            np.linalg.norm(np.roll(R[r], -s, axis=1) - moved[d], axis=-1).max(axis=1)
            for s in range(R.shape[1])
        ],
        axis=1,
    )
    s = diff.argmin(axis=1)
    assign[r], resid[r], shift[r] = d, diff[np.arange(len(r)), s], s
    return assign, resid, shift


# ------------------------------------------------------------------ rebuilding closed states


def place_from_shapes(pattern: Pattern, C: np.ndarray, state: int) -> tuple[np.ndarray, np.ndarray]:
    """Assemble a closed state from per-tile shapes ``C`` (T, 4, 2), any frames.

    Breadth-first from tile 0: each child turns so the edge bounding its folded
    gap lies along the parent's, and its hinge copy sits on the parent's.
    Returns the placed corners and every hinge's split (mm) — non-zero only on
    non-tree hinges, where the loops fail to close.
    """
    top = pattern.topology
    fold = top.fold(state)
    Y = C.copy()
    tree = top.spanning_tree(0)
    a_is_par = tree.parent_is_a
    cA, cB = top.hinge_corner[tree.hinges].T
    eA, eB = fold.fold_corner_ends[tree.hinges].T
    cp, ep = np.where(a_is_par, cA, cB), np.where(a_is_par, eA, eB)
    cc, ec = np.where(a_is_par, cB, cA), np.where(a_is_par, eB, eA)
    for sel in tree.levels():
        p, c = tree.parents[sel], tree.children[sel]
        hp = Y[p, cp[sel]]
        dp = Y[p, ep[sel]] - hp
        loc = C[c] - C[c, cc[sel]][:, None, :]
        dc = loc[np.arange(len(c)), ec[sel]]
        phi = np.arctan2(dp[:, 1], dp[:, 0]) - np.arctan2(dc[:, 1], dc[:, 0])
        Y[c] = geometry.rotate(loc, phi[:, None]) + hp[:, None, :]
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    split = np.linalg.norm(Y[A, cA] - Y[B, cB], axis=1)
    return Y, split


def assembled(pattern: Pattern, C: np.ndarray, state: int) -> tuple[np.ndarray, np.ndarray]:
    """The cut shapes ``C`` assembled into ``state``: the tree placement refined to the least-squares
    fit of every hinge at once (see :mod:`.assemble`), and every hinge's split (mm)."""
    from .assemble import fit_assembly

    Y0, _ = place_from_shapes(pattern, C, state)
    Y = fit_assembly(pattern, C, state, Y0)
    A, B = pattern.topology.hinge_tiles.T
    cA, cB = pattern.topology.hinge_corner.T
    return Y, np.linalg.norm(Y[A, cA] - Y[B, cB], axis=1)
