"""The one gate every fabrication command passes: the pattern must close in both states.

``cut``, ``print`` and ``export`` of a closed state call :func:`closes_gate`
before building any file, with their process's tolerance (the material's, the
printer's, the verifier's own) and the same ``--force``. The gate is the
verifier's tile checks, the closed states and their edge pairs: both states
for ``cut`` (its read-back reassembles the other state), the printed or
exported state and any other state the pattern stores for ``print`` and
``export`` (see :func:`claimed_states`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..errors import CheckFailed, Param
from ..pattern.model import Pattern
from ..verify import Check, Report, verify_pattern
from ..verify.pattern_checks import state_check_id

GATE_GROUPS = (
    "tiles",
    "state 1",
    "state 2",
)  # plus each state's edge pairs (fold edges of equal length)
# action -> (past participle, third person) for the message
VERBS = {"cut": ("cut", "cuts"), "print": ("printed", "prints"), "export": ("exported", "exports")}


def check_text(c: Check, scale: float) -> str:
    """A failed verifier check, lengths in the file's millimetres."""
    k = scale if c.unit == "mm" else (scale * scale if c.unit == "mm²" else 1.0)
    if isinstance(c.value, (int, float)) and isinstance(c.tol, (int, float)):
        return f"{c.name} {c.value * k:.3g} > {c.tol * k:.3g} {c.unit}"
    return f"{c.name} failed"


@dataclass
class GateResult:
    report: Report
    failed: list = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def claimed_states(pattern: Pattern, state: int) -> tuple[int, ...]:
    """The closed states a fabrication of ``state`` must find closing: that one, and the other one
    too when the pattern stores it (a contractible pattern, closing one way only, stores neither)."""
    other = 3 - state
    return (state, other) if other in pattern.contracted else (state,)


def closes_gate(
    pattern: Pattern,
    tol_mm: float | None,
    *,
    scale: float = 1.0,
    force: bool = False,
    action: str = "cut",
    tolerance: str = "material",
    states: tuple[int, ...] = (1, 2),
) -> GateResult:
    """Verify ``pattern`` at ``tol_mm`` (in the file's mm, the pattern drawn ``scale`` times its size;
    None: the verifier's own tolerance); raise :class:`CheckFailed` unless its tiles and ``states``
    close, or ``force``."""
    report = verify_pattern(pattern, tol_mm=None if tol_mm is None else tol_mm / scale)
    groups = ("tiles", *(f"state {s}" for s in states))
    gate = [
        c
        for c in report.checks
        if c.applies
        and not c.ok
        and (c.group in groups or c.id in {state_check_id(s, "edge-pairs") for s in states})
    ]
    out = GateResult(report, gate)
    if not gate:
        return out
    msg = "; ".join(check_text(c, scale) for c in gate[:3]) + (
        f" (+{len(gate) - 3} more)" if len(gate) > 3 else ""
    )
    done, does = VERBS[action]
    if not force:
        at = (
            f"at the {tolerance} tolerance {tol_mm:g} mm"
            if tol_mm is not None
            else "at the verifier's tolerance"
        )
        which = "in both states" if len(states) == 2 else f"in closed state {states[0]}"
        raise CheckFailed(
            f"the pattern does not close {which} {at}: {msg}; nothing {done} (",
            Param("force", True),
            f" {does} it anyway)",
        )
    out.warnings.append(f"{done} with --force although the pattern does not close: {msg}")
    return out
