from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
# the shared folder sits beside the main checkout, or two levels up from a worktree
REFERENCE = next(
    (
        p / "shared" / "reference" / "additive-kirigami"
        for p in (REPO.parent, REPO.parents[1])
        if (p / "shared" / "reference" / "additive-kirigami").is_dir()
    ),
    REPO.parent / "shared" / "reference" / "additive-kirigami",
)
TEMPLATES = REPO / "templates"


def ref(name: str) -> Path:
    path = REFERENCE / f"Example_{name}.obj"
    if not path.exists():
        pytest.skip(f"reference data not available: {path}")
    return path


@pytest.fixture
def run_cli(capsys):
    """Run the CLI in-process; returns (exit code, stdout, stderr)."""
    from fabkiri.cli.main import main

    def run(*argv: str):
        code = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return code, out, err

    return run
