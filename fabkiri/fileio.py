"""Safe file input and output: nothing half-written, never an input overwritten.

Every writer in fabkiri produces bytes in memory and hands them here.
:func:`publish` checks every destination first (not a folder, not an input of
the running command, its folder creatable), writes all files into a scratch
folder beside the destination, and only then moves them in; if a move fails,
the files already moved are taken back and the old ones restored, so the
destination is left as it was. Readers register the files they read
(:func:`read_input`, :func:`note_inputs`) so a writer can refuse to replace
one of them, whatever path (symlink, ``./x``, hard link) names it.
"""

from __future__ import annotations

import contextvars
import json
import os
import shutil
import tempfile
from collections.abc import Iterable, Mapping
from contextlib import contextmanager
from pathlib import Path

from .errors import InputError

# the files read by the running command (set by :func:`inputs_scope`; None outside one: nothing recorded)
_INPUTS: contextvars.ContextVar[tuple[Path, ...] | None] = contextvars.ContextVar(
    "fabkiri_inputs", default=None
)
# the files the running command has put in place (a list per :func:`inputs_scope`; None outside one)
_WRITTEN: contextvars.ContextVar[list[Path] | None] = contextvars.ContextVar(
    "fabkiri_written", default=None
)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _publish_mode(fd_or_path) -> None:
    """mkstemp makes 0600 files; outputs get the usual rw-r--r-- (per umask)."""
    os.chmod(fd_or_path, 0o666 & ~_umask())


# ------------------------------------------------------------------ inputs


@contextmanager
def inputs_scope():
    """One command's record of the files it reads and writes (the CLI opens one per run)."""
    token, wrote = _INPUTS.set(()), _WRITTEN.set([])
    try:
        yield
    finally:
        _INPUTS.reset(token)
        _WRITTEN.reset(wrote)


def written() -> list[Path]:
    """The files the running command has put in place so far, complete (an interrupt says them)."""
    return list(_WRITTEN.get() or [])


def note_inputs(*paths: str | os.PathLike) -> None:
    """Record files as inputs of the running command (existing regular files only)."""
    current = _INPUTS.get()
    if current is None:
        return
    known = list(current)
    for p in paths:
        p = Path(p)
        if p.is_file() and p not in known:
            known.append(p)
    _INPUTS.set(tuple(known))


def input_named_by(path: str | os.PathLike) -> Path | None:
    """The recorded input that ``path`` is (same file: symlink, hard link or another spelling)."""
    path = Path(path)
    if not path.exists():
        return None
    for p in _INPUTS.get() or ():
        try:
            if os.path.samefile(p, path):
                return p
        except OSError:
            continue
    return None


def refuse_input(path: str | os.PathLike) -> None:
    """Raise :class:`InputError` if writing ``path`` would replace an input file."""
    src = input_named_by(path)
    if src is not None:
        same = "" if Path(src) == Path(path) else f" (the same file as the input {src})"
        raise InputError(
            f"refusing to write {path}: it is an input of this command{same}; choose another output"
        )


def read_input(
    path: str | os.PathLike, *, max_bytes: int, what: str = "file", error=InputError
) -> str:
    """A UTF-8 text input, size-bounded and recorded; one-line ``error`` on any problem."""
    p = Path(path)
    if not p.exists():
        raise error(f"{p}: no such file")
    if p.is_dir():
        raise error(f"{p}: is a folder, expected a file")
    try:
        size = p.stat().st_size
    except OSError as exc:
        raise error(f"{p}: cannot be read ({exc.strerror})") from None
    if size > max_bytes:
        raise error(
            f"{p}: {size / 2**20:.1f} MB is larger than the {max_bytes / 2**20:.0f} MB a {what} "
            f"may have"
        )
    note_inputs(p)
    try:
        return p.read_text("utf-8-sig")  # a byte-order mark (Windows editors) is no text
    except UnicodeDecodeError:
        raise error(f"{p}: not a UTF-8 text file") from None
    except OSError as exc:
        raise error(f"{p}: cannot be read ({exc.strerror})") from None


# ----------------------------------------------------------------- outputs


def _first_existing(path: Path) -> Path:
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _refuse_link_loop(path: Path) -> None:
    """A symbolic link that loops (to itself, or round several) names no file: refuse it rather than
    replace the link."""
    if path.is_symlink():
        try:
            path.resolve(strict=True)
        except FileNotFoundError:
            return  # a link to a missing file: the link is replaced, as always
        except (OSError, RuntimeError):
            raise InputError(
                f"output {path} is a symbolic link that loops; nothing written"
            ) from None


def _check_destination(dest: Path) -> None:
    """``dest`` can take a file: not a folder, not an input, not a looping link, every missing folder
    creatable."""
    refuse_input(dest)
    _refuse_link_loop(dest)
    if dest.is_dir():
        raise InputError(f"output {dest} is a folder where a file must go; nothing written")
    base = _first_existing(dest.parent)
    if not base.is_dir():
        raise InputError(f"output {dest}: {base} exists and is not a folder; nothing written")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {dest}: folder {base} is not writable")


def _root_folder(root: Path) -> Path:
    if root.exists() and not root.is_dir():
        raise InputError(f"output folder {root} is a file, not a folder")
    if not root.is_dir():
        raise InputError(f"output folder {root} does not exist")
    if not os.access(root, os.W_OK):
        raise InputError(f"output folder {root} is not writable")
    return root


