"""A periodic pattern's tube in every state: radius, length, and the sheet rolled into 3D.

Rolling is an isometry of the plane onto a cylinder (or cone), so a state whose seam map is a pure
translation ``t`` rolls onto a cylinder of circumference ``|t|``: its radius is ``|t| / 2π``, its axis
runs along ``t`` turned by 90°, and its length is the extent of the tube's tiles along that axis. A
deployed state whose seam map is a rotation by ``α`` about an apex rolls onto a cone: a point at
distance ``ρ`` from the apex lands at radius ``ρ |α| / 2π`` and height ``ρ sqrt(1 - (α / 2π)²)``.

How a state changes into another is reported as ratios, as in the paper's Fig. 5: the **axial change**
(length ratio) and the **radial change** (radius ratio, at the tube's two ends; the two differ when the
change is not uniform along the axis).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..pattern.kinds.periodic.sheet import Seam, seam_map, seam_of, tube_tiles
from ..pattern.model import Pattern
from .contract import contract

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class TubeFrame:
    """Where a planar state rolls to: a cylinder (``apex`` None) or a cone about ``apex``.

    Cylinder: ``origin`` is on the seam, ``u`` the unit period direction, ``v`` the axis; ``period`` the
    circumference. Cone: ``apex``, ``u`` the direction of the first seam edge, ``alpha`` the sector angle.
    """

    origin: np.ndarray
    u: np.ndarray
    v: np.ndarray
    period: float
    apex: np.ndarray | None = None
    alpha: float = 0.0

    def roll(self, pts: np.ndarray) -> np.ndarray:
        """Planar points ``(..., 2)`` mm -> their place on the tube ``(..., 3)`` mm (isometric)."""
        if self.apex is None:
            d = pts - self.origin
            s, z = d @ self.u, d @ self.v
            R = self.period / TWO_PI
            return np.stack([R * np.cos(s / R), R * np.sin(s / R), z], -1)
        d = pts - self.apex
        rho = np.linalg.norm(d, axis=-1)
        phi = np.arctan2(d @ self.v, d @ self.u)  # angle from the seam, in [0, alpha) on the sheet
        k = abs(self.alpha) / TWO_PI
        az = phi / k
        return np.stack(
            [rho * k * np.cos(az), rho * k * np.sin(az), rho * np.sqrt(1.0 - k * k)], -1
        )


@dataclass
class TubeState:
    """One state's tube: radii at the two ends, length along the axis, and how periodic its seam is."""

    state: str
    shape: str  # "cylinder" or "cone"
    radius_min_mm: float
    radius_max_mm: float
    length_mm: float
    seam_rotation_rad: float
    seam_translation_dev_rel: float  # largest corner distance from a pure translation, tile sizes
    seam_kind: str = "cylinder"  # what the seam record asks of this state's seam map
    seam_dev_rel: float = (
        0.0  # distance from that kind: a translation (cylinder), a rigid motion (cone)
    )

    def to_dict(self) -> dict:
        return asdict(self)


def frame(corners: np.ndarray, seam: Seam, state) -> TubeFrame:
    """The tube frame of one state's per-tile corners (a cone where the seam record allows one)."""
    m = seam_map(corners, seam)
    first = corners[seam.first]
    if seam.state_kind(state) == "cone" and abs(m.rotation) > 1e-12:
        # the seam map x -> R x + t fixes the apex c = (I - R)^-1 t
        c, s = np.cos(m.rotation), np.sin(m.rotation)
        apex = np.linalg.solve(np.eye(2) - np.array([[c, -s], [s, c]]), m.translation)
        d = first.reshape(-1, 2).mean(0) - apex
        u = d / np.linalg.norm(d)
        v = np.array([-u[1], u[0]]) * np.sign(
            m.rotation
        )  # angles grow from the first column to its copy
        return TubeFrame(origin=apex, u=u, v=v, period=0.0, apex=apex, alpha=m.rotation)
    t = m.translation
    u = t / np.linalg.norm(t)
    v = np.array([-u[1], u[0]])
    origin = first[:, 0].mean(0)
    return TubeFrame(origin=origin, u=u, v=v, period=m.period)


