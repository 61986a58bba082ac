"""What a missed shape's message may advise: never an initial guess already tried, and where the outline
cut across a pocket of the target (a reflex corner, a hollow), that instead of a promise.

:func:`annotate` adds to each missed ``report["shape"][k]`` the guesses tried (``tried_inits``) and, for the
deployed outline, the pocket its worst point lies in (``pocket``, :mod:`fabkiri.design.pockets`);
``design.conformance.describe_miss`` words them.
"""

from __future__ import annotations

from ..design.pockets import pocket_at
from ..design.targets import Target

# the worst point counts as the pocket's when it lies within this many mean tip spacings of it
POCKET_REACH_SPACINGS = 1.0


def annotate(report: dict, attempts: list[dict], target: Target | None) -> None:
    """Add what was tried, and the pocket cut across, to every missed outline of ``report``."""
    tried = [a["init"] for a in attempts]
    for k, j in (report.get("shape") or {}).items():
        if j.get("status") != "missed":
            continue
        j["tried_inits"] = tried
        c = (report.get("conformance") or {}).get(k) or {}
        if k != "deployed" or target is None or "worst" not in c:
            continue
        reach = POCKET_REACH_SPACINGS * float(c.get("spacing_mean_mm", 0.0))
        pocket = pocket_at(target, c["worst"]["at"], reach)
        if pocket is not None:
            j["pocket"] = pocket.to_dict()
