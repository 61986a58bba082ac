"""Where the shipped templates (materials, printers, targets, patterns) live.

In a source checkout (or an editable install) they are the repository's
``templates/`` folder; a regular install carries the same files inside the
package as ``fabkiri._templates``.
"""

from __future__ import annotations

import difflib
from pathlib import Path

_REPO_TEMPLATES = Path(__file__).resolve().parents[1] / "templates"


def template_dir(kind: str) -> Path:
    """Folder of one kind of template: ``materials``, ``printers``, ``targets`` or ``patterns``."""
    repo = _REPO_TEMPLATES / kind
    if repo.is_dir():
        return repo
    return Path(__file__).resolve().parent / "_templates" / kind


def nearest(name: str, names: list[str]) -> str:
    """`` (did you mean 'card-0.3'?)`` for the presets nearest ``name`` (case ignored): those it begins,
    else the closest by :mod:`difflib`; ``""`` when none is near."""
    lower = {n.lower(): n for n in names}
    found = [n for n in lower if n.startswith(name.lower())] or difflib.get_close_matches(
        name.lower(), list(lower), n=1, cutoff=0.6
    )
    if not found:
        return ""
    return f" (did you mean {' or '.join(repr(lower[n]) for n in found)}?)"
