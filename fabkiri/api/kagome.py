"""``design_kagome``: the front door of kagome inverse design (``fabkiri design --lattice kagome``).

Policy: build the standard R x C kagome at the target's size, design it onto the target
(:mod:`fabkiri.design.kagome_fit`), contract both closed states, verify the pattern (both states,
overlaps, target shape) and judge the shape. The best iterate is always returned; ``valid`` and
``exit_code`` say whether it met the equality tolerance and every check.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..design import conformance as conf
from ..design.kagome_fit import design
from ..design.targets import load_target
from ..errors import InputError
from ..fileio import atomic_write
from ..mechanics.contract import with_contracted_states
from ..pattern.io import dumps
from ..pattern.kagome import standard_kagome
from ..pattern.model import Pattern
from ..verify import verify_pattern
from .designers import register_designer

if TYPE_CHECKING:
    from .design import PatternRequest

# options of the quad design that have no kagome counterpart yet
UNSUPPORTED = (
    "rigid",
    "holes",
    "contracted_target",
    "material",
    "printer",
    "min_feature",
    "min_hole",
)


@dataclass(frozen=True)
class KagomeOutcome:
    """A kagome design, its report and its verdict."""

    pattern: Pattern
    report: dict
    valid: bool
    tiles: tuple[int, int] = (0, 0)  # rows, cols

    @property
    def exit_code(self) -> int:
        return 0 if self.valid else 1

    def write(self, path, preview: bool = True) -> None:
        """Write the pattern (atomically); a kagome design has no preview yet."""
        atomic_write(path, dumps(self.pattern))

    def summary(self, path) -> list[str]:
        """The line ``fabkiri design --lattice kagome`` prints about the design written to ``path``."""
        r, (rows, cols) = self.report, self.tiles
        return [
            f"wrote {path}: kagome {rows}x{cols} {r['status']}, max equality residual "
            f"{r['max_equality_residual']:.2e}, Hausdorff {100 * r['conformance']['hausdorff_rel']:.2f} % of "
            f"the size (shape {r['shape']['status']}), verify: "
            f"{'pass' if not r['verify_failed'] else 'FAIL ' + ', '.join(r['verify_failed'])}"
        ]


def design_kagome(
    rows: int,
    cols: int,
    target: str,
    size: float | None = None,
    *,
    tol: float = 1e-10,
    shape_tol: str = conf.DEFAULT_SHAPE_TOL,
    name: str | None = None,
    symmetry: bool | str = True,
) -> KagomeOutcome:
    """Design a reconfigurable R x C kagome whose deployed outline follows ``target`` (mm).

    ``symmetry`` imposes every mirror the lattice and the target share (vertical for C odd, horizontal
    for R even; docs/kagome.md); False leaves the design free (about twice the fitting freedom); ``"x"``
    or ``"y"`` imposes that mirror alone (the lattice and the target must have it)."""
    tgt = load_target(target, size)
    shape = conf.parse_shape_tol(shape_tol)
    unit = standard_kagome(rows, cols, tile_size=1.0)
    tile = tgt.size / float(np.ptp(unit.nodes, axis=0).max())  # the standard spans the target
    std = standard_kagome(rows, cols, tile_size=tile)
    d = design(std, tgt, symmetry=symmetry)
    pattern, rejected = _first_closing(d)
    convex = (
        pattern is None
    )  # every candidate overlaps: again with convex holes, which rule crossings out
    if convex:
        d = design(std, tgt, symmetry=symmetry, convex=True)
        pattern, rejected = _first_closing(d)
    if pattern is None:  # still none: the solver's best, whose failures verify names
        pattern = with_contracted_states(d.pattern)
    measured = conf.deployed(pattern.nodes, pattern.topology, tgt)
    verdict = conf.judge(measured, shape, (rows, cols))
    rel = d.max_equality  # normalised units: already relative to the tile size
    report: dict[str, Any] = {
        "status": "converged" if d.converged and rel <= tol else "unconverged",
        "max_equality_residual": rel,
        "tol": tol,
        "iterations": d.iterations,
        "symmetry": list(d.symmetry),
        "min_gap_deg": d.min_gap_deg,
        "min_tile_quality": d.min_quality,
        "hausdorff_trace": list(d.hausdorff_trace),
        "candidates_rejected": rejected,
        "convex_holes": convex,
        "max_tip_distance_mm": d.max_tip_distance_mm,
        "tile_size_mm": tile,
        "conformance": measured,
        "shape": verdict,
    }
    pattern = replace(
        pattern,
        name=name or pattern.name,
        design={**(pattern.design or {}), "report": report, "shape_tol": shape_tol},
    )
    rep = verify_pattern(pattern, shape_tol=shape_tol)
    report["verify_failed"] = [c.name for c in rep.failed()]
    valid = report["status"] == "converged" and not report["verify_failed"]
    pattern = replace(pattern, design={**(pattern.design or {}), "report": report, "valid": valid})
    return KagomeOutcome(pattern, report, valid, (rows, cols))


def _first_closing(d) -> tuple[Pattern | None, int]:
    """The design's nearest candidate whose closed states pass every check but the shape (a Lawson step can
    fold a row's end tile onto its neighbour in a closed state, which only contraction shows), and how many
    nearer ones were rejected; None when none passes."""
    for k, (_, nodes) in enumerate(d.candidates):
        pattern = with_contracted_states(replace(d.pattern, nodes=nodes))
        if not [c for c in verify_pattern(pattern).failed() if c.name != "target shape"]:
            return pattern, k
    return None, len(d.candidates)


def check_options(**given) -> None:
    """:class:`InputError` naming the first quad-only option given for a kagome design."""
    for key in UNSUPPORTED:
        if given.get(key):
            raise InputError(f"--{key.replace('_', '-')} is not available for kagome designs yet")


def design_kagome_pattern(
    request: PatternRequest, notify: Callable[[str], None] | None = None
) -> KagomeOutcome:
    """The kagome front door for a :class:`~.design.PatternRequest` (``fabkiri design --lattice kagome``):
    refuses the quad-only options, then :func:`design_kagome` (the target defaults to a circle)."""
    check_options(**{k: getattr(request, k) for k in UNSUPPORTED})
    rows, cols = request.tiles
    return design_kagome(
        rows,
        cols,
        request.target or "circle",
        request.size,
        tol=request.tol,
        shape_tol=request.shape_tol,
        name=request.name,
        symmetry=SYMMETRY[request.symmetry],
    )


# --symmetry: absent imposes every mirror the lattice and target share; none leaves the design free
SYMMETRY: dict[str | None, bool | str] = {None: True, "none": False, "x": "x", "y": "y"}


register_designer("kagome", design_kagome_pattern)
