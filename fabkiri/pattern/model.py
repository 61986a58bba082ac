"""The one pattern model: topology + embeddings + metadata.

A :class:`Pattern` holds the deployed node coordinates (mm), the CCW tiles
of its tessellation kind (quads by default), and optionally the two closed (contracted) states stored per tile,
because closed states put several nodes at one point. The topology is derived
from the tiles on first use and cached; it is never stored.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache
from typing import Any

import numpy as np

from ..errors import PatternError
from . import geometry
from .kinds.tessellation import DEFAULT_KIND, tessellation
from .picture import pattern_png
from .topology import Topology, derive_topology


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@lru_cache(maxsize=8)
def _topology(tiles: bytes, shape: tuple, n_nodes: int, parity: int, kind: str) -> Topology:
    """``derive_topology`` memoised on the tiles' contents: a pattern and its copies (new states, a designed
    pattern on the standard lattice's tiles) share one topology instead of deriving it again. A bad
    pattern raises, and nothing is cached."""
    return derive_topology(
        np.frombuffer(tiles, dtype=np.int64).reshape(shape), n_nodes, parity, kind
    )


@dataclass(frozen=True, eq=False)
class Pattern:
    """A kirigami pattern: quads (rotating squares) unless ``kind`` names another tessellation.

    Parameters
    ----------
    nodes:
        ``(n, 2)`` deployed node coordinates in millimetres.
    tiles:
        ``(T, n)`` node indices of each tile, counter-clockwise (``n`` is the kind's arity, 4 for quads).
    contracted:
        Optional closed states, ``{1: (T, n, 2), 2: (T, n, 2)}`` per-tile corner
        coordinates in millimetres, tile corners in the same order as ``tiles``.
    parity:
        Which tile colour is "even" for the fold rules (0: tile 0). It decides
        which closed state is called state 1.
    name, lattice, design:
        Free-form metadata: a name, the lattice it came from (kind, rows, cols,
        angle, tile size) and how it was designed (target, options, solver report).
    kind:
        The tessellation (:mod:`fabkiri.pattern.kinds.tessellation`): tile and hole arity, closed
        states, fold rules.
    """

    nodes: np.ndarray
    tiles: np.ndarray
    contracted: dict[int, np.ndarray] = field(default_factory=dict)
    parity: int = 0
    name: str = ""
    lattice: dict[str, Any] | None = None
    design: dict[str, Any] | None = None
    kind: str = DEFAULT_KIND

    def __post_init__(self) -> None:
        tess = tessellation(self.kind)
        n = tess.arity
        nodes = np.array(self.nodes, dtype=float)
        if nodes.ndim != 2 or nodes.shape[1] != 2:
            raise PatternError(f"nodes must be a list of [x, y] pairs, got shape {nodes.shape}")
        if not np.isfinite(nodes).all():
            bad = int(np.flatnonzero(~np.isfinite(nodes).all(1))[0])
            raise PatternError(f"node {bad} has a non-finite coordinate {nodes[bad].tolist()}")
        try:
            tiles = np.array(self.tiles, dtype=np.int64)
        except (ValueError, TypeError) as exc:
            raise PatternError(f"tiles must be lists of {n} node indices ({exc})") from None
        if tiles.ndim != 2 or tiles.shape[1] != n:
            raise PatternError(
                f"every tile must be a {tess.tile_noun} of {n} node indices, got shape {tiles.shape}"
            )
        contracted = {}
        for key, val in dict(self.contracted).items():
            state = int(key)
            if state not in tess.states:
                names = " or ".join(str(s) for s in tess.states)
                raise PatternError(f"contracted state must be {names}, not {key!r}")
            arr = np.array(val, dtype=float)
            if arr.shape != (len(tiles), n, 2):
                raise PatternError(
                    f"contracted state {state} must hold {n} corners per tile "
                    f"({len(tiles)} tiles), got shape {arr.shape}"
                )
            if not np.isfinite(arr).all():
                raise PatternError(f"contracted state {state} has a non-finite coordinate")
            contracted[state] = _readonly(arr)
        object.__setattr__(self, "nodes", _readonly(nodes))
        object.__setattr__(self, "tiles", _readonly(tiles))
        object.__setattr__(self, "contracted", contracted)
        object.__setattr__(self, "parity", int(self.parity))
        # topology is validated eagerly so a bad pattern fails where it is made
        _ = self.topology

    @cached_property
    def topology(self) -> Topology:
        return _topology(
            self.tiles.tobytes(), self.tiles.shape, len(self.nodes), self.parity, self.kind
        )

    @property
    def n_tiles(self) -> int:
        return len(self.tiles)

    def corners(self, state: str | int = "deployed") -> np.ndarray:
        """Per-tile corners ``(T, n, 2)`` of the deployed state or a closed state."""
        if state in ("deployed", 0, "0"):
            return self.nodes[self.tiles]
        s = int(state)
        if s not in self.contracted:
            raise PatternError(f"the pattern has no contracted state {s}")
        return self.contracted[s]

    def node_positions(self, state: str | int = "deployed") -> np.ndarray:
        """Per-node coordinates; in a closed state each node takes the position
        of its first incident tile (coincident nodes come out duplicated)."""
        if state in ("deployed", 0, "0"):
            return self.nodes
        corners = self.corners(state)
        out = np.empty_like(self.nodes)
        flat_nodes = self.tiles.ravel()[::-1]
        out[flat_nodes] = corners.reshape(-1, 2)[::-1]  # reversed: first tile wins
        return out

    @cached_property
    def tile_size(self) -> float:
        """Mean tile edge in mm: the scale of every relative tolerance."""
        return geometry.mean_edge_length(self.corners())

    def with_contracted(self, contracted: dict[int, np.ndarray]) -> Pattern:
        return replace(self, contracted=contracted)

    def with_parity(self, parity: int) -> Pattern:
        return replace(self, parity=parity)

    def _repr_png_(self) -> bytes:
        """The picture a notebook shows: the deployed state and each stored closed state."""
        return pattern_png(self)

    def __repr__(self) -> str:
        t = self.topology
        return (
            f"Pattern({self.name!r}, tiles={t.n_tiles}, hinges={t.n_hinges}, holes={t.n_holes}, "
            f"contracted={sorted(self.contracted)})"
        )
