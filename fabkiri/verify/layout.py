"""Cut-layout verification (work in progress: reading DXF/SVG layouts)."""

from __future__ import annotations

from ..errors import VerifyError


def verify_layout(pattern, layout_path, manifest=None, tol_mm=0.05, tol_rad=1e-6):
    raise VerifyError("layout verification is not implemented yet")
