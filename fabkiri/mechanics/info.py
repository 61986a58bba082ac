"""A quick report on a pattern: counts, residuals and whether it closes.

This is what ``fabkiri info`` prints. The full geometric proof (compactness,
overlaps, cut layouts) is :mod:`fabkiri.verify`; this module only measures the
quantities of the inverse-design constraints and the two contractions.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ..pattern import geometry
from ..pattern.kinds.tessellation import tessellation
from ..pattern.lattice_counts import topology_count
from ..pattern.model import Pattern
from ..pattern.opening import Opening, opening
from ..pattern.residuals import hinge_sums, state_residuals
from ..pattern.topology import STATES
from .contract import contract
from .tube import tube_report

DEFAULT_TOL = 1e-9  # of the mean tile edge (exported tier: docs/algorithm.md#tolerance-tiers)
DEFAULT_TOL_RAD = 1e-9


@dataclass
class StateInfo:
    state: int
    closes: bool
    max_closure_mm: float
    max_closure_rel: float  # in tile sizes
    worst_hole: int | None
    edge_pair_max_mm: float
    edge_pair_max_rel: float
    ring_max_rad: float
    wrapped_tiles: list[int]
    supplied_match_rel: float | None = None  # aligned distance to the stored state, tile sizes
    supplied_matches: bool | None = None


@dataclass
class PatternInfo:
    name: str
    tiles: int
    nodes: int
    hinges: int
    free_corners: int
    holes: int
    tile_size_mm: float
    width_mm: float
    height_mm: float
    self_intersecting_tiles: list[int]
    clockwise_tiles: list[int]
    hinge_sum_max_rad: float | None  # None where the kind has no hinge-sum rigid family
    rigid_deployable: bool
    tolerance_rel: float
    tolerance_rad: float
    states: list[StateInfo] = field(default_factory=list)
    conformance: dict = field(
        default_factory=dict
    )  # "deployed" / "state_S" -> design.conformance measure
    tube: dict | None = None  # a periodic pattern's tube per state (mechanics.tube.tube_report)
    opening: dict = field(default_factory=dict)  # how much it opens (pattern.opening), to_dict form
    topology_problem: str | None = None  # the tiles form no lattice (pattern.lattice_counts)

    def seam_problems(self) -> list[str]:
        """A tube's closed states whose seam is not a pure translation (a rigid motion for a tube recorded
        as a cone in every state), within the tolerance."""
        if not self.tube:
            return []
        return [
            f"state {k}: the seam does not close by a "
            f"{'rigid motion' if s['seam_kind'] == 'cone' else 'pure translation'} (off by "
            f"{s['seam_dev_rel']:.3g} tile sizes, rotation {s['seam_rotation_rad']:.3g} rad, "
            f"tolerance {self.tolerance_rel:g})"
            for k, s in self.tube["states"].items()
            if k != "deployed" and not s["seam_dev_rel"] <= self.tolerance_rel
        ]

    @property
    def closes_both(self) -> bool:
        return (
            all(s.closes for s in self.states)
            and not self.seam_problems()
            and not self.topology_problem
        )

    @property
    def supplied_ok(self) -> bool:
        return all(s.supplied_matches is not False for s in self.states)

    def problems(self) -> list[str]:
        """One sentence per failed check (empty when the pattern closes in both states)."""
        out = [self.topology_problem] if self.topology_problem else []
        for s in self.states:
            if not s.closes:
                out.append(
                    f"does not close in state {s.state}: loop closure {s.max_closure_rel:.3g} tile sizes "
                    f"({s.max_closure_mm:.4g} mm) at hole {s.worst_hole}, tolerance {self.tolerance_rel:g}"
                )
            if s.supplied_matches is False:
                out.append(
                    f"stored state {s.state} differs from the computed one by {s.supplied_match_rel:.3g} "
                    f"tile sizes after rigid alignment (tolerance {self.tolerance_rel:g})"
                )
        return out + self.seam_problems()

    def to_dict(self) -> dict:
        d = asdict(self)
        if d["tube"] is None:  # a flat pattern's report stays as it was
            del d["tube"]
        d["closes_both"] = self.closes_both
        d["problems"] = self.problems()
        return d

    def to_text(self) -> str:
        lines = [
            f"pattern      {self.name or '(unnamed)'}",
            f"tiles        {self.tiles}   hinges {self.hinges}   free corners {self.free_corners}   "
            f"holes {self.holes}   nodes {self.nodes}",
            f"size         {self.width_mm:.3f} x {self.height_mm:.3f} mm deployed, mean tile edge "
            f"{self.tile_size_mm:.4g} mm",
        ]
        if self.self_intersecting_tiles:
            lines.append(f"WARNING      self-intersecting tiles: {self.self_intersecting_tiles}")
        if self.clockwise_tiles:
            lines.append(f"WARNING      clockwise (reversed) tiles: {self.clockwise_tiles}")
        if self.hinge_sum_max_rad is None:  # the hinge-sum test is the quad rigid family's
            lines.append("hinge sums   n/a (the quad rigid-deployability test)")
        else:
            lines.append(
                f"hinge sums   max |θA+θB-π| = {self.hinge_sum_max_rad:.3e} rad -> "
                f"{'rigid-deployable' if self.rigid_deployable else 'not rigid-deployable'}"
            )
        lines.append(
            "state  closes  loop closure (tile sizes / mm)   edge pairs (mm)   rings (rad)   stored state"
        )
        for s in self.states:
            stored = (
                "—"
                if s.supplied_match_rel is None
                else (
                    f"{'matches' if s.supplied_matches else 'DIFFERS'} ({s.supplied_match_rel:.2e})"
                )
            )
            lines.append(
                f"{s.state:>5}  {'yes' if s.closes else 'NO':>6}  {s.max_closure_rel:>12.3e} / {s.max_closure_mm:<12.3e}"
                f"   {s.edge_pair_max_mm:>13.3e}   {s.ring_max_rad:>11.3e}   {stored}"
            )
            if s.wrapped_tiles:
                lines.append(
                    f"       ring residuals wrapped by 2π because of tiles {s.wrapped_tiles}"
                )
        for key, c in self.conformance.items():
            lines.append(
                f"shape        {key.replace('_', ' ')} vs {c.get('target', 'target')}: Hausdorff "
                f"{c['hausdorff_mm']:.3g} mm ({100 * c['hausdorff_rel']:.2f} % of {c['size_mm']:.4g} mm), 1-IoU "
                f"{c['one_minus_iou']:.3g}, mean distance {c['mean_outline_to_target_mm']:.3g}/"
                f"{c['mean_target_to_outline_mm']:.3g} mm, spacing min/mean {c['spacing_min_mm']:.3g}/"
                f"{c['spacing_mean_mm']:.3g} mm"
            )
        if self.opening:
            lines.append(
                f"opening      {Opening.from_dict(self.opening).line()[len('opening: ') :]}"
            )
        if self.tube:
            from .tube import tube_lines

            lines += tube_lines(self.tube)
        lines.append(f"tolerance    {self.tolerance_rel:g} x tile size, {self.tolerance_rad:g} rad")
        verdict = "closes in both states" if self.closes_both else "; ".join(self.problems())
        lines.append(f"verdict      {verdict}")
        return "\n".join(lines)


def describe(
    pattern: Pattern, tol: float = DEFAULT_TOL, tol_rad: float = DEFAULT_TOL_RAD
) -> PatternInfo:
    """Measure a pattern: topology counts, residuals, both contractions."""
    top = pattern.topology
    corners = pattern.corners()
    size = pattern.tile_size
    lo, hi = pattern.nodes.min(0), pattern.nodes.max(0)
    hs = hinge_sums(pattern)
    quad_rigid = tessellation(pattern.kind).rigid_family
    info = PatternInfo(
        name=pattern.name,
        tiles=top.n_tiles,
        nodes=len(pattern.nodes),
        hinges=top.n_hinges,
        free_corners=len(top.free_nodes),
        holes=top.n_holes,
        tile_size_mm=size,
        width_mm=float(hi[0] - lo[0]),
        height_mm=float(hi[1] - lo[1]),
        self_intersecting_tiles=geometry.self_intersecting_tiles(corners).tolist(),
        clockwise_tiles=np.flatnonzero(geometry.signed_areas(corners) <= 0).tolist(),
        hinge_sum_max_rad=float(np.abs(hs).max(initial=0.0)) if quad_rigid else None,
        rigid_deployable=quad_rigid and bool(np.abs(hs).max(initial=0.0) <= tol_rad),
        tolerance_rel=tol,
        tolerance_rad=tol_rad,
        topology_problem=topology_count(pattern).problem(),
    )
    closed = {}
    for s in STATES:
        c = contract(pattern, s)
        closed[s] = pattern.contracted.get(s, c.corners)
        r = state_residuals(pattern, s)
        st = StateInfo(
            state=s,
            closes=bool(c.max_closure <= tol * size),
            max_closure_mm=c.max_closure,
            max_closure_rel=c.max_closure / size,
            worst_hole=c.worst_hole,
            edge_pair_max_mm=float(r.edge_pairs.max(initial=0.0)),
            edge_pair_max_rel=float(r.edge_pairs.max(initial=0.0)) / size,
            ring_max_rad=float(np.abs(r.rings).max(initial=0.0)),
            wrapped_tiles=r.wrapped_tiles.tolist(),
        )
        if s in pattern.contracted:
            # stored tiles must each be congruent and placed as computed (up to one rigid motion)
            d = geometry.aligned_distance(c.corners, pattern.contracted[s]) / size
            st.supplied_match_rel = d
            st.supplied_matches = bool(d <= tol * np.sqrt(top.n_tiles))
        info.states.append(st)
    info.conformance = _conformance(pattern)
    info.tube = tube_report(pattern, closed)
    info.opening = opening(pattern, closed).to_dict()
    return info


def _conformance(pattern: Pattern) -> dict:
    """Shape conformance of the outline to every stored target curve (see ``fabkiri.design.core.conformance``);
    targets that cannot be rebuilt are left out (``verify`` reports them)."""
    from ..design.core import conformance as conf
    from ..design.targets.lookup import target_from_dict
    from ..errors import InputError

    d = pattern.design or {}
    out = {}
    try:
        if isinstance(d.get("target"), dict):
            out["deployed"] = conf.deployed(
                pattern.nodes, pattern.topology, target_from_dict(d["target"])
            )
        for s, tgt in sorted((d.get("contracted_targets") or {}).items()):
            if int(s) in STATES:
                c = contract(pattern, int(s))
                out[f"state_{s}"] = conf.closed(
                    pattern.contracted.get(int(s), c.corners), target_from_dict(tgt)
                )
    except (InputError, ValueError, TypeError, KeyError):
        pass
    return out
