"""Separate tiles: each tile cut on its own, offset by half the kerf, laid out
exploded or nested; both corners of every hinge carry the partner tile's ID and
the face letter, so the maker finds which corners join. The cutting is :mod:`.separate_cut`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ....errors import InputError
from . import HingeKind, register

if TYPE_CHECKING:
    from ..materials import Material


class Separate(HingeKind):
    name = "separate"
    default_layout = "exploded"
    both_corner_labels = True
    cut_apart = True
    cutter = "fabkiri.fabricate.cut.hingekinds.separate_cut"

    def check_layout(self, layout: str) -> None:
        if layout == "in-place":
            raise InputError(
                "separate tiles are offset by half the kerf and would overlap in place; "
                "use --layout exploded or nested"
            )

    def hinge_spacing(self, material: Material) -> float:
        return 0.0  # tiles cut apart: nothing on the tile between two hinges

    def coupon_variants(self, material: Material) -> tuple[str, str, list[dict[str, float]]]:
        ks = sorted(
            {round(max(0.01, material.kerf_mm * f), 3) for f in (0.5, 0.75, 1.0, 1.25, 1.5)}
        )
        return "kerf_mm", "K", [{"tile": 10.0, "kerf": k, "value": k} for k in ks]

    def assembly_steps(self, n_top: int, n_bottom: int) -> list[str]:
        return [
            "0. place each tile by its ID next to its partners: a corner label '12T' joins this corner "
            "to tile 12 on the top face (B: bottom)",
            *super().assembly_steps(n_top, n_bottom),
        ]


SEPARATE = register(Separate())
