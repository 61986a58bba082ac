"""Where the shipped templates (materials, printers, targets, patterns) live.

In a source checkout (or an editable install) they are the repository's
``templates/`` folder; a regular install carries the same files inside the
package as ``fabkiri._templates``.
"""

from __future__ import annotations

from pathlib import Path

_REPO_TEMPLATES = Path(__file__).resolve().parents[1] / "templates"


def template_dir(kind: str) -> Path:
    """Folder of one kind of template: ``materials``, ``printers``, ``targets`` or ``patterns``."""
    repo = _REPO_TEMPLATES / kind
    if repo.is_dir():
        return repo
    return Path(__file__).resolve().parent / "_templates" / kind
