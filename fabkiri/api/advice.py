"""What works when ``cut`` or ``print`` refuses a pattern at a size: :func:`alternatives`, checked.

A refusal of a fabricability check names every option that passes the same gate at the size asked
for: another material or hinge kind (``cut``'s web and edge rules in closed form,
:func:`fabkiri.fabricate.fabricability.cut_minimum`), another printer or print style (``print``'s plan
checks and the bed at that scale, :func:`~fabkiri.fabricate.fabricability.print_refusal`), the smallest
scale of the process asked for, and the ``fabkiri design`` line (with the equivalent ``fabkiri make``
line) that keeps the size when the design's own up-front checks (Pál's bound,
:func:`fabkiri.design.quad.fabrication.smallest_size`, and a print style's least tile width,
:func:`.print_tiles.narrow_tiles`) do not refuse it. Nothing is suggested that was not checked. The front doors raise :class:`Refused` (exit 1: a
check failed, whatever the flags) carrying the alternatives; the CLI prints them under the refusal.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import CheckFailed, FabkiriError, FabricationError
from ..fabricate import fabricability as fb
from ..fabricate.cut.materials import (
    DEFAULT_MATERIAL,
    HINGE_KINDS,
    Material,
    available,
    load_material,
)
from ..fabricate.print.printers import available_printers, load_printer
from ..pattern.model import Pattern
from .print_options import DEFAULT_STYLE, PrintOptions, minimum, printer_for
from .print_tiles import narrow_tiles

if TYPE_CHECKING:
    from ..fabricate.cut.sheets import CutOptions

CUT_GATE = "cut's web and edge rules at this scale (closed form)"
PRINT_GATE = "print's plan checks and bed at this scale"
DESIGN_GATE = "design's up-front checks at this size (room (Pál), a print style's least tile width)"


@dataclass(frozen=True)
class Alternative:
    """One option that works: ``command`` is the exact ``fabkiri`` line, ``detail`` what it changes and
    the figure that admits it, ``checked`` the gate it was run through (``CUT_GATE``, ``PRINT_GATE`` or
    ``DESIGN_GATE``) and ``changes`` the options it sets (``material``, ``hinge``, ``printer``, ``style``,
    ``scale``, ``size``), for callers that run it themselves (``fabkiri make``, notebooks)."""

    what: str  # "scale", "material", "printer", "design", "make"
    command: str
    detail: str
    checked: str
    changes: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Ask:
    """How the refused command was given, so each suggestion is a line that runs: the pattern ``file``,
    the ``output`` folder, ``flags`` kept in every suggestion (sheet, layout, state, ...) and
    ``process_flags`` (material or printer field overrides) kept only where the material or printer
    stays the one asked for (other presets are checked as shipped)."""

    file: str = "pattern.json"
    output: str | None = None
    flags: tuple[str, ...] = ()
    process_flags: tuple[str, ...] = ()
    given: str | None = None  # the --material or --printer as typed (a preset name or a .json file)


class Refused(CheckFailed, FabricationError):
    """A fabricability refusal (exit 1, a check failed, whatever the flags) carrying the
    :class:`Alternative` s that pass; its text is the one-line reason, :meth:`option_lines` the options
    (the CLI prints them on stdout, one runnable line each)."""

    def __init__(self, reason: str | FabkiriError, options: list[Alternative]):
        super().__init__(reason)  # a refusal's own error: its Params worded as it words them
        self.reason = str(reason)
        self.alternatives = list(options)

    def option_lines(self) -> list[str]:
        """``# options ...`` and then one ``fabkiri ...    # detail`` line per option: each runs as it is."""
        return option_lines(self.alternatives)


def option_lines(options: list[Alternative]) -> list[str]:
    """The lines a refusal prints on stdout: a ``#`` heading, then ``fabkiri ...    # detail`` each."""
    if not options:
        return ["# options: none passes the same checks"]
    return ["# options (each passes the same checks; run one as it is):"] + [
        f"{a.command}    # {a.detail}" for a in options
    ]


