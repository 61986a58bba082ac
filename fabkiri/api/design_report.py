"""The design report: what a design writes into ``pattern.json`` under ``design.report``, as types; and
:class:`DesignAttempt`, one judged try of the quad front door that the report comes from.

The report stays a plain ``dict`` (its JSON is written as it always was); these ``TypedDict`` types name
its keys and their types for a reader and for mypy, and ``design-report.schema.json`` beside this module
states the same for any JSON reader. A quad design (:func:`~.design.design_pattern`) writes a
:class:`DesignReport`, a kagome one (:func:`~.kagome.design_kagome`) a :class:`KagomeReport`.
"""

from __future__ import annotations

from typing import Any, NamedTuple, NotRequired, TypedDict

from ..pattern.model import Pattern
from ..schemas import load_schema, schema_problem

SCHEMA = "design-report.schema.json"


class DesignAttempt(NamedTuple):
    """One judged design: the solver's pattern with its report, what failed, and both closed states."""

    pattern: Pattern
    report: dict  # the solver's report with the front door's checks, conformance and shape verdicts
    problems: list[str]  # why it is not valid (empty when valid)
    valid: bool  # converged, both closed states close, no overlapping tiles
    states: dict  # the closed states' tile corners by state (1, 2)


class Conformance(TypedDict, total=False):
    """How close one outline came to its target curve (``fabkiri.design.core.conformance``)."""

    hausdorff_mm: float
    hausdorff_rel: float  # over the target's size
    one_minus_iou: float
    spacing_min_mm: float
    spacing_mean_mm: float
    size_mm: float


class ShapeVerdict(TypedDict, total=False):
    """One outline judged against the shape tolerance."""

    status: str  # "met" or "missed"
    tol_mm: float
    tol_rel: float
    hausdorff_mm: float
    hausdorff_rel: float


class AttemptRecord(TypedDict):
    """One initial guess, continuation or refinement the front door tried (``report["attempts"]``)."""

    init: str  # the guess, or what was tried ("continuation", "minimax refinement", ...)
    status: str
    problems: list[str]
    time_s: float
    fit_max_rel_size: NotRequired[float]
    hausdorff_max_rel: NotRequired[float]
    shape: NotRequired[str]  # "met" or "missed"
    kept: NotRequired[bool]  # a refinement: whether it replaced the design
    tiles: NotRequired[
        list[int]
    ]  # rows, cols of an attempt on another lattice than asked (a bent strip)
    # the axis of a mirrored design tried for a request without a symmetry
    mirrored: NotRequired[str]
    # the lattice's angle of a design tried along the outline's mirror axis (api/design_turn.py)
    lattice_angle_deg: NotRequired[float]


class DesignReport(TypedDict):
    """The report of a quad design: the solver's figures, the front door's checks and verdicts."""

    status: str  # "converged" or "unconverged"
    max_equality_residual: float
    time_s: float
    problems: list[str]  # why the design is not valid (empty when it is)
    checks: dict[str, Any]  # closure and overlaps per state, the bed for a printer, hinge sums
    conformance: dict[str, Conformance]  # by outline: "deployed", "state_1", "state_2"
    shape: dict[str, ShapeVerdict]  # the same outlines judged against the shape tolerance
    attempts: list[AttemptRecord]
    time_s_total: float
    fabricability: dict[str, Any]  # every material and printer preset (``fabricate.fabricability``)
    opening: NotRequired[dict[str, Any]]  # how far the design opens (``pattern.opening``)
    solver: NotRequired[str]
    shape_matching: NotRequired[str]
    tolerance: NotRequired[float]
    iterations_total: NotRequired[int]
    fit: NotRequired[dict[str, Any]]
    residuals: NotRequired[dict[str, Any]]
    residual_units: NotRequired[str]
    fabrication: NotRequired[dict[str, Any]]  # the fabrication rows of a material or printer
    continuation: NotRequired[dict[str, Any]]
    minimax: NotRequired[dict[str, Any]]
    closed_outline_fit: NotRequired[dict[str, Any]]
    preview: NotRequired[str]  # the preview PNG's name, beside the pattern
    # a request without a symmetry answered by the design mirrored about this axis
    mirrored: NotRequired[str]
    mirrored_why: NotRequired[str]
    # the lattice's angle in degrees, counter-clockwise from the drawing's axes (api/design_turn.py)
    lattice_angle_deg: NotRequired[float]
    # the lattice of a strip bent along the outline, in place of the N x N asked (api/design_strip.py)
    strip: NotRequired[dict[str, Any]]


class KagomeReport(TypedDict):
    """The report of a kagome design."""

    status: str
    max_equality_residual: float
    tol: float
    conformance: Conformance  # of the deployed outline
    shape: ShapeVerdict
    verify_failed: list[str]  # the names of the ``verify`` checks it fails
    fabricability: NotRequired[dict[str, Any]]
    fabrication: NotRequired[dict[str, Any]]
    opening: NotRequired[dict[str, Any]]
    opening_problems: NotRequired[list[str]]
    trimmed_tiles: NotRequired[int | None]  # None: the whole R x C block
    aspect: NotRequired[
        dict[str, Any]
    ]  # the lattice's aspect against the outline's, when chosen from it
    tile_size_mm: NotRequired[float]
    iterations: NotRequired[int]
    symmetry: NotRequired[list[str]]
    pair_rows: NotRequired[bool]
    convex_holes: NotRequired[bool]
    candidates_rejected: NotRequired[int]
    min_gap_deg: NotRequired[float]
    min_tile_quality: NotRequired[float]
    max_tip_distance_mm: NotRequired[float]
    hausdorff_trace: NotRequired[list[Any]]


def report_problem(report: Any) -> str | None:
    """Where ``report`` (a quad or kagome design report, as written) breaks the schema, or None."""
    return schema_problem(report, load_schema("fabkiri.api", SCHEMA))