def publish(files: dict[Path, bytes | str], root: str | os.PathLike) -> list[Path]:
    """Write every file all-or-nothing; ``root`` (an existing folder) holds them all.

    Missing folders between ``root`` and a file are created (and removed again
    on failure). Raises :class:`InputError` with nothing changed on disk.
    """
    root = _root_folder(Path(root) if str(root) else Path("."))
    dests = [Path(d) for d in files]
    for d in dests:
        _check_destination(d)
    try:
        scratch = Path(
            tempfile.mkdtemp(prefix=".fabkiri-", suffix=".tmp", dir=root)
        )  # 0700, never published
    except OSError as exc:
        raise InputError(f"cannot write into {root}: {exc.strerror or exc}") from None
    try:
        staged = []
        for i, data in enumerate(files.values()):
            tmp = scratch / f"new-{i}"
            tmp.write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
            _publish_mode(tmp)
            staged.append(tmp)
        _move_in(dests, staged, scratch)
    except OSError as exc:
        raise InputError(f"cannot write {root}: {exc.strerror or exc}; nothing written") from None
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return dests


def _move_in(dests: list[Path], staged: list[Path], scratch: Path) -> None:
    """Move the staged files to their destinations; on any failure undo every step taken."""
    made: list[Path] = []  # folders created, outermost first
    done: list[tuple[Path, Path | None]] = []  # (destination, backup of the file it replaced)
    try:
        for i, (dest, tmp) in enumerate(zip(dests, staged)):
            missing = []
            p = dest.parent
            while not p.exists():
                missing.append(p)
                p = p.parent
            for folder in reversed(missing):
                folder.mkdir()
                made.append(folder)
            backup = None
            if dest.exists() or dest.is_symlink():
                backup = scratch / f"old-{i}"
            done.append((dest, backup))  # before the move: a signal between them must undo it
            _record(dest)
            if backup is not None:
                os.replace(dest, backup)
            os.replace(tmp, dest)
    except BaseException:
        _undo(done, made)
        raise


def _record(dest: Path, put: bool = True) -> None:
    record = _WRITTEN.get()
    if record is not None:
        record.append(dest) if put else record.remove(dest)


def _undo(done: list[tuple[Path, Path | None]], made: list[Path]) -> None:
    """Put back what :func:`_move_in` replaced and remove the folders it made."""
    for dest, backup in reversed(done):
        _record(dest, put=False)
        try:
            if backup is not None and backup.exists():
                os.replace(backup, dest)
            elif backup is None:
                dest.unlink(missing_ok=True)
        except OSError:
            pass
    for folder in reversed(made):
        try:
            folder.rmdir()
        except OSError:
            pass


def atomic_write(path: str | os.PathLike, data: bytes | str) -> Path:
    """Write ``data`` to ``path`` (its folder must exist) through a scratch file beside it."""
    path = Path(path)
    refuse_input(path)
    if path.is_dir():
        raise InputError(f"output {path} is a folder, expected a file name")
    return publish({path: data}, path.parent)[0]


def check_output_file(path: str | os.PathLike) -> None:
    """Up-front check of a single-file output (before a long computation)."""
    path = Path(path)
    refuse_input(path)
    _refuse_link_loop(path)
    if path.is_dir():
        raise InputError(f"output {path} is a folder, expected a file name")
    _root_folder(path.parent if str(path.parent) else Path("."))


def check_output_parent(path: str | os.PathLike) -> None:
    """Up-front check of any output, file or folder: the folder that takes its files (an existing output
    folder, else the one it goes in) exists and is writable, before a command's work rather than after."""
    _root_folder(_scratch_root(Path(path)))


def _scratch_root(path: Path) -> Path:
    """Where a writer's scratch goes for the output ``path``: an existing folder itself (a mount point,
    a USB stick, takes no rename from its parent's file system), else the folder it goes in."""
    if path.is_dir():
        return path
    return path.parent if str(path.parent) else Path(".")


def check_output_folder(folder: str | os.PathLike) -> None:
    """Up-front check of a folder output: a folder (or creatable as one), not an input."""
    folder = Path(folder)
    refuse_input(folder)
    _refuse_link_loop(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"output {folder} exists and is not a folder")
    _root_folder(_scratch_root(folder))


def atomic_write_many(folder: str | os.PathLike, files: Mapping[str, bytes | str]) -> list[Path]:
    """Write several files into ``folder`` (created if missing) all-or-nothing.

    Every destination is checked before anything is written; everything is
    written to a scratch folder in ``folder`` (beside it when it is new) and
    moved in only when every file is complete (see :func:`publish`).
    """
    folder = Path(folder)
    check_output_folder(folder)
    root = _scratch_root(folder)
    return publish({folder / name: data for name, data in files.items()}, root)


def left_over(folder: str | os.PathLike, names: Iterable[str]) -> list[str]:
    """The files an earlier run's ``manifest.json`` in ``folder`` lists that a run writing ``names`` leaves
    in place (a cut of another pattern into the same folder): to be named, never silently beside the
    new ones. Empty when there is no readable manifest."""
    try:
        old = json.loads((Path(folder) / "manifest.json").read_text("utf-8")).get("files")
    except (OSError, ValueError, AttributeError):
        return []
    if not isinstance(old, list):
        return []
    keep = set(names)
    return sorted(
        str(f) for f in old if isinstance(f, str) and f not in keep and (Path(folder) / f).is_file()
    )