def alternatives(
    pattern: Pattern, process: str, scale: float | None = 1.0, **kw: Any
) -> list[Alternative]:
    """Every checked option for ``cut`` (``process="cut"``) or ``print`` of ``pattern`` at ``scale`` (mm
    per mm of the pattern; a design is made at scale 1 = its ``--size``; None: at any size, as
    ``--scale auto``). Keywords: ``size_mm`` (instead of ``scale``: the size asked for, over the stored
    design's ``--size``), ``options`` (a :class:`~fabkiri.fabricate.cut.sheets.CutOptions` or
    :class:`~fabkiri.api.print.PrintOptions`; default: the design's intent) and ``ask`` (:class:`Ask`).
    Each :class:`Alternative` has passed the same gate as the refusal (its ``checked``): run its
    ``command``, or apply its ``changes``, and it passes that gate."""
    if kw.get("size_mm") is not None:
        stored = ((pattern.design or {}).get("target") or {}).get("size_mm")
        if not stored:
            raise ValueError("size_mm needs a pattern with a stored design target size")
        scale = float(kw["size_mm"]) / float(stored)
    if process == "cut":
        return cut_alternatives(pattern, kw.get("options"), scale, ask=kw.get("ask") or Ask())
    if process == "print":
        return print_alternatives(pattern, kw.get("options"), scale, ask=kw.get("ask") or Ask())
    raise ValueError(f"process must be 'cut' or 'print', got {process!r}")


def _line(*words: Any) -> str:
    return " ".join(shlex.quote(str(w)) for w in words if w is not None and w != "")


def _out(ask: Ask) -> tuple[str, ...]:
    return ("-o", ask.output) if ask.output else ()


def _scale_words(scale: float | None) -> tuple[str, str]:
    return ("--scale", "auto" if scale is None else f"{scale:g}")


def _run_line(ask: Ask, words: tuple[str, str, str, str, str], at: float | None, own: bool) -> str:
    """The ``fabkiri cut`` or ``print`` line of ``words`` (command, --material or --printer and its name,
    --hinge or --style and its value) at scale ``at``; ``own``: the material or printer asked for,
    named as typed and with its overrides."""
    process, flag, name, kind_flag, kind = words
    extra = ask.process_flags if own else ()
    name = (ask.given or name) if own else name
    return _line(
        "fabkiri", process, ask.file, flag, name, kind_flag, kind,
        *_scale_words(at), *ask.flags, *extra, *_out(ask),
    )  # fmt: skip


# ------------------------------------------------------------------ cut
def cut_refusal(
    corners, material: Material, kind: str, scale: float | None
) -> fb.CutMinimum | None:
    """The closed-form minimum when ``cut``'s rules refuse ``material``/``kind`` at ``scale`` (None: any
    scale works nowhere), else None (the rules accept it)."""
    need = fb.cut_minimum(corners, material, kind)
    return need if _refuses(need, scale) else None


def _refuses(need: fb.CutMinimum, scale: float | None) -> bool:
    """Whether the rules with minimum ``need`` refuse ``scale`` (None: any scale; refused if none works)."""
    if need.scale is None:
        return True
    return scale is not None and need.exact is not None and scale < need.exact * (1 - 1e-9)


