"""STL, the plain triangle mesh of a print: written and read back with trimesh.

A print job writes its STLs from trimesh meshes (:func:`.mesh.job_files`); :func:`stl_bytes`
writes named meshes the same way (one binary STL holding them all) and :func:`read_stl` reads one
back with its vertices welded, as slicers do and as the job's read-back checks them
(:func:`.checks.read_back_files`). Registered as the solid format ``stl``
(:mod:`fabkiri.exchange.file_formats`).
"""

from __future__ import annotations

import io
from typing import cast

import numpy as np

from ...exchange.file_formats import Mesh, SolidFormat, register_format


def stl_bytes(meshes: dict[str, tuple[np.ndarray, np.ndarray]]) -> bytes:
    """One binary STL of every mesh ``{name: (vertices, triangles)}`` (STL has no names)."""
    import trimesh

    parts = [trimesh.Trimesh(v, f, process=False) for v, f in meshes.values()]
    both = cast(trimesh.Trimesh, trimesh.util.concatenate(parts))
    return cast(bytes, both.export(file_type="stl"))


def read_stl(data: bytes) -> list[Mesh]:
    """The one mesh of an STL, vertices welded: ``[("", vertices, triangles)]``."""
    import trimesh

    tm = cast(trimesh.Trimesh, trimesh.load(io.BytesIO(data), file_type="stl", process=True))
    return [("", np.asarray(tm.vertices), np.asarray(tm.faces))]


register_format(SolidFormat("stl", (".stl",), write=stl_bytes, read=read_stl))
