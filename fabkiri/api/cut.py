"""``cut_files``: a pattern's laser-cut files, verified by reading them back, as :class:`CutOutcome`.

The sheets are made by :func:`fabkiri.fabricate.cut.sheets.cut_pattern`; this front door holds the policy
``fabkiri cut`` applies around it: the material and hinge kind the design was made for, the bounds
on ``scale`` and ``width``, a tube's flat sheet with its seam marks and note, and the read-back
verification that must pass before anything may be written. A failed check raises
:class:`~fabkiri.errors.CheckFailed`; bad input raises :class:`~fabkiri.errors.InputError`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import Any

from .. import limits
from ..errors import CheckFailed, FabkiriError, FabricationError, InputError, Param
from ..fabricate.cut.materials import DEFAULT_MATERIAL, Material, load_material, parse_setting
from ..fabricate.cut.readback import Readback, verified_files
from ..fabricate.cut.sheets import CutOptions, CutResult, closed_states, cut_pattern
from ..fabricate.tube.sheet import mark_seam, tube_cut_inputs
from ..pattern.fingerprint import KEY, fingerprint
from ..pattern.model import Pattern
from .advice import Ask, Refused, cut_alternatives, cut_refusal
from .intent import design_intent

_SHEET = re.compile(r"\s*([0-9.]+)\s*[xX×]\s*([0-9.]+)\s*")


def parse_sheet(value: str | tuple[float, float]) -> tuple[float, float]:
    """A sheet's width and height in mm from ``"600x400"`` or a pair, both positive and finite;
    else :class:`InputError` naming ``sheet`` (``--sheet`` on the command line)."""
    m = _SHEET.fullmatch(value) if isinstance(value, str) else None
    try:
        w, h = (float(m.group(1)), float(m.group(2))) if m else map(float, value)
    except (TypeError, ValueError):
        raise InputError(
            Param("sheet"), f" expects WxH in mm such as 600x400, got {value!r}"
        ) from None
    if not (0 < w < math.inf and 0 < h < math.inf):
        raise InputError(Param("sheet"), f" needs a positive width and height, got {value!r}")
    return w, h


def cut_material(
    pattern: Pattern,
    name: str | None = None,
    hinge: str | None = None,
    *,
    changes: dict[str, Any] | None = None,
    settings: Iterable[str] = (),
) -> tuple[Material, str | None]:
    """The material and hinge kind to cut with: a named material (or, none named, the design's
    material and hinge kind, else acrylic-3), with ``changes`` (None values ignored) and then the
    ``FIELD=VALUE`` ``settings`` applied."""
    if name is None:
        name = design_intent(pattern, "material") or DEFAULT_MATERIAL
        hinge = hinge or design_intent(pattern, "hinge")
    material = load_material(name)
    changes = dict(changes or {})
    for setting in settings:
        key, value = parse_setting(setting)
        changes[key] = value
    given = [k for k in ("strain_limit", "gap_mm") if changes.get(k) is not None]
    _refuse_ligament_only(hinge or material.hinge, given)
    return material.override(**changes), hinge


def _refuse_ligament_only(hinge: str, given: Iterable[str]) -> None:
    """Settings only ligament hinges read, given for another kind: refused rather than read by nothing."""
    for name in given if hinge != "ligament" else ():
        raise InputError(
            Param(name, flag="--" + name.removesuffix("_mm").replace("_", "-")),
            f" is read by ligament hinges only; these are {hinge} hinges: give ",
            Param("hinge", "ligament"),
            ", or drop it",
        )


@dataclass(frozen=True, eq=False)
class CutOutcome:
    """A verified cut: ``files`` (names relative to the output folder, ``manifest.json`` included),
    the cut ``result`` (sheets, manifest, warnings) and the ``readback`` report that passed (with
    ``force``, one whose verifier failed on a pattern that does not close)."""

    result: CutResult
    readback: Readback
    files: dict[str, bytes]

    def __repr__(self) -> str:  # the files are bytes: named, not printed
        return f"CutOutcome({self.result!r}, read-back {'ok' if self.readback.ok else 'failed'})"


def cut_files(
    pattern: Pattern, options: CutOptions, *, use_verifier: bool = True, ask: Ask | None = None
) -> CutOutcome:
    """Cut ``pattern`` as ``options`` say (a tube: its flat sheet and seam), then read the files back.
    A refusal of the web and edge rules raises :class:`~fabkiri.api.advice.Refused` naming the options
    that pass (``ask``: how the command was given, so that each is a line that runs)."""
    if options.ligament_width is not None:
        _refuse_ligament_only(options.hinge or options.material.hinge, ["ligament_width"])
    if options.label_height is not None and not options.labels:
        raise InputError(Param("label_height"), " sizes the labels; there are none (no labels)")
    if isinstance(
        options.scale, float
    ):  # numbers that would overflow the geometry: one line, up front
        limits.check_scale(pattern.nodes, pattern.tiles, options.scale, Param("scale"))
    if isinstance(options.width, float):
        limits.check_length(options.width, Param("width"))
    made_from = fingerprint(pattern)  # the input pattern's (a tube's, not its flat sheet's)
    pattern, seam_files, seam_entry = tube_cut_inputs(
        pattern, options.state
    )  # a tube: its flat sheet

    def cut_once(opts: CutOptions) -> CutResult:
        result = cut_pattern(pattern, opts)
        result.manifest[KEY] = made_from
        if (
            seam_files
        ):  # both ends of every seam hinge engraved, the note and the manifest entry added
            mark_seam(result, seam_entry["hinges"], pattern, opts.state, opts)
            result.files.update(seam_files)
            result.manifest["seam"] = seam_entry
        return result

    def verified(result: CutResult) -> CutOutcome:
        rb, files = verified_files(pattern, result, use_verifier=use_verifier, force=options.force)
        return CutOutcome(result=result, readback=rb, files=files)

    result = _refusal_advice(lambda: cut_once(options), pattern, options, ask)
    try:
        return verified(result)
    except CheckFailed as exc:
        if "auto" not in (options.scale, options.width) or not str(exc).startswith(
            READBACK_REFUSED
        ):
            raise
        return _read_back_scale(
            lambda k: verified(cut_once(replace(options, scale=k, width=None))),
            float(result.manifest["scale"]),
            exc,
        )


def _refusal_advice(
    step: Callable[[], CutResult], pattern: Pattern, options: CutOptions, ask: Ask | None
) -> CutResult:
    """``step()``; when it fails and the web and edge rules refuse the material and hinge kind at the
    scale asked for, the refusal is raised again as :class:`Refused` with the checked options (exit 1
    whatever the flags: a ligament sheet that cannot be cut used to exit 2 at a given scale)."""
    try:
        return step()
    except Refused:  # already advised
        raise
    except (CheckFailed, FabricationError) as exc:
        try:  # a pattern that does not close has no closed-form minimum: the refusal as it was
            corners = closed_states(pattern)[options.state]
            scale = _asked_scale(options, corners)
            kind = options.hinge or options.material.hinge
            why = cut_refusal(corners, options.material, kind, scale)
        except FabkiriError:
            why = None
        if why is None:
            raise
        raise Refused(exc, cut_alternatives(pattern, options, scale, ask=ask or Ask())) from None


def _asked_scale(options: CutOptions, corners) -> float | None:
    """The scale asked for: ``--scale``, ``--width`` over the closed span, 1, or None for ``auto``."""
    if "auto" in (options.scale, options.width):
        return None
    if isinstance(options.width, float):
        return options.width / float(corners[..., 0].max() - corners[..., 0].min())
    return 1.0 if options.scale is None else float(options.scale)


READBACK_REFUSED = "read-back verification failed"
AUTO_STEP = 1.05  # --scale auto steps up by 5 % while the read-back refuses the files ...
AUTO_STEPS = 10  # ... at most this often (x1.63), then gives the first refusal


def _read_back_scale(
    cut_at: Callable[[float], CutOutcome], refused: float, first: CheckFailed
) -> CutOutcome:
    """``--scale auto`` when the read-back refuses the files at the size the sheet rules allow
    (``refused``; a kagome ligament sheet's small triangles among their strips): step the scale up by
    5 % until it accepts them, then bisect between the last refusal and the first acceptance to
    0.1 % (stated to 4 digits). The files returned are always ones the read-back accepted, at the
    smallest scale tried that it accepted; a warning says so. If none is found, raises the refusal
    at the largest scale tried."""
    from ..fabricate import fabricability as fb

    last = [first]

    def at(k: float) -> CutOutcome | None:
        try:
            return cut_at(k)
        except CheckFailed as exc:
            if not str(exc).startswith(READBACK_REFUSED):
                raise
            last[0] = exc
            return None

    lo = hi = refused
    found = None
    for _ in range(AUTO_STEPS):
        hi = fb.ceil_sig(hi * AUTO_STEP)
        if (found := at(hi)) is not None:
            break
        lo = hi
    if found is None:  # the binding limit at the largest scale tried, not at the first
        raise CheckFailed(
            Param("scale", "auto"), ": refused from ", Param("scale", refused, "g"),
            f" up to {hi:g}; at ", Param("scale", hi, "g"), ": ", last[0],
        )  # fmt: skip
    while hi - lo > fb.BISECT_RTOL * hi:
        mid = fb.ceil_sig(0.5 * (lo + hi))
        if mid >= hi:
            break
        got = at(mid)
        lo, hi, found = (mid, hi, found) if got is None else (lo, mid, got)
    found.result.warnings.append(
        f"--scale auto: the read-back refused the files at --scale {refused:g}; "
        f"cut at {hi:g}, the smallest scale found (0.1 %) at which it accepts them"
    )
    return found