def cut_alternatives(
    pattern: Pattern, options: CutOptions | None, scale: float | None, *, ask: Ask = Ask()
) -> list[Alternative]:
    """The checked options for ``cut`` at ``scale``: the smallest scale of the material and hinge kind
    asked for, every other preset material and hinge kind whose rules pass at ``scale``, the design
    line that keeps the size."""
    from ..fabricate.cut.hingekinds import hinge_kind
    from ..fabricate.cut.sheets import CutOptions, closed_states
    from .intent import design_intent

    if options is None:
        options = CutOptions(
            material=load_material(design_intent(pattern, "material") or DEFAULT_MATERIAL),
            hinge=design_intent(pattern, "hinge"),
        )
    corners = closed_states(pattern)[options.state]
    mat = options.material
    kind = options.hinge or mat.hinge
    out: list[Alternative] = []

    def cmd(name: str, k: str, at: float | None, own: bool) -> str:
        return _run_line(ask, ("cut", "--material", name, "--hinge", k), at, own)

    need = fb.cut_minimum(corners, mat, kind)
    if need.scale is not None and scale is not None and need.scale > scale:
        out.append(
            Alternative(
                "scale",
                cmd(mat.name, kind, need.scale, True),
                f"{mat.name} {kind} at its smallest scale, --width {need.width_mm:g} mm",
                CUT_GATE,
                {"material": mat.name, "hinge": kind, "scale": need.scale},
            )
        )
    for name in (mat.name, *(n for n in available() if n != mat.name)):  # the one asked first
        own = name == mat.name
        preset = mat if own else load_material(name)
        fits = []
        for k in HINGE_KINDS:
            if (name, k) == (mat.name, kind) or (
                options.layout and not _layout_ok(hinge_kind(k), options.layout)
            ):
                continue
            m = fb.cut_minimum(corners, preset, k)
            if not _refuses(m, scale):
                fits.append((k, m))
        if fits:
            k, m = next(((k, m) for k, m in fits if k == preset.hinge), fits[0])
            also = [f for f, _ in fits if f != k]
            out.append(
                Alternative(
                    "material",
                    cmd(name, k, scale, own),
                    f"{name} {k} (from --scale {m.scale:g})"
                    + (f"; also --hinge {', '.join(also)}" if also else ""),
                    CUT_GATE,
                    {"material": name, "hinge": k, "scale": scale},
                )
            )
    line = design_line(
        pattern,
        1.0 if scale is None else scale,
        {"material": ask.given or mat.name, "hinge": kind},
        ask,
    )
    if line is not None:
        out += [*make_line(pattern, line, ask), line]  # the design line last, as before
    return out


def _layout_ok(kind, layout: str) -> bool:
    try:
        kind.check_layout(layout)
    except FabkiriError:
        return False
    return True


# ------------------------------------------------------------------ print
def print_alternatives(
    pattern: Pattern,
    options: PrintOptions | None,
    scale: float | None,
    *,
    ask: Ask = Ask(),
    memo: dict | None = None,
) -> list[Alternative]:
    """The checked options for ``print`` at ``scale``: the smallest (or, past the bed, the largest) scale
    of the printer and style asked for, every preset printer and style whose plan checks and bed pass at
    ``scale`` (None: that print at some scale), the design line that keeps the size. ``memo``: the plan
    checks' answers for ``pattern`` known already (the refused print's, :func:`.print_options.minimum`)."""
    from .intent import design_intent

    o = options or PrintOptions()
    state = int(o.state or design_intent(pattern, "state") or 1)
    style = o.style or design_intent(pattern, "style") or DEFAULT_STYLE
    given = o.printer or design_intent(pattern, "printer")
    asked = printer_for(given, style, o)
    out: list[Alternative] = []

    def cmd(printer: str, s: str, at: float | None, own: bool) -> str:
        return _run_line(ask, ("print", "--printer", printer, "--style", s), at, own)

    memo = {} if memo is None else memo
    found = _print_scale(pattern, style, asked, state, scale, memo) if scale is not None else None
    if found is not None:
        at, text = found
        out.append(
            Alternative(
                "scale",
                cmd(asked.name, style, at, True),
                text,
                PRINT_GATE,
                {"printer": asked.name, "style": style, "scale": at},
            )
        )
    styles = (style, *(s for s in fb.PRINT_STYLES if s != style))
    names = (
        asked.name,
        *(n for n in available_printers() if n != asked.name),
    )  # the one asked first
    for name in names:
        own = name == asked.name
        fits = _fits(pattern, o, given, name, own, styles, state, scale, memo)
        if fits:
            s, from_ = fits[0]
            also = [f for f, _ in fits[1:]]
            out.append(
                Alternative(
                    "printer",
                    cmd(name, s, scale, own),
                    f"{name} {s}"
                    + ("" if scale is not None else f" (from --scale {from_:g})")
                    + (f"; also --style {', '.join(also)}" if also else ""),
                    PRINT_GATE,
                    {"printer": name, "style": s, "scale": scale},
                )
            )
    if scale is not None and not any(a.what == "printer" for a in out):
        # nothing prints at this size: the printers and styles that print at some size
        out += [
            replace(a, what="scale")
            for a in print_alternatives(pattern, o, None, ask=ask, memo=memo)
            if a.what == "printer"
        ]
    line = design_line(
        pattern,
        1.0 if scale is None else scale,
        {"printer": given or asked.name, "style": style},
        ask,
    )
    if line is not None:
        out += [*make_line(pattern, line, ask), line]  # the design line last, as before
    return out