def tube_state(pattern: Pattern, seam: Seam, corners: np.ndarray, state) -> TubeState:
    """Radius, length and seam figures of one state."""
    m = seam_map(corners, seam)
    f = frame(corners, seam, state)
    pts = corners[tube_tiles(pattern, seam)].reshape(-1, 2)
    if f.apex is None:
        z = (pts - f.origin) @ f.v
        r = f.period / TWO_PI
        rmin = rmax = r
        shape = "cylinder"
    else:
        xyz = f.roll(pts)
        z = xyz[:, 2]
        rad = np.hypot(xyz[:, 0], xyz[:, 1])
        rmin, rmax = float(rad.min()), float(rad.max())
        shape = "cone"
    return TubeState(
        state=str(state),
        shape=shape,
        radius_min_mm=float(rmin),
        radius_max_mm=float(rmax),
        length_mm=float(z.max() - z.min()),
        seam_rotation_rad=m.rotation,
        seam_translation_dev_rel=m.translation_dev / pattern.tile_size,
        seam_kind=seam.state_kind(state),
        seam_dev_rel=(m.rigid_dev if seam.state_kind(state) == "cone" else m.translation_dev)
        / pattern.tile_size,
    )


def tube_report(pattern: Pattern, closed: dict | None = None) -> dict | None:
    """The tube in every state and its changes (None for a planar pattern).

    ``closed`` maps state -> corners; missing states are contracted here. Changes are ratios closed ->
    deployed: ``axial`` = deployed length / closed length, ``radial_min``/``radial_max`` = deployed
    radius / closed radius at the narrow and the wide end.
    """
    seam = seam_of(pattern)
    if seam is None:
        return None
    closed = dict(closed or {})
    states = {"deployed": pattern.corners()}
    for s in (1, 2):
        states[str(s)] = (
            closed[s] if s in closed else pattern.contracted.get(s, contract(pattern, s).corners)
        )
    out = {
        k: tube_state(pattern, seam, Y, "deployed" if k == "deployed" else int(k))
        for k, Y in states.items()
    }
    dep = out["deployed"]
    changes = {}
    for k in ("1", "2"):
        c = out[k]
        changes[k] = {
            "axial": dep.length_mm / c.length_mm,
            "radial_min": dep.radius_min_mm / c.radius_min_mm,
            "radial_max": dep.radius_max_mm / c.radius_max_mm,
        }
    return {
        "columns": seam.columns,
        "rows": len(seam.pairs),
        "deployed_seam": seam.deployed,
        "closed_seam": seam.closed,
        "states": {k: v.to_dict() for k, v in out.items()},
        "changes_from_closed": changes,
    }


def tube_lines(rep: dict) -> list[str]:
    """The tube report as text lines for ``info`` and ``design``."""
    lines = [
        f"tube         {rep['rows']} rows x {rep['columns']} columns around, deployed seam "
        f"{rep['deployed_seam']} (sheet stores one seam copy column)"
    ]
    for k, s in rep["states"].items():
        name = "deployed" if k == "deployed" else f"state {k}"
        radius = (
            f"radius {s['radius_min_mm']:.4g} mm"
            if s["shape"] == "cylinder"
            else f"radius {s['radius_min_mm']:.4g}..{s['radius_max_mm']:.4g} mm"
        )
        lines.append(
            f"  {name:<9} {s['shape']:<8} {radius}, length {s['length_mm']:.4g} mm; seam rotation "
            f"{s['seam_rotation_rad']:.2e} rad, off a "
            f"{'rigid motion' if s['seam_kind'] == 'cone' else 'translation'} by {s['seam_dev_rel']:.2e} "
            f"tile sizes"
        )
    for k, c in rep["changes_from_closed"].items():
        lines.append(
            f"  state {k} -> deployed: axial x{c['axial']:.4g}, radial x{c['radial_min']:.4g}"
            + ("" if abs(c["radial_max"] - c["radial_min"]) < 1e-9 else f"..x{c['radial_max']:.4g}")
        )
    return lines


