"""Pattern files in and out: the front doors of ``import``, ``export`` and every command that reads
a pattern. The formats are :mod:`fabkiri.exchange.file_formats` strategies chosen by suffix or by name;
this module adds the policy around them: fold-parity labels for the closed states a file brings,
contraction of the closed states an export needs (it must close), and the fabrication gate.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import CheckFailed, InputError, Param, PatternError
from ..exchange.file_formats import format_of, pattern_format
from ..exchange.obj import import_obj
from ..mechanics.contract import adopt_state_labels, contract
from ..pattern.model import Pattern


def load_pattern(path: str, scale: float = 1.0, *, fallback: str = "json") -> Pattern:
    """The pattern in ``path``: its format chosen by suffix (a folder: PyKirigami), else ``fallback``."""
    fmt = format_of(path, fallback)
    if fmt.read is None:
        raise InputError(f"{path}: fabkiri writes {fmt.name} files but cannot read them")
    pattern = _naming(path, fmt.read, Path(path), scale)
    return adopt_state_labels(pattern) if fmt.adopt_labels else pattern


def _naming(path: str, read, *args, **kwargs) -> Pattern:
    """``read(*args, **kwargs)``; a mesh check's error (:mod:`fabkiri.pattern.topology`: a node of three
    tiles, a node of none), which names no file, names ``path``."""
    try:
        return read(*args, **kwargs)
    except PatternError as exc:
        if str(exc).startswith(str(path)):
            raise
        raise PatternError(f"{path}: {exc}") from None


def import_pattern(path: str, contracted: list[str] | tuple = (), scale: float = 1.0) -> Pattern:
    """``fabkiri import``: a design in any readable format (OBJ when the suffix says nothing), or an
    OBJ design with its contracted OBJ files as closed states 1 and 2."""
    if contracted:
        design = _naming(path, import_obj, path, list(contracted), scale=scale)
        return with_import_tier(adopt_state_labels(design))
    return with_import_tier(load_pattern(path, scale, fallback="obj"))


def with_import_tier(pattern: Pattern) -> Pattern:
    """The imported pattern with the precision its files close to recorded in ``design.source``:
    ``closes_to_rel``, the worst closure (and stored-state mismatch) in tile sizes of the closed
    states that close within the optimiser tier, and ``tier``, the verifier's tier that meets it
    (:mod:`fabkiri.verify.tolerances`). Others' optimised files close to their solver's precision
    (1e-8, not 1e-9) and are judged at it; a state that does not close at all stays open."""
    from ..mechanics.info import describe
    from ..verify.tolerances import TIER_EXPORTED, TIER_OPTIMISED, tier_name

    figures = [
        f
        for s in describe(pattern).states
        for f in (s.max_closure_rel, s.supplied_match_rel)
        if f is not None and f <= TIER_OPTIMISED
    ]
    worst = max(figures, default=0.0)
    design = dict(pattern.design or {})
    source = design.get("source")
    design["source"] = {
        **(source if isinstance(source, dict) else {"name": source} if source else {}),
        "closes_to_rel": worst,
        "tier": tier_name(optimised=worst > TIER_EXPORTED),
    }
    return replace(pattern, design=design)


@dataclass(frozen=True)
class Exported:
    """An export: ``text`` for one file, or ``files`` by name for a folder, and the line to say."""

    text: str | None
    files: dict[str, str] | None
    said: str


def export_pattern(
    pattern: Pattern,
    fmt_name: str,
    state: str = "deployed",
    *,
    unit: float | None = None,
    force: bool = False,
    output: str = "",
    notify: Callable[[str], None] | None = None,
) -> Exported:
    """``fabkiri export``: ``pattern`` in the format ``fmt_name`` (``state``: ``deployed``, ``1`` or ``2``).

    A closed state the format needs is contracted when not stored (it must close), after the
    fabrication gate (closed states are what gets fabricated); its warnings go to ``notify``.
    """
    fmt = pattern_format(fmt_name, writable=True)
    if fmt.write is None:  # (pattern_format refused it already)
        raise InputError(f"fabkiri cannot write {fmt.name} files")
    if unit is not None and not fmt.takes_unit:  # else read by nothing
        raise InputError(Param("unit"), f" is read by nothing: {fmt.name} files are written in mm")
    if fmt.every_state and state != "deployed":
        raise InputError(
            Param("state"), f" is read by nothing: a {fmt.name} file holds every state"
        )
    need = fmt.closed_states(state)
    if need:
        from ..fabricate.gate import (  # lazy: `design` imports the CLI's readers
            claimed_states,
            closes_gate,
        )

        states = (1, 2) if fmt.every_state else claimed_states(pattern, need[0])
        for w in closes_gate(pattern, None, force=force, action="export", states=states).warnings:
            if notify is not None:
                notify(f"warning: {w}")
    for s in need:
        pattern = _with_state(pattern, s)
    out = fmt.write(pattern, state, unit)
    said = fmt.said(pattern, state, output, unit) if fmt.said else f"wrote {output}"
    return Exported(None, out, said) if isinstance(out, dict) else Exported(out, None, said)


def _closure_tol(pattern: Pattern) -> float:
    """The closure a computed state must meet, in tile sizes: the info tolerance, or the optimiser
    tier for files recorded at import as closing to an optimiser's precision."""
    # imported here: a command that only reads patterns (cut, print) does not load `info`'s report
    from ..mechanics.info import DEFAULT_TOL
    from ..verify.tolerances import TIER_OPTIMISED, tier_name

    source = (pattern.design or {}).get("source")
    optimised = isinstance(source, dict) and source.get("tier") == tier_name(optimised=True)
    return TIER_OPTIMISED if optimised else DEFAULT_TOL


def _with_state(pattern: Pattern, s: int) -> Pattern:
    """The pattern with closed state ``s`` stored (contracted if missing; it must close)."""
    if s in pattern.contracted:
        return pattern
    c = contract(pattern, s)
    if c.max_closure > _closure_tol(pattern) * pattern.tile_size:
        raise CheckFailed(
            f"state {s} does not close (loop closure {c.max_closure / pattern.tile_size:.3g} tile sizes "
            f"at hole {c.worst_hole}); nothing exported"
        )
    return pattern.with_contracted({**pattern.contracted, s: c.corners})