def _fits(pattern: Pattern, o, given, name: str, own: bool, styles, state: int, scale, memo: dict):
    """``(style, scale)`` of every style in ``styles`` that printer ``name`` prints at ``scale`` (None: at
    some scale); the printer asked for (``own``) with the command's overrides, past its style asked for
    (``styles[0]``)."""
    from ..fabricate.print.job import print_style

    fits = []
    for s in styles[1:] if own else styles:
        pr = printer_for(given, s, o) if own else load_printer(name).with_overrides()
        if print_style(s).plan is None:
            continue
        ok = _prints(pattern, s, pr, state, scale, memo)
        if ok is not None:
            fits.append((s, ok))
    return fits


def _print_scale(pattern: Pattern, style: str, printer, state: int, scale: float, memo: dict):
    """``(scale, text)``: the smallest scale the plan checks accept, or past the bed the largest the bed
    takes, for the printer and style asked for; None when no scale prints it or ``scale`` already does."""
    need = minimum(pattern, style, printer, state, memo)
    if not need.possible or need.min_scale is None:
        return None
    top = need.max_scale
    at = need.min_scale if scale < need.min_scale else top
    if at is None or at == scale:
        return None
    bed = "" if top is None else f" to {top:g} (the bed)"
    return at, f"{printer.name} {style} prints from --scale {need.min_scale:g}{bed}"


def _prints(
    pattern: Pattern, style: str, printer, state: int, scale: float | None, memo: dict
) -> float | None:
    """``scale`` (or, None, the smallest that prints) when ``printer`` prints ``style`` there, else None."""
    if scale is not None:
        return None if _refused(pattern, style, printer, state, scale, memo) else scale
    # at any size: the closed form, checked at the scale it names (one plan evaluation, not a bisection)
    key = fb.plan_family(printer, style)
    if key not in memo:
        bound = fb.print_bound(pattern, style, printer, state)
        memo[key] = bound.min_scale
    at = memo[key]
    if at is None or _refused(pattern, style, printer, state, at, memo):
        return None
    return at


def _refused(pattern: Pattern, style: str, printer, state: int, scale: float, memo: dict) -> bool:
    """Whether :func:`~fabkiri.fabricate.fabricability.print_refusal` refuses, the bed asked first: its
    box of the closed corners needs no plan geometry (a pinned plan past the bed is slow to build)."""
    try:
        top = fb.bed_scale(fb.scaled(pattern, scale), style, state, printer)
    except CheckFailed:  # it does not close: the plan checks say so
        top = None
    if top is not None and top < 1.0:
        return True
    return bool(fb.print_refusal(pattern, style, printer, state, scale, memo))


