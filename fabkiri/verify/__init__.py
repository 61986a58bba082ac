"""The geometric verifier: proof that a pattern and its cut layout close into both compact states.

``verify_pattern(pattern)`` checks the pattern itself; ``verify_layout(pattern, path)`` reads a DXF or
SVG cut file (fabkiri's own, with its ``manifest.json``, or plain closed outlines from another tool),
recovers the tiles and checks them against both closed states. Both return a :class:`Report`.
"""

from .pattern_checks import rigid_claimed, tolerances, verify_pattern
from .report import Check, Report

__all__ = ["Check", "Report", "verify_pattern", "verify_layout", "rigid_claimed", "tolerances"]


def verify_layout(pattern, layout_path, manifest=None, tol_mm=0.05, tol_rad=1e-6):
    """See :func:`fabkiri.verify.layout.verify_layout`."""
    from .layout import verify_layout as _impl

    return _impl(pattern, layout_path, manifest=manifest, tol_mm=tol_mm, tol_rad=tol_rad)
