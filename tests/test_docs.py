"""The documentation the code cites lives in the repository, its anchors exist, and comments carry no timings.

Fast: reads text only. Four rules:
- nothing cites the method's old spec outside the repository (its section signs or its folder);
- every ``docs/NAME.md#anchor`` named in the code, the tests and the benches, and every relative link
  between the Markdown pages, resolves to a file and to a heading (GitHub's anchor of it) or an ``<a id>``;
- comments and docstrings in ``fabkiri/`` carry no benchmark timings or memory figures (they go stale:
  the figures live in docs/speed.md#figures-from-code-comments and in the benches' output);
- every path docs/architecture.md names exists, and every ``name.py`` a comment or docstring in
  ``fabkiri/`` names is a file of the repository (module names go stale when files move).
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from functools import cache
from pathlib import Path

from .conftest import REPO

PY_DIRS = ("fabkiri", "tests", "bench")
PAGES = [
    REPO / "README.md",
    REPO / "CONTRIBUTING.md",
    REPO / "CHANGELOG.md",
    *(REPO / "docs").glob("*.md"),
]
THIS = Path(__file__).resolve()

# the old citations, spelled in pieces so this file does not match itself
OUTSIDE = re.compile(
    "|".join(
        [
            "spec " + "§",
            r"\.\./" + "shared",
            "shared/" + "docs",
            "algorithm " + "spec",
            "fabrication " + "spec",
            r"(?:algorithm|fabrication)\.md " + "§",
        ]
    )
)

# a number with a unit of time or memory, or a speed-up: "0.8 s", "12 ms", "80 µs", "4 min", "52 CPU s",
# "540 MB", "3x faster". A plain "s" needs the space ("4s" is a plural), and bare "h" is not matched (a step
# size in the maths).
TIMING = re.compile(
    r"\d\s?(?:ms|µs|us|ns)\b"
    r"|\d\s(?:s|secs?|seconds?|min|mins|minutes?|hours?)\b"
    r"|\d\s?(?:CPU|wall)[ -]?(?:s|secs?|seconds?|time)\b"
    r"|\d\s?(?:x|×|times)\s(?:faster|slower|quicker)"
    r"|\d\s?[KMG]i?B\b"
)

CITED = re.compile(r"docs/([\w.-]+\.md)(?:#([\w-]+))?")
LINK = re.compile(r"\]\(([^)\s]*)\)")


def _py_files(*dirs: str) -> list[Path]:
    return sorted(p for d in dirs for p in (REPO / d).rglob("*.py") if p.resolve() != THIS)


@cache
def _anchors(page: Path) -> frozenset[str]:
    """GitHub's anchors of a page's headings (lower case, punctuation dropped, spaces to hyphens, repeats
    numbered) and its explicit ``<a id>``/``<a name>``."""
    seen: dict[str, int] = {}
    out = set(re.findall(r"<a (?:id|name)=\"([^\"]+)\"", page.read_text()))
    fenced = False
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            fenced = not fenced
        m = None if fenced else re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            slug = re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-")
            n = seen.get(slug, 0)
            seen[slug] = n + 1
            out.add(slug if n == 0 else f"{slug}-{n}")
    return frozenset(out)


def _comments_and_docstrings(path: Path):
    """``(line, text)`` of every comment and every module, class and function docstring."""
    src = path.read_text()
    for tok in tokenize.generate_tokens(io.StringIO(src).readline):
        if tok.type == tokenize.COMMENT:
            yield tok.start[0], tok.string
    for node in ast.walk(ast.parse(src)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            first = node.body[0] if node.body else None
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                for i, line in enumerate(first.value.value.splitlines()):
                    yield first.lineno + i, line


def test_nothing_cites_docs_outside_the_repository():
    bad = [
        f"{p.relative_to(REPO)}:{i}: {line.strip()}"
        for p in [*_py_files(*PY_DIRS), *PAGES]
        if p.exists()
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if OUTSIDE.search(line)
    ]
    assert not bad, "cite docs/*.md#anchor instead:\n" + "\n".join(bad)


def test_every_cited_docs_anchor_exists():
    bad = []
    for p in _py_files(*PY_DIRS):
        for i, line in enumerate(p.read_text().splitlines(), 1):
            for name, anchor in CITED.findall(line):
                page = REPO / "docs" / name
                if not page.exists() or (anchor and anchor not in _anchors(page)):
                    bad.append(f"{p.relative_to(REPO)}:{i}: docs/{name}#{anchor}")
    assert not bad, "no such page or heading:\n" + "\n".join(bad)


def test_every_link_between_pages_resolves():
    bad = []
    for page in PAGES:
        if not page.exists():
            continue
        for i, line in enumerate(page.read_text().splitlines(), 1):
            for target in LINK.findall(line):
                if re.match(r"[a-z]+:", target):  # http:, https:, mailto:
                    continue
                file, _, anchor = target.partition("#")
                dest = (page.parent / file) if file else page
                if not dest.exists():
                    bad.append(f"{page.relative_to(REPO)}:{i}: {target}")
                elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest):
                    bad.append(f"{page.relative_to(REPO)}:{i}: {target}")
    assert not bad, "broken links:\n" + "\n".join(bad)


def test_comments_carry_no_timings():
    bad = [
        f"{p.relative_to(REPO)}:{i}: {text.strip()}"
        for p in _py_files("fabkiri")
        if TIMING.search(p.read_text())  # only files with a figure anywhere are tokenised
        for i, text in _comments_and_docstrings(p)
        if TIMING.search(text)
    ]
    assert not bad, (
        "move measured figures to docs/speed.md#figures-from-code-comments (or a bench's output) and keep "
        "the reason in the comment:\n" + "\n".join(bad)
    )


def test_the_timing_pattern_catches_timings_and_spares_the_rest():
    for text in (
        "took 0.8 s",
        "12 ms a call",
        "~80 µs",
        "4 min 51 s",
        "52 CPU s",
        "540 MB",
        "3x faster",
    ):
        assert TIMING.search(text), text
    for text in (
        "4s and 2s",
        "1e-6 h",
        "Hausdorff 1.4 %",
        "a 16x16 heart",
        "the wall s spent",
        "0.4 mm",
    ):
        assert not TIMING.search(text), text


def test_architecture_names_real_paths():
    """Every path in backticks on docs/architecture.md exists: one with a folder (``fabkiri/...``, or a
    path under ``fabkiri/`` such as ``pattern/kinds/quad/``) from the repository or the package, a bare
    file name (listed under its folder) somewhere in the package. Files an example would add are written
    in italics, not backticks."""
    page = (REPO / "docs" / "architecture.md").read_text()
    paths = set(re.findall(r"`([\w.-]*/[\w./-]*)`", page))
    files = set(re.findall(r"`([\w-]+\.(?:py|json|js|toml))`", page))
    assert len(paths) > 40 and len(files) > 40  # the page names the tree
    package = {p.name for p in (REPO / "fabkiri").rglob("*")}
    missing = [
        n
        for n in sorted(paths)
        if not any((b / n.rstrip("/")).exists() for b in (REPO, REPO / "fabkiri"))
    ] + [n for n in sorted(files) if n not in package and not (REPO / n).exists()]
    assert not missing, "docs/architecture.md names paths that do not exist: " + ", ".join(missing)


def test_ci_runs_the_readme_test_command():
    """The README's two set-up commands stay as they are, and `.ci/run` runs the second one (with the
    lint, format and type checks between its install and its tests)."""
    readme = (REPO / "README.md").read_text()
    install = "python3 -m pip install . && fabkiri cut templates/patterns/standard-8x8.json"
    test = "python3 -m pip install -e '.[test,cad]' && python3 -m pytest -n 2 --dist loadgroup"
    assert install in readme and test in readme
    ci = " ".join((REPO / ".ci" / "run").read_text().replace("\\\n", " ").split())
    pip, pytest = test.split(" && ")
    assert pip in ci and pytest in ci and ci.index(pip) < ci.index(pytest)


def test_comments_name_files_that_exist():
    """``reduced_mirror.py`` in a docstring after the file became ``rigid/mirror.py`` points nowhere: every
    ``name.py`` (or ``folder/name.py``) in a comment or docstring of ``fabkiri/`` ends some file's path."""
    known = ["/" + p.relative_to(REPO).as_posix() for p in _py_files(*PY_DIRS)] + [f"/{THIS.name}"]
    named = re.compile(r"(?<![\w/.])([a-z_][\w/]*\.py)\b")  # lower case: "Boxes.py" is a project
    bad = [
        f"{p.relative_to(REPO)}:{i}: {name}"
        for p in _py_files("fabkiri")
        if named.search(p.read_text())  # only files that name one are tokenised
        for i, text in _comments_and_docstrings(p)
        for name in named.findall(text)
        if not any(k.endswith("/" + name) for k in known)
    ]
    assert not bad, "no such file (moved?):\n" + "\n".join(bad)
