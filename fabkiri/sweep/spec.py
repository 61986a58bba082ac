"""The sweep file: axes whose product is the jobs, each job named by a hash of its inputs.

```toml
[sweep]
actions = ["design"]            # or ["design", "cut", "print", "deploy"]
[axes]                          # every combination is one job
target = ["circle", "heart", "my-outline.csv"]
tiles = ["4x4", "6x6"]
rigid = [true, false]
seed = [0, 1]
[fixed]                         # the same for every job
shape_tol = "5%"
```
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from .. import __version__, limits
from ..errors import InputError
from ..fabricate.cut.materials import HINGE_KINDS
from ..fabricate.fabricability import PRINT_STYLES
from ..pattern.tilecount import tile_count

if TYPE_CHECKING:
    from ..api.design import PatternRequest

ACTIONS = ("design", "cut", "print", "deploy")
# axis -> the Python types a value may have (PatternRequest's fields, the cut/print choices, the seed)
PARAMS: dict[str, tuple[type, ...]] = {
    "target": (str,),
    "tiles": (str, int),
    "size": (int, float),
    "rigid": (bool,),
    "symmetry": (str,),
    "holes": (str,),
    "contracted_target": (str, list),
    "init": (str,),
    "solver": (str,),
    "fit": (str,),
    "tol": (float,),
    "shape_tol": (str,),
    "material": (str,),
    "hinge": (str,),
    "printer": (str,),
    "style": (str,),
    "min_feature": (int, float),
    "min_hole": (int, float),
    "min_opening": (int, float),
    "seed": (int,),
    "cut_material": (str,),
    "print_printer": (str,),
    "deploy_steps": (int,),
}
CHOICES = {
    "symmetry": ("none", "x", "y"),
    "holes": ("rhombus", "parallelogram"),
    "fit": ("outline", "tips"),
    "solver": ("auto", "reduced", "full"),
    "init": ("standard", "rescaled", "conformal", "coarse"),
    "hinge": HINGE_KINDS,
    "style": PRINT_STYLES,
}  # the hinge kinds and print styles there are
MAX_JOBS = 100_000


@dataclass(frozen=True)
class Job:
    """One design (and what to make of it): ``params`` are plain TOML values, files as absolute paths."""

    id: str
    params: dict
    actions: tuple[str, ...]
    digest: str  # sha256 of the inputs: parameters, actions, target file contents, fabkiri version


@dataclass
class SweepSpec:
    jobs: list[Job]
    actions: tuple[str, ...] = ("design",)
    source: str = ""
    axes: dict = field(default_factory=dict)


def parse_tiles(value) -> tuple[int, int]:
    """A job's ``tiles``: ``"RxC"``, a pair, or one number for a square lattice."""
    if isinstance(value, int) and not isinstance(value, bool):
        value = (value, value)
    return tile_count(value)


