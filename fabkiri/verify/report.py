"""Check results and the verification report.

Every check names what it measured, the tolerance (mm, mm², rad, or a count)
and the worst tile, hinge or hole, so a failure can be acted on without
re-running anything. A :class:`Report` is plain data: it serialises to JSON
and prints as a table with failing checks first.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any, TypedDict

SCHEMA = "verify-report.schema.json"  # beside this module: what :meth:`Report.to_dict` writes


def _num(v: Any) -> Any:
    """JSON-safe float (NaN/inf become None: 'not measured')."""
    if v is None:
        return None
    if isinstance(v, bool):
        return v
    if isinstance(v, int):
        return v
    v = float(v)
    return v if math.isfinite(v) else None


class CheckRecord(TypedDict):
    """One check as written (:meth:`Check.to_dict`)."""

    name: str
    group: str
    ok: bool
    value: float | int | None  # None: not measured
    tol: float | int | None
    unit: str
    op: str  # "<=", ">=" or "=="
    worst: str | None
    detail: str
    applies: bool


class ReportRecord(TypedDict):
    """A verification report as written (:meth:`Report.to_dict`, ``fabkiri verify --json``)."""

    subject: str
    kind: str
    ok: bool
    failed: list[str]  # the names of the failing checks
    meta: dict[str, Any]
    checks: list[CheckRecord]


@dataclass
class Check:
    """One measured property.

    ``op`` says how ``value`` is compared with ``tol``: ``"<="`` (a residual or
    count that must stay small) or ``">="`` (a size that must stay large).
    ``applies`` is False for figures measured for information only (e.g. hinge
    sums of a pattern that does not claim rigid deployability); they never fail.
    ``id`` is a stable dotted identifier (e.g. ``state1.edge-pairs``) for code that
    selects checks: the display ``name`` may be reworded, the id may not. (It is
    not serialised: reports and manifests stay as they were written.)
    """

    name: str
    ok: bool
    value: float | int | None
    tol: float | int | None
    unit: str
    worst: str | None = None
    detail: str = ""
    group: str = ""
    op: str = "<="
    applies: bool = True
    id: str = ""

    def to_dict(self) -> CheckRecord:
        return {
            "name": self.name,
            "group": self.group,
            "ok": bool(self.ok),
            "value": _num(self.value),
            "tol": _num(self.tol),
            "unit": self.unit,
            "op": self.op,
            "worst": self.worst,
            "detail": self.detail,
            "applies": self.applies,
        }


def measured(  # noqa: PLR0913 (the fields of a Check, by keyword)
    name: str,
    value: float,
    tol: float,
    unit: str,
    *,
    worst: str | None = None,
    detail: str = "",
    group: str = "",
    op: str = "<=",
    applies: bool = True,
    id: str = "",
) -> Check:
    """A check whose verdict is the comparison of ``value`` with ``tol``.

    A NaN value (nothing could be measured) fails.
    """
    v = float(value)
    if not math.isfinite(v):
        ok = False
    elif op == "<=":
        ok = v <= tol
    else:
        ok = v >= tol
    return Check(
        name=name,
        ok=bool(ok) or not applies,
        value=v,
        tol=tol,
        unit=unit,
        worst=worst,
        detail=detail,
        group=group,
        op=op,
        applies=applies,
        id=id,
    )


@dataclass
class Report:
    """The outcome of a verification: an ordered list of checks plus context."""

    subject: str
    kind: str  # "pattern" or "layout"
    checks: list[Check] = field(default_factory=list)
    meta: dict[str, Any] = field(default_factory=dict)

    def add(self, check: Check) -> Check:
        self.checks.append(check)
        return check

    def extend(self, other: Report) -> None:
        self.checks.extend(other.checks)

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    def failed(self) -> list[Check]:
        return [c for c in self.checks if not c.ok]

    def get(self, name: str) -> Check:
        """The check called ``name`` (KeyError if absent)."""
        for c in self.checks:
            if c.name == name:
                return c
        raise KeyError(name)

    def by_id(self, id: str) -> Check:
        """The check whose stable :attr:`Check.id` is ``id`` (KeyError if absent)."""
        for c in self.checks:
            if c.id == id:
                return c
        raise KeyError(id)

    def names(self) -> list[str]:
        return [c.name for c in self.checks]

    def to_dict(self) -> ReportRecord:
        return {
            "subject": self.subject,
            "kind": self.kind,
            "ok": self.ok,
            "failed": [c.name for c in self.failed()],
            "meta": json.loads(json.dumps(self.meta, default=_num)),
            "checks": [c.to_dict() for c in self.checks],
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)

    def to_text(self) -> str:
        """A readable table, failing checks first."""
        ordered = self.failed() + [c for c in self.checks if c.ok]
        rows = [("", "check", "measured", "tolerance", "worst")]
        for c in ordered:
            mark = "FAIL" if not c.ok else ("ok" if c.applies else "info")
            rel = c.op if c.applies else "(n/a)"
            rows.append(
                (mark, c.name, _fmt(c.value, c.unit), f"{rel} {_fmt(c.tol, c.unit)}", c.worst or "")
            )
        w = [max(len(r[i]) for r in rows) for i in range(4)]
        lines = [f"{self.kind} verification of {self.subject}"]
        for meta_key in ("tol_mm", "tol_rad", "tile_size_mm"):
            if meta_key in self.meta:
                lines[0] += f"  {meta_key}={_fmt(self.meta[meta_key], '')}"
        if self.meta.get("tolerance"):
            lines[0] += f"  [{self.meta['tolerance']}]"
        for i, r in enumerate(rows):
            lines.append(
                f"{r[0]:<{w[0]}}  {r[1]:<{w[1]}}  {r[2]:>{w[2]}}  {r[3]:<{w[3]}}  {r[4]}".rstrip()
            )
            if (
                i
                and ordered[i - 1].detail
                and (not ordered[i - 1].ok or not ordered[i - 1].applies)
            ):
                lines.append(f"{'':<{w[0]}}    {ordered[i - 1].detail}")
        n_bad = len(self.failed())
        lines.append(
            f"verdict: {'PASS' if self.ok else 'FAIL'} ({len(self.checks) - n_bad}/{len(self.checks)} "
            f"checks pass{'' if self.ok else ', ' + str(n_bad) + ' fail'})"
        )
        return "\n".join(lines)


def _fmt(v: Any, unit: str) -> str:
    if v is None:
        return "—"
    if isinstance(v, (bool, int)) or (
        isinstance(v, float) and v.is_integer() and abs(v) < 1e6 and unit in ("", "count")
    ):
        s = f"{int(v)}"
    else:
        v = float(v)
        s = "nan" if not math.isfinite(v) else f"{v:.3g}"
    return f"{s} {unit}".strip() if unit and unit != "count" else s
