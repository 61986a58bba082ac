"""Square/circle closed-state outlines in the parallelogram-hole rigid family (``offsets.py``).

The same problem as ``outline.py`` (an exact square, a size-free least-squares circle) with one more unknown
per hole, its offset: the additive-kirigami demo's freedom, which the rhombus family lacks (a 5x5 square to
circle ends at 3.7 % circle RMS there whatever the start, with no inequality active).

State 1's outline does not depend on the offsets (the boundary rows of ``A(t)`` involve boundary nodes
only), so a square there is the same linear equality on the seeds as in the rhombus family and is made
exact the same way: ``S = S₀ + N u``. State 2 is ``J W Z(t) S``, nonlinear in the offsets only through the
sparse solve for ``Z(t)``. The unknowns ``(u, t, o, R)`` are found by the outline solver's Levenberg–Marquardt
on circle fit + w·E_reg + ρ|min(0, g − m)|², with two inequality rows per hole keeping |t| < 1
(the hole's merge corners strictly inside its slit; ``T_SOFT``, ``T_HARD``).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .constraints import ClosedGrid
from .offsets import OffsetFamily
from .outline import PSI_DEPLOYED, REG_WEIGHT, _lm, outline_kind, square_affine

# |t| above T_SOFT is penalised like any inequality inside its margin; T_HARD is never crossed (step
# limiting). A hard wall alone at the soft bound left LM halving every step that touched it: 5x5 ended at
# 3.3 % circle RMS with offsets stuck on it
T_SOFT, T_HARD = 0.9, 0.98
# (penalty, stall tolerance, iteration cap). The first stage's cap trades time for fit (square->circle,
# vertices only, quiet machine: 7x7 at 60/120/200 iterations 0.18/0.33/0.51 CPU s for 0.96/0.78/0.59 %)
STAGES = ((1e2, 1e-5, 120), (1e4, 1e-6, 10))
# Above this many tiles the rhombus members take it: an iteration costs 45 ms at 17x17 and the offsets
# gain little there (square->circle 17x17: 0.239 % after 1.4 CPU s against the rhombus family's 0.25 %;
# 13x13: 0.41 % against 0.43 %), while at 9x9 they take 0.95 % to 0.53 % and at 5x5 3.7 % to 0.23 %.
OFFSET_MAX_TILES = 11 * 11
MID_WEIGHT = 1.0  # 5x5: vertex RMS 1.61 %, Hausdorff 1.06 %; at 0.5: 1.28 % but Hausdorff 2.03 % (the outline's
# edges cut inside the circle); without midpoints 0.21 % but Hausdorff 8.7 % (vertices bunched, long chords)


def covers(req) -> bool:
    """A rigid parallelogram-hole design of square/circle closed-state outlines only."""
    # a square only in state 1: there it is linear in the seeds (state 2's outline moves with the offsets)
    return (req.rigid and req.holes == "parallelogram" and not req.symmetry and req.target is None
            and bool(req.contracted) and all(outline_kind(v) for v in req.contracted.values())
            and all(outline_kind(v) != "square" or s == 1 for s, v in req.contracted.items()))


def applies(req) -> bool:
    """``covers(req)`` at a size where the offsets are worth their cost (``OFFSET_MAX_TILES``)."""
    return covers(req) and req.rows * req.cols <= OFFSET_MAX_TILES


def preferred_holes(rows: int, cols: int, rigid: bool, symmetry, target, contracted: dict) -> str:
    """The hole shape when the user gives none: parallelogram where this solver applies, else rhombus."""
    r = SimpleNamespace(rows=rows, cols=cols, rigid=rigid, symmetry=symmetry, target=target, contracted=contracted,
                        holes="parallelogram")  # the request's fields that ``applies`` reads
    return "parallelogram" if applies(r) else "rhombus"


def _reps(st, state: int) -> tuple[np.ndarray, ClosedGrid]:
    """One node at every grid vertex of the closed state, and the grid."""
    g = ClosedGrid.build(st, state, 0)
    rep = np.empty(g.n_vertices, dtype=np.int64)
    rep[g.vertex.ravel()] = st.tiles.ravel()
    return rep, g


def closed_grid(fam: OffsetFamily, st, y: np.ndarray, state: int) -> np.ndarray:
    """Grid vertices of a closed state: the mean of the nodes at each (merge corners of a hole differ by
    its offset; boundary vertices are exact)."""
    g = ClosedGrid.build(st, state, 0)
    pos = y if state == 1 else fam.at(y, np.pi / 2)
    acc = np.zeros((g.n_vertices, 2))
    cnt = np.zeros(g.n_vertices)
    np.add.at(acc, g.vertex.ravel(), pos[st.tiles.ravel()])
    np.add.at(cnt, g.vertex.ravel(), 1.0)
    return acc / cnt[:, None]


def solve_offset_outline(prob, log, iters: dict, t_start=None):
    """``(X, mode, fitted)`` like ``outline.solve_outline`` (X: deployed nodes at ψ = π/4, then each target
    state's grid), or None when a square cannot be exact."""
    req, st = prob.req, prob.st
    fam = OffsetFamily.build(st, prob.std.topology.spanning_tree(0))
    nf, K, n = fam.n_seeds, fam.n_holes, prob.n
    states = sorted(prob.grids)
    kinds = {s: outline_kind(req.contracted[s]) for s in states}
    t0 = np.zeros(K)
    _, Z0, _ = fam.state1(np.zeros((nf, 2)), t0, jac=True)
    # the start: the rhombus member nearest the initial guess (least squares over the deployed nodes)
    c, s_ = np.cos(PSI_DEPLOYED), np.sin(PSI_DEPLOYED)
    WZ = fam.W @ Z0
    Kx = np.block([[c * Z0, -s_ * WZ], [s_ * WZ, c * Z0]])
    sol = np.linalg.lstsq(Kx, np.concatenate([prob.X0[:n, 0], prob.X0[:n, 1]]), rcond=None)[0]
    rep1, g1 = _reps(st, 1)
    # centred on the origin like the square rows (a translation of state 1 is a member's rigid motion; the
    # orthogonal projection onto the square rows is not, and would fold tiles when far off)
    y0 = Z0 @ np.stack([sol[:nf], sol[nf:]], -1)
    lo, hi = y0[rep1[g1.boundary]].min(0), y0[rep1[g1.boundary]].max(0)
    s0 = sol - np.repeat(0.5 * (lo + hi), nf)  # vec S = (Sx, Sy)
    E, e = [], []
    for s in states:
        if kinds[s] == "square":
            if s != 1:
                log("offset outline: a square in state 2 is not linear in the seeds; rhombus holes take it")
                return None
            lo, hi = prob.curves_mm[s].bbox
            half = 0.5 * float((hi - lo).max()) / prob.L0
            gi, gj = np.divmod(np.arange(g1.n_vertices), st.cols + 1)
            zr = np.zeros_like(Z0)
            for on, xy, val in [(gi == 0, 1, -half), (gi == st.rows, 1, half), (gj == 0, 0, -half),
                                (gj == st.cols, 0, half)]:
                Zs = Z0[rep1[on]]
                E.append(np.hstack([Zs, zr[rep1[on]]]) if xy == 0 else np.hstack([zr[rep1[on]], Zs]))
                e.append(np.full(int(on.sum()), val))
    affine = square_affine(E, e, 2 * nf)
    if affine is None:
        log("offset outline: the square rows are inconsistent")
        return None
    base, Nsp = affine
    k = Nsp.shape[1]
    u0 = Nsp.T @ (s0 - base)
    circles = [s for s in states if kinds[s] == "circle"]
    rep2, g2 = _reps(st, 2)
    M, N = st.rows, st.cols
    idx = np.arange((M + 1) * (N + 1)).reshape(M + 1, N + 1)
    ring = np.concatenate([idx[0, :-1], idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0]])
    bnodes = {s: (rep1 if s == 1 else rep2)[ring] for s in circles}
    # the circle's points: the outline's vertices (in ring order) and, weighted by MID_WEIGHT, its edge
    # midpoints, so that the vertices also spread round the circle
    B = len(ring)
    P = np.vstack([np.eye(B), MID_WEIGHT * 0.5 * (np.eye(B) + np.roll(np.eye(B), 1, 1))])
    wts = np.r_[np.ones(B), np.full(B, MID_WEIGHT)]
    relative = not any(kinds[s] == "square" for s in states)
    fams_reg, fams_ineq, margin = prob.of("reg"), prob.of("ineq"), prob.margin
    w = np.sqrt(REG_WEIGHT)

    def seeds(p):
        v = base + Nsp @ p[:k]
        return np.stack([v[:nf], v[nf:]], -1)

    def member(p, jac):
        return fam.state1(seeds(p), p[k:k + K], jac=jac)

    def states_of(y):
        return {1: y, 2: fam.at(y, np.pi / 2)}

    def deployed(y):
        X = np.zeros((prob.nv, 2))
        X[:n] = fam.at(y, PSI_DEPLOYED)
        return X

    def nodes(p):
        """What the step limiting checks: the deployed nodes and the offsets."""
        return deployed(member(p, False)), p[k:k + K]

    def viol(Xt):
        X, t = Xt
        g = min((float(f.residual(X).min(initial=0.0)) for f in fams_ineq), default=0.0)
        return max(0.0, -g, float(np.abs(t).max(initial=0.0)) - T_HARD)

    # circle start from the start member's algebraic circle
    if t_start is not None:
        t0 = np.asarray(t_start, dtype=float)
    y0 = member(np.r_[u0, t0], False)
    p0, R0 = [u0, t0], {}
    for s in circles:
        q = states_of(y0)[s][bnodes[s]]
        A = np.c_[2 * q, np.ones(len(q))]
        so = np.linalg.lstsq(A, (q * q).sum(1), rcond=None)[0]
        R0[s] = float(np.sqrt(so[2] + so[:2] @ so[:2]))
        p0.append(np.array([so[0], so[1], R0[s]]))
    p = np.concatenate(p0)
    npar = len(p)

    def dmember(Z, Dt):
        """``∂y/∂(u, t)`` and ``J W ∂y/∂(u, t)``, each ``(V, 2, k + K)``: closed state 1 and closed state 2;
        the deployed nodes at ψ are ``cos ψ`` and ``sin ψ`` times them."""
        V = Z.shape[0]
        Dy = np.concatenate([Z @ Nsp[:nf], Z @ Nsp[nf:]], 1).reshape(V, 2, k)
        Dy = np.concatenate([Dy, Dt], 2)
        WD = (fam.W @ Dy.reshape(V, -1)).reshape(Dy.shape)
        return Dy, np.stack([-WD[:, 1], WD[:, 0]], 1)

    def evaluate(p, rho, jac=True):
        if jac:
            y, Z, Dt = member(p, True)
        else:
            y = member(p, False)
        X = deployed(y)
        st_pos = states_of(y)
        rs, Js = [], []
        off = k + K
        D1, D2 = dmember(Z, Dt) if jac else (None, None)
        for s in circles:
            q = (P @ st_pos[s][bnodes[s]]) / wts[:, None]
            o, R = p[off:off + 2], p[off + 2]
            d = q - o
            dist = np.sqrt((d * d).sum(1))
            a = wts * (R0[s] / R if relative else 1.0)
            rs.append(a * (dist - R))
            if jac:
                unit = d / dist[:, None]
                Dq = np.einsum("pb,bdk->pdk", P / wts[:, None], (D2 if s == 2 else D1)[bnodes[s]])
                J = np.zeros((len(q), npar))
                J[:, :k + K] = a[:, None] * np.einsum("bd,bdk->bk", unit, Dq)
                J[:, off:off + 2] = -a[:, None] * unit
                J[:, off + 2] = -wts * R0[s] * dist / R ** 2 if relative else -wts
                Js.append(J)
            off += 3
        Dd = (np.cos(PSI_DEPLOYED) * D1 + np.sin(PSI_DEPLOYED) * D2).reshape(2 * len(y), -1) if jac else None
        pad = npar - k - K
        for f in fams_reg:
            if jac:
                r, Jx = f(X)
                Js.append(np.hstack([w * (Jx[:, :2 * n] @ Dd), np.zeros((len(r), pad))]))
            else:
                r = f.residual(X)
            rs.append(w * r)
        sq = np.sqrt(rho)
        for f in fams_ineq:
            v = f.residual(X) - margin[f.name]
            act = v < 0
            rs.append(sq * v[act])
            if jac and act.any():
                _, Jx = f(X)
                Js.append(np.hstack([sq * (Jx[np.flatnonzero(act)][:, :2 * n] @ Dd),
                                     np.zeros((int(act.sum()), pad))]))
        t = p[k:k + K]
        v = np.r_[T_SOFT - t, T_SOFT + t]
        act = v < 0
        rs.append(sq * v[act])
        if jac and act.any():
            Jt = np.zeros((2 * K, npar))
            Jt[np.arange(K), k + np.arange(K)] = -1.0
            Jt[K + np.arange(K), k + np.arange(K)] = 1.0
            Js.append(sq * Jt[act])
        return (X, t), np.concatenate(rs), (np.vstack(Js) if jac else None)

    log(f"offset outline start: violation {viol(nodes(p)):.2e}")
    for rho, stall_tol, cap in STAGES:
        p, it = _lm(evaluate, viol, nodes, p, rho, cap, stall_tol)
        iters[f"offset_outline_rho_{rho:g}"] = it
        log(f"offset outline rho={rho:g}: {it} iterations, violation {viol(nodes(p)):.2e}")
    y = member(p, False)
    X = deployed(y)
    for s_, g in prob.grids.items():
        X[g.offset:g.offset + g.n_vertices] = closed_grid(fam, st, y, s_)
    # the stored circle is the outline's own: the geometric least-squares circle of its vertices (the
    # solver's circle also saw the edge midpoints)
    fitted = {s: _lsq_circle(states_of(y)[s][bnodes[s]]) for s in circles}
    prob.offsets = p[k:k + K].copy()
    log(f"offsets: |t| max {np.abs(prob.offsets).max():.3f}, mean {np.abs(prob.offsets).mean():.3f}")
    return X, "least-squares" if circles else "hard", fitted


def _lsq_circle(q: np.ndarray, iters: int = 50) -> tuple[np.ndarray, float]:
    """Geometric least-squares circle through ``q``: Gauss-Newton on the centre from the algebraic circle
    (for a given centre the best radius is the mean distance)."""
    c = np.linalg.lstsq(np.c_[2 * q, np.ones(len(q))], (q * q).sum(1), rcond=None)[0][:2]
    for _ in range(iters):
        d = q - c
        dist = np.sqrt((d * d).sum(1))
        J = -d / dist[:, None]
        step = np.linalg.lstsq(J - J.mean(0), -(dist - dist.mean()), rcond=None)[0]
        c = c + step
        if np.abs(step).max() <= 1e-14 * dist.mean():
            break
    return c, float(np.sqrt(((q - c) ** 2).sum(1)).mean())
