"""``deploy_pattern``: a pattern's deployment path and everything written about it.

The path itself is :func:`fabkiri.mechanics.deploy.deployment_path`; this front door adds what a user
of the path gets from ``fabkiri deploy``: the energy table, the summary, the plot and animation, one
pattern file per frame, and the checks that make the command exit 1 (a collision, a missed closed
state, a rigid path with energy). Notebooks and sweeps call it and get the same verdict.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

from ..exchange.pattern_json import dumps
from ..mechanics.collisions import Overlap
from ..mechanics.deploy import DeploymentPath, deployment_path
from ..mechanics.path import DeployReport
from ..mechanics.tube import tube_along_path
from ..pattern.fingerprint import KEY, fingerprint
from ..pattern.model import Pattern

SCHEMA = "deploy.schema.json"  # beside this module: what deploy.json holds (DeployReport)

ZERO_ENERGY = 1e-12  # the rigid path's energy must be zero to rounding


@dataclass(frozen=True, eq=False)
class DeployOutcome:
    """The path, its summary, the files to write and what failed (like scipy's ``OptimizeResult``).

    ``files`` maps names relative to the output folder to their contents; ``problems`` is empty
    exactly when the path reaches both closed states without a collision (and, rigid, at zero energy).
    """

    path: DeploymentPath
    summary: DeployReport  # written as deploy.json (deploy.schema.json beside this module)
    files: dict[str, bytes | str]
    problems: list[str] = field(default_factory=list)

    @property
    def success(self) -> bool:
        return not self.problems

    def __repr__(self) -> str:  # the path holds arrays per frame: summed up, not printed
        return (
            f"DeployOutcome({self.path.kind} path, {self.path.n_frames} frames, "
            f"{len(self.files)} files, problems {self.problems})"
        )

    @property
    def n_frame_files(self) -> int:
        return sum(1 for k in self.files if k.startswith("frames/"))


def deploy_pattern(
    pattern: Pattern,
    steps: int = 40,
    *,
    path: str = "auto",
    driver: str = "auto",
    plot: bool = False,
    gif: bool = False,
    color: str = "auto",
    gif_frames: int = 61,
    frames: bool = True,
) -> DeployOutcome:
    """Compute the deployment path of ``pattern`` and everything ``fabkiri deploy`` writes about it."""
    p = deployment_path(pattern, steps, path=path, driver=driver)
    summary = p.summary()
    summary["overlap_max_depth_mm"] = max(
        (overlap_depth(p, o) for o in p.collisions.overlaps), default=0.0
    )
    summary[KEY] = fingerprint(pattern)
    tube = tube_along_path(pattern, p.corners, p.t)
    if tube is not None:  # a periodic pattern: its tube in every frame
        summary["tube"] = tube
    files: dict[str, bytes | str] = {
        "energy.csv": energy_csv(p),
        "deploy.json": json.dumps(summary, indent=2, sort_keys=True) + "\n",
    }
    if tube is not None:
        files["tube.csv"] = tube_csv(tube)
    if plot:
        from ..render.deployment import energy_plot_png

        files["energy.png"] = energy_plot_png(p, title=pattern.name)
    if gif:
        from ..render.deployment import deployment_gif

        files["deploy.gif"] = deployment_gif(p, color=color, max_frames=gif_frames)
    if frames:
        files.update(frame_patterns(pattern, p))
    return DeployOutcome(path=p, summary=summary, files=files, problems=check_problems(p))


def energy_csv(path: DeploymentPath) -> str:
    """One row per frame: t, E, the largest tile energy and the other per-frame figures."""
    rows = ["t,energy,max_tile_energy,rotation_rad,rotation_spread_rad,hinge_gap_mm,overlaps"]
    per_frame = [0] * path.n_frames
    for o in path.collisions.overlaps:
        per_frame[o.frame] += 1
    rot, spread = path.rotation_magnitude, path.rotation_spread
    for f in range(path.n_frames):
        rows.append(
            f"{path.t[f]:.10f},{path.energy[f]:.6e},{path.max_tile_energy[f]:.6e},{rot[f]:.12f},"
            f"{spread[f]:.3e},{path.hinge_gap[f]:.3e},{per_frame[f]}"
        )
    return "\n".join(rows) + "\n"


def tube_csv(tube: dict) -> str:
    """One row per frame of a tube's path: t, radius at the narrow and wide end, length, seam figures."""
    rows = ["t,radius_min_mm,radius_max_mm,length_mm,seam_rotation_rad,seam_translation_dev_rel"]
    cols = (
        "radius_min_mm",
        "radius_max_mm",
        "length_mm",
        "seam_rotation_rad",
        "seam_translation_dev_rel",
    )
    for f, t in enumerate(tube["t"]):
        rows.append(f"{t:.10f}," + ",".join(f"{tube[c][f]:.9g}" for c in cols))
    return "\n".join(rows) + "\n"


def frame_patterns(pattern: Pattern, path: DeploymentPath) -> dict[str, str]:
    """``frames/frame-NNNN.json``: each frame as a pattern whose deployed state is that frame."""
    out = {}
    width = max(4, len(str(path.n_frames - 1)))
    base = pattern.name or "pattern"
    for f in range(path.n_frames):
        frame = Pattern(
            nodes=path.nodes[f],
            tiles=pattern.tiles,
            parity=pattern.parity,
            name=f"{base} deployment frame {f} (t = {path.t[f]:.4f})",
            lattice=pattern.lattice,
            design={
                "deployment": {
                    "source": base,
                    "path": path.kind,
                    "driver": path.driver,
                    "frame": f,
                    "t": float(path.t[f]),
                    "energy": float(path.energy[f]),
                }
            },
            kind=pattern.kind,
        )
        out[f"frames/frame-{f:0{width}d}.json"] = dumps(frame)
    return out


def check_problems(path: DeploymentPath, tol: float = 1e-9) -> list[str]:
    """What makes ``deploy`` exit 1, one sentence each."""
    out = []
    size = path.tile_size
    for name, d in path.state_mismatch.items():
        if d > tol * size * max(1.0, path.corners.shape[1] ** 0.5):
            out.append(f"the path misses the {name} by {d:.3g} mm")
    if path.kind == "rigid" and path.energy.max() > ZERO_ENERGY:
        out.append(f"the rigid path has energy {path.energy.max():.3g} > {ZERO_ENERGY:g}")
    unconverged = path.solver.get("unconverged_steps", 0)
    if unconverged:
        out.append(f"{unconverged} of the path's {path.solver['solves']} solves did not converge")
    if path.collisions.self_intersecting:
        bowties = path.collisions.self_intersecting
        out.append(
            f"{len(bowties)} tiles cross themselves (bow-ties) along the path: {bowties[:8]}"
            f"{' ...' if len(bowties) > 8 else ''}"
        )
    mirrored = path.solver.get("mirrored_tiles_max", 0)
    if mirrored:
        out.append(f"{mirrored} tiles turn over (into their mirror image) along the path")
    c = path.collisions
    if not c.collision_free():
        o = max(c.overlaps, key=lambda o: o.area)
        out.append(
            f"{len(c.overlaps)} tile overlaps in {len(c.frames)} frames, the largest {o.area:.3g} mm² "
            f"({overlap_depth(path, o):.3g} mm deep) between tiles {o.tile_a} and {o.tile_b} "
            f"at t = {path.t[o.frame]:.3f}{_deployed_overlaps(path)}{_tried(path)}"
        )
    return out


def _tried(path: DeploymentPath) -> str:
    """A note when more than one driver was tried and none found a clean path."""
    tried = path.solver.get("drivers_tried")
    if not tried or len(tried) < 2:
        return ""
    each = ", ".join(
        f"{name} {f['overlaps']} overlaps, {f['self_intersecting_tiles']} bow-tie tiles, "
        f"E up to {f['energy_max']:.3g}"
        for name, f in tried.items()
    )
    return (
        f"; no driver found a collision-free path ({each}): the tiles must strain this far to "
        f"pass between the states, and a real sheet may not deploy without contact"
    )


def _deployed_overlaps(path: DeploymentPath) -> str:
    """A note when the deployed state itself overlaps: no path through it can be collision-free."""
    f = path.mark_frames()["deployed"]
    at = [o for o in path.collisions.overlaps if o.frame == f]
    if not at:
        return ""
    worst = max(o.area for o in at)
    return (
        f"; {len(at)} of them in the deployed state itself (largest {worst:.3g} mm²): the "
        f"design overlaps before it moves"
    )


def overlap_depth(path: DeploymentPath, o: Overlap) -> float:
    """How far (mm) the two tiles of an overlap reach into each other: the separating-axis depth."""
    from ..verify.geom import sat_penetration

    frame = path.corners[o.frame]
    return float(sat_penetration(frame[[o.tile_a]], frame[[o.tile_b]])[0])