# ------------------------------------------------------------------ design
def design_line(
    pattern: Pattern, scale: float | None, process: dict[str, str], ask: Ask
) -> Alternative | None:
    """The ``fabkiri design`` line that makes the pattern's design again, for ``process`` (``material``
    and ``hinge``, or ``printer`` and ``style``), at the size asked for (the design's ``--size`` times
    ``scale``); None when the pattern has no stored design target the CLI can name, the design was
    already made for this process at this size, or the design's own up-front checks refuse it (the
    room check rules the size out, or the tiles are too narrow for the print style)."""
    from ..design.quad.fabrication import smallest_size
    from ..design.targets.lookup import named_targets, target_from_dict
    from ..fabricate import design_limits

    design = pattern.design or {}
    target_d, lattice = design.get("target"), pattern.lattice or {}
    if scale is None or not isinstance(target_d, dict) or "rows" not in lattice:
        return None
    name = str(target_d.get("name", ""))
    if name not in named_targets() or "size_mm" not in target_d:
        return None
    size = float(f"{float(target_d['size_mm']) * scale:.4g}")
    intent = (design.get("options") or {}).get("fabrication") or {}
    if (
        all(intent.get(k) == v for k, v in process.items())
        and abs(float(intent.get("size_mm", -1)) - size) <= 1e-6 * size
    ):
        return None  # already this design: it would repeat what was tried
    target = target_from_dict(target_d).scaled_to(size)
    try:
        limits, _ = design_limits.resolve(
            process.get("material"), process.get("hinge"), process.get("printer"),
            process.get("style"), None, None, target,
        )  # fmt: skip
    except FabkiriError:
        return None
    rows, cols = int(lattice["rows"]), int(lattice["cols"])
    if limits is None or smallest_size(size, abs(target.area), rows * cols, limits) is not None:
        return None
    if "printer" in process and narrow_tiles(
        target, (rows, cols), process["printer"], process["style"]
    ):
        return None  # the design refuses tiles too narrow for the print style up front too
    opts = design.get("options") or {}
    flags = [
        "--material" if "material" in process else "--printer",
        process.get("material") or process["printer"],
    ]
    flags += [
        "--hinge" if "hinge" in process else "--style",
        process.get("hinge") or process["style"],
    ]
    new = _beside(ask, process.get("material") or process["printer"], ".json")
    command = _line(
        "fabkiri", "design", "--tiles", f"{rows}x{cols}", "--target", name, "--size", f"{size:g}",
        *(["--lattice", lattice["kind"]] if lattice.get("kind", "quad") != "quad" else []),
        *(["--rigid"] if opts.get("rigid") else []),
        *(["--symmetry", opts["symmetry"]] if opts.get("symmetry") else []),
        *flags, "-o", new,
    )  # fmt: skip
    return Alternative(
        "design",
        command,
        f"a design made for {' '.join(process.values())} at --size {size:g}, which the design's "
        f"up-front checks do not refuse (a necessary condition, not designed; then "
        f"`fabkiri {'cut' if 'material' in process else 'print'} {new}`)",
        DESIGN_GATE,
        {**process, "size": size},
    )


def _beside(ask: Ask, tag: str, suffix: str = "") -> str:
    """Where a suggested design or make writes: beside the output (else the pattern), named after the
    pattern and ``tag`` (the material or printer, a preset name or a .json file)."""
    where = Path(ask.output).parent if ask.output else Path(ask.file).parent
    return str(where / f"{Path(ask.file).stem}-{Path(tag).stem}{suffix}")


def make_line(pattern: Pattern, design: Alternative, ask: Ask) -> list[Alternative]:
    """The ``fabkiri make`` line equivalent to the ``design`` option (the same target, size, tiles and
    process, the same room check passed), when ``make`` can say all the design asks for: a quad
    lattice without ``--rigid`` or ``--symmetry``. Empty otherwise."""
    stored = pattern.design or {}
    opts = stored.get("options") or {}
    lattice = pattern.lattice or {}
    if lattice.get("kind", "quad") != "quad" or opts.get("rigid") or opts.get("symmetry"):
        return []
    ch = design.changes
    process = (
        ["--material", ch["material"], "--hinge", ch["hinge"]]
        if "material" in ch
        else ["--printer", ch["printer"], "--style", ch["style"]]
    )
    floor = opts.get("min_opening")
    folder = _beside(ask, str(ch.get("material") or ch["printer"]))
    command = _line(
        "fabkiri", "make", stored["target"]["name"], "--size", f"{ch['size']:g}",
        *process, "--tiles", f"{lattice['rows']}x{lattice['cols']}",
        *(["--min-opening", f"{floor:g}"] if floor else []), "-o", folder,
    )  # fmt: skip
    what = "cuts" if "material" in ch else "prints"
    detail = f"the same design in one go: designs, {what}, deploys and reports into {folder}"
    return [Alternative("make", command, detail, DESIGN_GATE, dict(ch))]


__all__ = [
    "CUT_GATE",
    "DESIGN_GATE",
    "PRINT_GATE",
    "Alternative",
    "Ask",
    "Refused",
    "alternatives",
    "cut_alternatives",
    "cut_refusal",
    "design_line",
    "make_line",
    "option_lines",
    "print_alternatives",
]
