"""Atomic file output: nothing half-written ever appears under a final name.

Every writer in fabkiri produces bytes in memory (or in a scratch folder) and
hands them here; files appear under their final names only by ``os.replace``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from .errors import InputError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _publish_mode(fd_or_path) -> None:
    """mkstemp makes 0600 files; outputs get the usual rw-r--r-- (per umask)."""
    os.chmod(fd_or_path, 0o666 & ~_umask())


def _parent(path: Path) -> Path:
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(f"output folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise InputError(f"output folder {parent} is not writable")
    return parent


def atomic_write(path: str | os.PathLike, data: bytes | str) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"output {path} is a folder, expected a file name")
    parent = _parent(path)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=parent)
    except OSError as exc:
        raise InputError(f"cannot write {path}: {exc.strerror or exc}") from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
        _publish_mode(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise InputError(f"cannot write {path}: {exc.strerror or exc}") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_many(folder: str | os.PathLike, files: dict[str, bytes | str]) -> list[Path]:
    """Write several files into ``folder`` (created if missing) all-or-nothing.

    Everything is first written to a scratch folder beside ``folder``; only when
    every file is complete are they moved into place.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"output {folder} exists and is not a folder")
    parent = _parent(folder)
    created = not folder.exists()
    try:
        scratch = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=parent))  # mode 0700, never published
    except OSError as exc:
        raise InputError(f"cannot write into {parent}: {exc.strerror or exc}") from None
    try:
        for name, data in files.items():
            target = scratch / name
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
        if created:
            folder.mkdir()
        out = []
        for name in files:
            dest = folder / name
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.replace(scratch / name, dest)
            out.append(dest)
        return out
    except OSError as exc:
        raise InputError(f"cannot write {folder}: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