def tube_along_path(pattern: Pattern, corners: np.ndarray, t: np.ndarray) -> dict | None:
    """Each frame's tube along a deployment path, and how its radius changes in time (None if planar).

    ``corners`` are the path's per-frame tile corners ``(F, T, k, 2)``, ``t`` its parameter (0 closed
    state 1, ½ deployed, 1 closed state 2). Every frame is rolled as the deployed state is (a cylinder
    unless the seam record makes the deployed state a cone). Fig. 5B's "nonuniform radial change
    throughout the deployment and contraction process" is measured per half of the path: whether the
    radius is monotonic there and by how much it passes beyond the range of that half's two ends.
    """
    seam = seam_of(pattern)
    if seam is None:
        return None
    frames = [tube_state(pattern, seam, Y, "deployed") for Y in corners]
    r_lo = np.array([f.radius_min_mm for f in frames])
    r_hi = np.array([f.radius_max_mm for f in frames])
    length = np.array([f.length_mm for f in frames])
    half = int(np.argmin(np.abs(np.asarray(t) - 0.5)))
    halves = {
        "closed state 1 -> deployed": slice(0, half + 1),
        "deployed -> closed state 2": slice(half, None),
    }
    return {
        "t": [float(x) for x in t],
        "radius_min_mm": r_lo.tolist(),
        "radius_max_mm": r_hi.tolist(),
        "length_mm": length.tolist(),
        "seam_rotation_rad": [f.seam_rotation_rad for f in frames],
        "seam_translation_dev_rel": [f.seam_translation_dev_rel for f in frames],
        "radius_change": {
            name: _change_in_time(r_hi[s], np.asarray(t)[s]) for name, s in halves.items()
        },
        "length_change": {
            name: _change_in_time(length[s], np.asarray(t)[s]) for name, s in halves.items()
        },
    }


def _change_in_time(v: np.ndarray, t: np.ndarray) -> dict:
    """Ends, extremes and monotonicity of one figure over one half of the path (mm)."""
    lo, hi = min(v[0], v[-1]), max(v[0], v[-1])
    step = np.diff(v)
    tol = 1e-9 * max(1.0, float(np.abs(v).max()))
    return {
        "start_mm": float(v[0]),
        "end_mm": float(v[-1]),
        "peak_mm": float(v.max()),
        "t_at_peak": float(t[int(np.argmax(v))]),
        "low_mm": float(v.min()),
        "t_at_low": float(t[int(np.argmin(v))]),
        "beyond_ends_mm": float(max(v.max() - hi, lo - v.min(), 0.0)),
        "monotonic": bool(np.all(step >= -tol) or np.all(step <= tol)),
    }


def path_lines(prof: dict) -> list[str]:
    """The tube along a path as text lines for ``deploy``."""
    r, n = prof["radius_max_mm"], len(prof["t"])
    mid = int(np.argmin(np.abs(np.asarray(prof["t"]) - 0.5)))
    off = max(prof["seam_translation_dev_rel"])
    lines = [
        f"tube along the path: radius {r[0]:.4g} -> {r[mid]:.4g} -> {r[n - 1]:.4g} mm, length "
        f"{prof['length_mm'][0]:.4g} -> {prof['length_mm'][mid]:.4g} -> {prof['length_mm'][n - 1]:.4g} mm; "
        f"seams off a translation by <= {off:.2e} tile sizes over {n} frames"
    ]
    for name, c in prof["radius_change"].items():
        how = (
            "monotonic"
            if c["monotonic"]
            else f"not monotonic: passes {c['beyond_ends_mm']:.3g} mm beyond its ends "
            f"(peak {c['peak_mm']:.4g} mm at t = {c['t_at_peak']:.3f}, low {c['low_mm']:.4g} mm at "
            f"t = {c['t_at_low']:.3f})"
        )
        lines.append(f"  radius, {name}: {how}")
    return lines
