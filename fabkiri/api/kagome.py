"""``design_kagome``: the front door of kagome inverse design (``fabkiri design --lattice kagome``).

Policy: build the standard R x C kagome at the target's size, design it onto the target
(:mod:`fabkiri.design.kagome_fit`), contract both closed states, verify the pattern (both states,
overlaps, target shape) and judge the shape. The best iterate is always returned; ``valid`` and
``exit_code`` say whether it met the equality tolerance and every check.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

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

# options of the quad design that have no kagome counterpart yet
UNSUPPORTED = ("rigid", "symmetry", "holes", "contracted_target", "material", "printer", "min_feature",
               "min_hole")


@dataclass(frozen=True)
class KagomeOutcome:
    """A kagome design, its report and its verdict."""

    pattern: Pattern
    report: dict
    valid: bool

    @property
    def exit_code(self) -> int:
        return 0 if self.valid else 1

    def write(self, path) -> None:
        atomic_write(path, dumps(self.pattern))


def design_kagome(rows: int, cols: int, target: str, size: float | None = None, *, tol: float = 1e-10,
                  shape_tol: str = conf.DEFAULT_SHAPE_TOL, name: str | None = None) -> KagomeOutcome:
    """Design a reconfigurable R x C kagome whose deployed outline follows ``target`` (mm)."""
    tgt = load_target(target, size)
    shape = conf.parse_shape_tol(shape_tol)
    unit = standard_kagome(rows, cols, tile_size=1.0)
    tile = tgt.size / float(np.ptp(unit.nodes, axis=0).max())  # the standard spans the target
    d = design(standard_kagome(rows, cols, tile_size=tile), tgt)
    pattern = with_contracted_states(d.pattern)
    measured = conf.deployed(pattern.nodes, pattern.topology, tgt)
    verdict = conf.judge(measured, shape, (rows, cols))
    rel = d.max_equality  # normalised units: already relative to the tile size
    report: dict[str, Any] = {"status": "converged" if d.converged and rel <= tol else "unconverged",
              "max_equality_residual": rel, "tol": tol, "iterations": d.iterations,
              "penalty_status": d.penalty_status, "max_tip_distance_mm": d.max_tip_distance_mm,
              "tile_size_mm": tile, "conformance": measured, "shape": verdict}
    pattern = replace(pattern, name=name or pattern.name,
                      design={**(pattern.design or {}), "report": report, "shape_tol": shape_tol})
    rep = verify_pattern(pattern, shape_tol=shape_tol)
    report["verify_failed"] = [c.name for c in rep.failed()]
    valid = report["status"] == "converged" and not report["verify_failed"]
    pattern = replace(pattern, design={**(pattern.design or {}), "report": report, "valid": valid})
    return KagomeOutcome(pattern, report, valid)


def check_options(**given) -> None:
    """:class:`InputError` naming the first quad-only option given for a kagome design."""
    for key in UNSUPPORTED:
        if given.get(key):
            raise InputError(f"--{key.replace('_', '-')} is not available for kagome designs yet")