def load_spec(path: str | Path) -> SweepSpec:
    """Read and check a sweep file; raises :class:`InputError` naming the first problem."""
    path = Path(path)
    limits.check_file_size(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not valid TOML ({exc})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read sweep file {path}: {exc}") from None
    spec = spec_from_dict(data, base=path.parent, source=str(path))
    check_sizes(spec.jobs, str(path))
    return spec


def spec_from_dict(data: dict, base: str | Path = ".", source: str = "") -> SweepSpec:
    """The jobs of a sweep given as a dict (the TOML's tables); relative target files are under ``base``."""
    where = source or "sweep"
    unknown = set(data) - {"sweep", "axes", "fixed"}
    if unknown:
        raise InputError(
            f"{where}: unknown table [{sorted(unknown)[0]}] (tables: sweep, axes, fixed)"
        )
    head = _table(data, "sweep", where)
    actions = _actions(head, where)
    axes = _table(data, "axes", where)
    settings = _settings(data, where)
    count = 1
    for values in settings.values():
        count *= len(values)
    if count > MAX_JOBS:
        raise InputError(f"{where}: {count} jobs is more than the {MAX_JOBS} a sweep may hold")
    base = Path(base)
    names = list(settings)
    jobs, seen = [], set()
    for combo in itertools.product(*(settings[n] for n in names)):
        params = {n: _resolve(n, v, base) for n, v in zip(names, combo)}
        job = make_job(params, actions)
        if job.id not in seen:  # the same inputs twice (e.g. a repeated value) are one job
            seen.add(job.id)
            jobs.append(job)
    _check_targets(jobs, where)
    return SweepSpec(
        jobs=jobs, actions=actions, source=source, axes={k: list(v) for k, v in axes.items()}
    )


def _actions(head: dict, where: str) -> tuple[str, ...]:
    """The ``[sweep]`` table's actions, in the order they run."""
    bad = set(head) - {"actions", "name"}
    if bad:
        raise InputError(
            f"{where}: unknown key {sorted(bad)[0]!r} in [sweep] (keys: actions, name)"
        )
    actions = head.get("actions", ["design"])
    actions = [actions] if isinstance(actions, str) else actions
    if (
        not isinstance(actions, list)
        or not all(a in ACTIONS for a in actions)
        or "design" not in actions
    ):
        raise InputError(
            f"{where}: [sweep] actions must list 'design' and any of cut, print, deploy; got {actions!r}"
        )
    return tuple(a for a in ACTIONS if a in actions)


def _settings(data: dict, where: str) -> dict[str, list]:
    """Each parameter's values: an axis's list, a fixed key's one value; checked, tiles and target given."""
    axes, fixed = _table(data, "axes", where), _table(data, "fixed", where)
    for name, values in axes.items():
        if not isinstance(values, list) or not values:
            raise InputError(f"{where}: axis {name!r} must be a non-empty list of values")
    both = set(axes) & set(fixed)
    if both:
        raise InputError(f"{where}: {sorted(both)[0]!r} is both an axis and fixed")
    settings = {**{k: list(v) for k, v in axes.items()}, **{k: [v] for k, v in fixed.items()}}
    for name, values in settings.items():
        kind = "axis" if name in axes else "fixed key"
        if name not in PARAMS:
            raise InputError(f"{where}: unknown {kind} {name!r}; known: {', '.join(PARAMS)}")
        for v in values:
            _check_value(name, v, where)
    if "tiles" not in settings:
        raise InputError(
            f"{where}: no tiles: give a 'tiles' axis (or fixed tiles) such as [\"6x6\"]"
        )
    if "target" not in settings and "contracted_target" not in settings:
        raise InputError(f"{where}: no target: give a 'target' axis (or fixed target)")
    return settings


def make_job(params: dict, actions: tuple[str, ...]) -> Job:
    files = {}
    for key in ("target", "contracted_target"):
        value = params.get(key)
        for v in value if isinstance(value, list) else [value]:
            p = Path(re.sub(r"^\s*[12]\s*:", "", v)) if isinstance(v, str) else None
            if p is not None and p.is_absolute() and p.is_file():
                files[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
    blob = json.dumps(
        {"params": params, "actions": actions, "files": files, "fabkiri": __version__},
        sort_keys=True,
    )
    digest = hashlib.sha256(blob.encode()).hexdigest()
    return Job(id=f"{_slug(params)}-{digest[:10]}", params=params, actions=actions, digest=digest)


def _table(data: dict, name: str, where: str) -> dict:
    t = data.get(name, {})
    if not isinstance(t, dict):
        raise InputError(f"{where}: [{name}] must be a table")
    return t


def _check_value(name: str, v, where: str) -> None:
    types = PARAMS[name]
    if not isinstance(v, types) or (isinstance(v, bool) and bool not in types):
        raise InputError(
            f"{where}: {name} value {v!r} is not a {' or '.join(t.__name__ for t in types)}"
        )
    if name in CHOICES and v not in CHOICES[name]:
        raise InputError(f"{where}: {name} value {v!r} is not one of {', '.join(CHOICES[name])}")
    if name == "tiles":
        r, c = parse_tiles(v)
        if r < 2 or c < 2:
            raise InputError(f"{where}: tiles {v!r}: inverse design needs at least 2x2 tiles")
    if isinstance(v, (int, float)) and not isinstance(v, bool) and name != "seed" and not v > 0:
        raise InputError(f"{where}: {name} value {v!r} must be positive")


def _resolve(name: str, v, base: Path):
    """Target files relative to the sweep file become absolute (named targets stay names)."""
    if name == "target" and isinstance(v, str) and (base / v).is_file():
        return str((base / v).resolve())
    if name == "contracted_target":
        items = v if isinstance(v, list) else [v]
        out = []
        for item in items:
            m = re.fullmatch(r"\s*([12])\s*:\s*(.+?)\s*", str(item))
            out.append(
                f"{m.group(1)}:{(base / m.group(2)).resolve()}"
                if m and (base / m.group(2)).is_file()
                else item
            )
        return out
    return v


def _slug(params: dict) -> str:
    t = params.get("target") or "outline"
    t = Path(t).stem if ("/" in t or "." in t) else t
    r, c = parse_tiles(params.get("tiles", 8))
    s = f"{re.sub(r'[^A-Za-z0-9_-]+', '_', t)[:24]}-{r}x{c}"
    return s + ("-rigid" if params.get("rigid") else "")


def _check_targets(jobs: list[Job], where: str) -> None:
    """Every named target or target file loads (cheap, before any worker starts)."""
    from ..design.targets.lookup import load_target

    for t in sorted({t for j in jobs if (t := j.params.get("target"))}):
        try:
            load_target(t, None)
        except InputError as exc:
            raise InputError(f"{where}: target {t!r}: ", exc) from None


def check_sizes(jobs: list[Job], where: str) -> None:
    """Every job within the design's size bound (:mod:`fabkiri.limits`), before any worker starts:
    a sweep file with one job too large to run is refused whole, naming the job. (A spec built with
    :func:`spec_from_dict` leaves it to each job, which records the refusal as its error.)"""
    from ..api.design import check_size

    for job in jobs:
        try:
            check_size(request_of(job.params))
        except InputError as exc:
            raise InputError(f"{where}: job {job.id}: ", exc) from None


REQUEST_KEYS = (
    "target",
    "size",
    "rigid",
    "symmetry",
    "holes",
    "contracted_target",
    "init",
    "solver",
    "fit",
    "tol",
    "shape_tol",
    "material",
    "hinge",
    "printer",
    "style",
    "min_feature",
    "min_hole",
    "min_opening",
    "seed",
)


def request_of(params: dict) -> PatternRequest:
    """The design request of a job's parameters (``tiles`` and the :data:`REQUEST_KEYS` it names)."""
    from ..api.design import PatternRequest  # the design front door: loaded when a request is made

    kw = {k: params[k] for k in REQUEST_KEYS if k in params}
    if kw.get("symmetry") == "none":
        kw["symmetry"] = None
    if isinstance(kw.get("contracted_target"), (list, str)):
        ct = kw["contracted_target"]
        kw["contracted_target"] = tuple([ct] if isinstance(ct, str) else ct)
    for k in ("size", "min_feature", "min_hole", "min_opening"):
        if k in kw:
            kw[k] = float(kw[k])
    return PatternRequest(tiles=parse_tiles(params["tiles"]), quiet=True, **kw)
