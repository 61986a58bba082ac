"""A pattern's fingerprint: what the files made from it (cut, print, deploy, tolerance) record of it,
so that a report can tell a folder made from this pattern from one made from another."""

from __future__ import annotations

import hashlib
import json
from typing import Any, Final

import numpy as np

from .model import Pattern

KEY: Final = "pattern_fingerprint"  # the manifest key that holds it (a literal: a TypedDict key)
DIGITS = 6  # nodes rounded to 1 nm: a re-saved pattern keeps its fingerprint


def pattern_sha256(pattern: Pattern) -> str:
    """SHA-256 of the tessellation, the tiles and the deployed nodes (mm, rounded to ``DIGITS``)."""
    nodes = np.round(np.asarray(pattern.nodes, dtype=float), DIGITS) + 0.0  # no -0.0
    text = json.dumps(
        {
            "kind": pattern.kind,
            "tiles": np.asarray(pattern.tiles).tolist(),
            "nodes": nodes.tolist(),
        },
        separators=(",", ":"),
    )
    return hashlib.sha256(text.encode()).hexdigest()


def fingerprint(pattern: Pattern) -> dict[str, Any]:
    """What a manifest records of its pattern under ``KEY``: the hash, the tessellation, the counts."""
    return {
        "sha256": pattern_sha256(pattern),
        "kind": pattern.kind,
        "tiles": int(len(pattern.tiles)),
        "nodes": int(len(pattern.nodes)),
    }
