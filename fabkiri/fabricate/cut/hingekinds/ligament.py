"""Ligament hinges: the tiles shrunk by half the gap and joined by strips of the
sheet itself (living hinges), cut in place as one piece of material.

The free spans of the strips (material not in any tile) are declared in the
manifest, so the verifier can check each ligament's width and length. The cutting
is :mod:`.ligament_cut`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ... import fabricability as fb
from . import HingeKind, register

if TYPE_CHECKING:
    from ..materials import Material


class Ligament(HingeKind):
    name = "ligament"
    shrinks = True
    one_piece = True
    cutter = "fabkiri.fabricate.cut.hingekinds.ligament_cut"

    def never(self, material: Material) -> str:
        return fb.ligament_never(material)

    def min_width(self, material: Material) -> float:
        # a strip's root reaches into the shrunk tile: the tile holds it and a web (cut itself asks a web;
        # at a web alone the layout verifier's four-corner recovery failed on 0.46 mm pp tiles, 16x16 circle)
        return material.ligament_width_mm + material.min_web_mm

    def hinge_spacing(self, material: Material) -> float:
        return (
            material.ligament_width_mm + material.min_web_mm
        )  # a strip is its width plus a web from the next

    def coupon_variants(self, material: Material) -> tuple[str, str, list[dict[str, float]]]:
        base = material.ligament_width_mm
        ws = sorted(
            {round(max(material.min_web_mm, base * f), 3) for f in (0.6, 0.8, 1.0, 1.25, 1.5)}
        )
        return (
            "ligament_width_mm",
            "W",
            [{"tile": 10.0, "ligament_width": w, "value": w} for w in ws],
        )

    def assembly_steps(self, n_top: int, n_bottom: int) -> list[str]:
        return [
            "the sheet comes out as one piece: push out the tiles' holes and fold along the ligaments; "
            "nothing to join"
        ]


LIGAMENT = register(Ligament())
