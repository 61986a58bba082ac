"""The design front doors' side of the opening figures (:mod:`fabkiri.pattern.opening`): the floor
``--min-opening`` is checked, the figures go in the report, the summary says them and warns when a
design opens little."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..pattern.model import Pattern
from ..pattern.opening import Opening, opening

# a floor the solver met (its row >= 0) reads back through the mm figures to about round-off
FLOOR_SLACK = 1e-9


def check_floor(floor: float | None) -> None:
    """InputError unless ``floor`` is None or a hole fraction in (0, 1)."""
    if floor is not None and not (np.isfinite(floor) and 0.0 < floor < 1.0):
        raise InputError(
            f"--min-opening is a deployed hole fraction in (0, 1) (e.g. 0.3), got {floor}"
        )


def judge(pattern: Pattern, report: dict, floor: float | None) -> list[str]:
    """Put the opening figures in ``report["opening"]`` (with the floor asked) and return the problem of a
    design that opens less than ``floor`` (the solver's row read back on the final pattern)."""
    o = opening(pattern)
    report["opening"] = {**o.to_dict(), **({"min_opening": floor} if floor else {})}
    if floor and o.hole_fraction < floor - FLOOR_SLACK:
        return [
            f"opens {100 * o.hole_fraction:.2f} % (deployed hole fraction), below --min-opening "
            f"{floor:g}"
        ]
    return []


def summary_lines(report: dict) -> list[str]:
    """The opening line and, for a design that opens little, the one-line warning (with the option that
    asks for more when it was not given)."""
    d = report.get("opening")
    if not d:
        return []
    o = Opening.from_dict(d)
    out = [o.line()]
    warn = o.warning()
    if warn:
        out.append(
            warn + ("" if d.get("min_opening") else "; design --min-opening F sets a floor on it")
        )
    return out
