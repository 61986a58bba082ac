"""The wheel must carry every subpackage and the templates."""

from __future__ import annotations

import tomllib

from fabkiri.templates import template_dir

from .conftest import REPO


def test_every_subpackage_is_listed_in_pyproject():
    listed = set(
        tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    )
    found = {
        ".".join(p.parent.relative_to(REPO).parts) for p in (REPO / "fabkiri").rglob("__init__.py")
    }
    assert found <= listed, f"add to [tool.setuptools] packages: {sorted(found - listed)}"


def test_templates_are_found():
    for kind in ("materials", "printers", "targets", "patterns"):
        assert any(template_dir(kind).glob("*.json")), kind


# what the tests need of a library beyond its own requirements: trimesh loads 3MF through networkx
INDIRECT = {"networkx"}
LOCAL = {"fabkiri", "tests", "conftest", "layout_fixtures", "layout_mutations", "designs", "slicer"}


def _declared() -> set[str]:
    import re

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    reqs = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        reqs += extra
    return {re.split(r"[\[<>=!~ ;]", r, maxsplit=1)[0].lower().replace("_", "-") for r in reqs}


def test_every_package_the_tests_import_is_declared():
    """`pip install .[test]` (and `.[cad]` for STEP) gives every module the tests and benches import,
    and what trimesh needs to load a 3MF."""
    import ast
    import sys
    from importlib.metadata import packages_distributions

    dists = packages_distributions()
    modules = set(INDIRECT)
    for f in [*(REPO / "tests").rglob("*.py"), *(REPO / "bench").glob("*.py")]:
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if isinstance(node, ast.Import):
                modules |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                modules.add(node.module.split(".")[0])
            elif (
                isinstance(node, ast.Call)
                and getattr(node.func, "attr", "") == "importorskip"
                and node.args
                and isinstance(node.args[0], ast.Constant)
            ):
                modules.add(str(node.args[0].value).split(".")[0])
    modules -= (
        set(sys.stdlib_module_names) | LOCAL | {p.stem for p in (REPO / "bench").glob("*.py")}
    )
    declared = _declared()
    missing = {}
    for m in sorted(modules):
        names = {d.lower().replace("_", "-") for d in dists.get(m, [m])}
        if not names & declared and not (
            m == "distributed" and "dask" in declared
        ):  # dask[distributed]
            missing[m] = sorted(names)
    assert not missing, f"declare in pyproject.toml (the test extra): {missing}"


def test_one_version_source(capsys):
    """The version lives in ``fabkiri/__init__.py`` only: pyproject reads it, ``--version`` prints it."""
    import fabkiri
    import pytest
    from fabkiri.cli.main import main

    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert "version" not in pyproject["project"]
    assert "version" in pyproject["project"]["dynamic"]
    assert pyproject["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "fabkiri.__version__"}
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.strip() == f"fabkiri {fabkiri.__version__}"
