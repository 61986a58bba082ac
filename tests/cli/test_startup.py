"""Lazy start-up: the command table matches what the modules register, and a command loads only its own
module (timings live in bench/solve.py, not here)."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from fabkiri.cli import main as cli
from hypothesis import given, settings
from hypothesis import strategies as st


def _registered(parser) -> dict[str, str]:
    sub = next(a for a in parser._actions if a.dest == "command")
    return {a.dest: a.help for a in sub._choices_actions}


def test_summaries_match_the_modules():
    full = _registered(cli.build_parser(""))
    assert {k: v[1] for k, v in cli.SUMMARIES.items()} == {k: full[k] for k in cli.SUMMARIES}
    for name, (module, _) in cli.SUMMARIES.items():
        assert module in cli.COMMANDS, name


def test_lazy_parser_has_every_command():
    assert set(_registered(cli.build_parser(None))) == set(_registered(cli.build_parser("")))
    assert set(_registered(cli.build_parser("design"))) == set(_registered(cli.build_parser("")))


def _modules_after(argv: list[str]) -> set[str]:
    code = (
        "import sys\nfrom fabkiri.cli.main import main\n"
        f"try:\n    main({argv!r})\nexcept SystemExit:\n    pass\n"
        "print('\\n'.join(sys.modules))"
    )
    return set(_printed(code))


def _printed(code: str) -> list[str]:
    """The words ``code`` prints, run in a fresh interpreter (nothing loaded by this test process)."""
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split()


def test_help_imports_no_numerics():
    mods = _modules_after(["--help"])
    assert not {"numpy", "scipy", "shapely", "ezdxf", "trimesh", "matplotlib"} & mods
    assert not any(m.startswith("fabkiri.cli.") and m != "fabkiri.cli.main" for m in mods)


@pytest.mark.slow
def test_design_with_its_preview_imports_only_what_it_uses(tmp_path):
    # one process for both checks (each is an interpreter start and a design): the preview PNG is drawn
    # without matplotlib, so a design with its preview must import no more than one without
    mods = _modules_after(
        [
            "design",
            "--tiles",
            "3x3",
            "--target",
            "circle",
            "--rigid",
            "-o",
            str(tmp_path / "p.json"),
        ]
    )
    assert (tmp_path / "p.json").exists()
    png = (tmp_path / "p.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert "fabkiri.design.quad.solve" in mods
    assert (
        not {
            "scipy.interpolate",
            "scipy.optimize",
            "ezdxf",
            "trimesh",
            "matplotlib",
            "svgwrite",
            "jsonschema",
        }
        & mods
    )
    assert not {"fabkiri.cli.cut_cmd", "fabkiri.cli.print_cmd", "fabkiri.cli.deploy_cmd"} & mods


@settings(max_examples=30, deadline=None)
@given(st.integers(3, 60), st.integers(0, 2**32 - 1))
def test_periodic_spline_equals_scipy(k, seed):
    from fabkiri.design.core.spline import PeriodicCubic
    from scipy.interpolate import CubicSpline

    rng = np.random.default_rng(seed)
    x = np.concatenate([[0.0], np.cumsum(rng.uniform(0.2, 2.0, k))])
    x /= x[-1]
    y = rng.normal(size=(k + 1, 2))
    y[-1] = y[0]
    ref = CubicSpline(x, y, bc_type="periodic")
    ours = PeriodicCubic.interpolate(x, y)
    u = rng.uniform(-1.0, 2.0, 50)
    vals = ours.value_and_derivatives(u)
    for nu in (0, 1, 2):
        scale = np.abs(ref(u, nu)).max() + 1.0
        assert np.abs(ours(u, nu) - ref(u, nu)).max() <= 1e-9 * scale
        assert np.abs(vals[nu] - ref(u, nu)).max() <= 1e-9 * scale


@settings(max_examples=20, deadline=None)
@given(
    st.integers(1, 9),
    st.integers(1, 9),
    st.integers(1, 20),
    st.integers(1, 20),
    st.integers(0, 2**32 - 1),
)
def test_grid_resampling_equals_scipy(m, n, rows, cols, seed):
    from fabkiri.design.quad.rigid.family import resample_grid
    from scipy.interpolate import RegularGridInterpolator

    grid = np.random.default_rng(seed).normal(size=(m + 1, n + 1, 2))
    at = RegularGridInterpolator((np.arange(m + 1.0), np.arange(n + 1.0)), grid, method="linear")
    yi, xi = np.meshgrid(
        np.linspace(0.0, m, rows + 1), np.linspace(0.0, n, cols + 1), indexing="ij"
    )
    assert np.abs(resample_grid(grid, rows, cols) - at(np.stack([yi, xi], -1))).max() <= 1e-12


@pytest.mark.slow
def test_design_defers_unused_numpy_subpackages(tmp_path):
    # scipy's array-API shim binds every numpy subpackage; the DEFERRED ones stay unloaded (lazy)
    # through a design and still work when used
    code = (
        "import sys\nfrom fabkiri.cli.main import main\n"
        f"main(['design', '--tiles', '3x3', '--target', 'circle', '--rigid', '--no-preview', '-o', "
        f"{str(tmp_path / 'p.json')!r}])\n"
        f"lazy = [type(sys.modules[m]).__name__ for m in {cli.DEFERRED!r}]\n"
        "print(lazy, 'charset_normalizer' in sys.modules, 'unittest' in sys.modules)\n"
        "import numpy as np\nnp.testing.assert_allclose(np.ones(2), np.ones(2))\n"
        "from numpy.testing import assert_array_equal\nassert_array_equal([1], [1])\n"
        "print(type(sys.modules['numpy.testing']).__name__)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split("\n")
    assert out[0] == f"{['_LazyModule'] * len(cli.DEFERRED)} False False"
    assert out[1] == "module"  # loaded for real on first use


def test_defer_is_a_no_op_once_scipy_is_loaded():
    import scipy  # noqa: F401  (this test process has it)

    assert cli.defer_unused_numpy() == []


def test_rigid_8x8_design_loads_no_unused_scipy(tmp_path):
    # the rigid 8x8 circle of the start-up goal (issue #18), preview included: its KD-trees come from the
    # compiled extension alone (fabkiri/kdtree.py), not through scipy.spatial, which loads scipy.special,
    # scipy.spatial.distance and scipy.spatial.transform; OpenBLAS started with one thread; modules frozen
    code = (
        "import gc, os, sys\nfrom fabkiri.cli.main import main\n"
        f"main(['design', '--tiles', '8x8', '--target', 'circle', '--rigid', '-o', {str(tmp_path / 'p.json')!r}])\n"
        "print(os.environ.get('OPENBLAS_NUM_THREADS'), gc.get_freeze_count() > 10000)\n"
        "print('\\n'.join(sys.modules))"
    )
    env = {k: v for k, v in os.environ.items() if k not in cli.BLAS_THREAD_VARS}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    )
    first, *mods = out.stdout.split("\n")
    assert (tmp_path / "p.json").exists() and (tmp_path / "p.png").exists()
    assert "scipy.spatial._ckdtree" in mods  # the KD-tree was used
    assert not {
        "scipy.spatial",
        "scipy.special",
        "scipy.spatial.distance",
        "scipy.spatial.transform",
        "scipy.optimize",
        "scipy.interpolate",
    } & set(mods)
    # the ligament's cut bound needs no layout reader (verify.quads loads the DXF/SVG readers)
    assert (
        "fabkiri.fabricate.cut.hingekinds.ligament" in mods and "fabkiri.verify.quads" not in mods
    )
    assert first == "1 True"


def test_blas_threads_follow_the_user():
    # a library caller's process (numpy loaded) and a user's own choice are left alone
    assert "numpy" in sys.modules and not cli.single_thread_blas_process("design")
    code = (
        "import os\nfrom fabkiri.cli.main import single_thread_blas_process as s\n"
        "print(s('info'), s('design'), os.environ['OPENBLAS_NUM_THREADS'])"
    )
    env = {k: v for k, v in os.environ.items() if k not in cli.BLAS_THREAD_VARS}
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    )
    assert run.stdout.split() == ["False", "True", "1"]
    env["OMP_NUM_THREADS"] = "2"
    code = code.replace(
        "os.environ['OPENBLAS_NUM_THREADS']", "os.environ.get('OPENBLAS_NUM_THREADS')"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    )
    assert run.stdout.split() == ["False", "False", "None"]
    # a cut's linear algebra is sparse or small too (issue #36): its process starts OpenBLAS on one thread
    code = "from fabkiri.cli.main import single_thread_blas_process as s\nprint(s('cut'))"
    env.pop("OMP_NUM_THREADS")
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    )
    assert run.stdout.split() == ["True"]


def test_kdtree_is_scipys_class_before_and_after_scipy_spatial():
    # loaded alone first, then `import scipy.spatial` reuses the same extension module: one class, one answer
    code = (
        "import sys\nimport numpy as np\nfrom fabkiri.kdtree import KDTree\n"
        "pts = np.random.default_rng(1).normal(size=(500, 2))\n"
        "t = KDTree(pts)\nalone = 'scipy.spatial' in sys.modules\n"
        "import scipy.spatial\n"
        "d1, i1 = t.query(pts[:50] + 0.01, k=3)\nd2, i2 = scipy.spatial.cKDTree(pts).query(pts[:50] + 0.01, k=3)\n"
        "print(alone, type(t) is scipy.spatial.cKDTree, (d1 == d2).all(), (i1 == i2).all())"
    )
    assert _printed(code) == ["False", "True", "True", "True"]


def test_cut_loads_neither_the_solver_nor_scipy_spatial(tmp_path):
    # issue #36: `fabkiri.api` and `fabkiri.design` load their names on first use, so a cut (which reads
    # a stored target through design.conformance) does not import the design solver; the read-back's
    # convex hull comes from the compiled qhull extension alone (fabkiri/kdtree.py)
    from fabkiri.templates import template_dir

    src = str(template_dir("patterns") / "standard-8x8.json")
    mods = _modules_after(["cut", src, "-o", str(tmp_path / "c")])
    assert (tmp_path / "c" / "manifest.json").exists()
    assert "scipy.spatial._qhull" in mods  # the hull was used
    assert (
        not {"fabkiri.design.quad.solve", "fabkiri.api.design", "scipy.spatial", "scipy.special"}
        & mods
    )
    # the pattern checks' rigid path comes from mechanics.rigid_path, not through mechanics.deploy (which
    # loads the deployment drivers, the elastic path and contact); the web checks' print-style lookup loads no
    # print plan geometry; the pattern reader and the shared options come without `new`'s command module
    # and `info`'s report
    assert "fabkiri.mechanics.rigid_path" in mods and "fabkiri.fabricate.print.job" in mods
    assert (
        not {
            "fabkiri.mechanics.deploy",
            "fabkiri.mechanics.drivers",
            "fabkiri.mechanics.elastic",
            "fabkiri.fabricate.print.geometry",
            "fabkiri.fabricate.print.pingeom",
            "fabkiri.fabricate.print.solid",
            "fabkiri.cli.pattern_cmds",
            "fabkiri.mechanics.info",
        }
        & mods
    )
    # the sheet preview and the assembly map are drawn with Pillow (fabricate/pngcanvas.py), not matplotlib
    assert (tmp_path / "c" / "standard-8x8.png").exists() and (
        tmp_path / "c" / "assembly.png"
    ).exists()
    assert "PIL.ImageDraw" in mods and not any(m.split(".")[0] == "matplotlib" for m in mods)


def test_convex_hull_is_scipys_class_before_and_after_scipy_spatial():
    code = (
        "import sys\nimport numpy as np\nfrom fabkiri.kdtree import ConvexHull\n"
        "pts = np.random.default_rng(2).normal(size=(300, 2))\n"
        "h = ConvexHull(pts)\nalone = 'scipy.spatial' in sys.modules\n"
        "import scipy.spatial\n"
        "print(alone, type(h) is scipy.spatial.ConvexHull, "
        "(h.vertices == scipy.spatial.ConvexHull(pts).vertices).all())"
    )
    assert _printed(code) == ["False", "True", "True"]


def test_a_print_loads_neither_the_cutter_nor_its_svg_writer(tmp_path):
    # issue #36: `print` read the design's intent and a tube's seam through `api.cut` and
    # `fabricate.tube_cut`, which loaded the cutter, its read-back and svgwrite (~0.1 CPU s) for a planar
    # pattern; a print that is refused (the 8x8 heart past prusa-mk4's bed) is decided without them
    from pathlib import Path

    src = str(Path(__file__).parents[1] / "data" / "heart-8x8.json")
    mods = _modules_after(["print", src, "-o", str(tmp_path / "p")])
    assert "fabkiri.api.print" in mods and "fabkiri.api.advice" in mods  # refused, with its advice
    assert not (tmp_path / "p").exists()
    assert (
        not {"fabkiri.api.cut", "fabkiri.fabricate.cut.sheets", "fabkiri.fabricate.cut.readback"}
        & mods
    )
    assert not any(m.split(".")[0] in ("svgwrite", "ezdxf", "trimesh", "matplotlib") for m in mods)


@pytest.fixture(scope="module")
def design_modules(tmp_path_factory) -> dict[str, str]:
    """Every module the rigid 8x8 design's process loaded (it converges without the full solver's CG),
    by name, with its type's name (one process for the tests that read it)."""
    out = tmp_path_factory.mktemp("design") / "p.json"
    code = (
        "import sys\nfrom fabkiri.cli.main import main\n"
        f"main(['design', '--tiles', '8x8', '--target', 'circle', '--rigid', '--no-preview', '-o', {str(out)!r}])\n"
        "print('\\n'.join(f'{k} {type(v).__name__}' for k, v in list(sys.modules.items())))"
    )
    lines = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    assert out.exists()
    return dict(line.split(" ", 1) for line in lines if line.count(" ") == 1)


def test_a_design_defers_numpys_string_and_record_modules(design_modules):
    # scipy's `from numpy import *` loaded them for nothing
    for name in ("numpy.strings", "numpy.char", "numpy.rec", "numpy.ctypeslib", "numpy.core"):
        assert design_modules.get(name) == "_LazyModule", name


def test_a_design_loads_no_other_commands_module_nor_what_it_never_calls(design_modules):
    # issue #36: design_cmd took `--i-know` from `new`'s command module (which loads the tube command and
    # `info`'s report); `mechanics`' package loaded `describe`'s report, the tube frames and the seams for a
    # design that contracts only; the continuation in the fabrication limits loaded for every design; the
    # deployment path for a constant, make's tile chooser, the large lattices' grid core and the offsets' family
    assert (
        "fabkiri.cli.design_cmd" in design_modules
        and "fabkiri.mechanics.contract" in design_modules
    )
    for name in (
        "fabkiri.cli.pattern_cmds",
        "fabkiri.cli.tube_cmd",
        "fabkiri.mechanics.info",
        "fabkiri.mechanics.tube",
        "fabkiri.pattern.kinds.periodic.sheet",
        "fabkiri.api.continuation",
        "fabkiri.mechanics.path",
        "fabkiri.api.maker_tiles",
        "fabkiri.design.quad.rigid.core",
        "fabkiri.design.quad.rigid.offsets",
    ):
        assert name not in design_modules, name


def test_a_design_sizes_every_hinge_kind_and_print_style_by_their_rules_alone(design_modules):
    # issue #36: the summary's cut and print sizes ask every kind's and style's rules; their cutting, the
    # print jobs, plans, solids and pin plans (with dataclasses a design never makes) stay unloaded, and so
    # does the cut drawings' SVG module a named target never reads
    assert {
        "fabkiri.fabricate.cut.hingekinds.ligament",
        "fabkiri.fabricate.print.styles.rules",
        "fabkiri.fabricate.print.pinsizes",
    } <= set(design_modules)
    for name in (
        "fabkiri.fabricate.cut.hingekinds.cutting",
        "fabkiri.fabricate.cut.hingekinds.ligament_cut",
        "fabkiri.fabricate.cut.hingekinds.tape_cut",
        "fabkiri.fabricate.cut.hinges",
        "fabkiri.fabricate.print.build",
        "fabkiri.fabricate.print.styles.pinned",
        "fabkiri.fabricate.print.styles.strips",
        "fabkiri.fabricate.print.geometry",
        "fabkiri.fabricate.print.pingeom",
        "fabkiri.fabricate.print.solid",
        "fabkiri.exchange.svg",
        "fabkiri.exchange.drawing",
    ):
        assert name not in design_modules, name


def test_a_command_loads_numpy_ma_and_scipy_linalg_before_its_own_modules(tmp_path):
    # imported a dozen imports deep, their docstring processing crossed a frame chunk's end of CPython 3.11
    # thousands of times (an mmap and munmap each): `main` loads them first, at the foot of the stack
    code = (
        "import sys\nimport fabkiri.cli.main as m\nparser = m.build_parser\n"
        "def build(command):\n"
        "    print(*(n in sys.modules for n in (*m.PRELOAD, 'scipy.linalg', 'fabkiri.api')))\n"
        "    return parser(command)\n"
        "m.build_parser, m._run = build, lambda args: 0\n"
        f"m.main(['design', '--tiles', '8x8', '--target', 'circle', '-o', {str(tmp_path / 'p.json')!r}])\n"
    )
    assert _printed(code) == ["True", "True", "True", "False"]


@pytest.mark.slow
def test_every_command_preloaded_loads_the_libraries_anyway():
    # the preload changes where they load, never what a command loads: each command's own modules load them
    # (coupon's none, so it is skipped); one fresh interpreter per command, all at once
    code = (
        "import sys\nfrom fabkiri.cli.main import PRELOAD, build_parser\nbuild_parser(sys.argv[1])\n"
        "print(all(m in sys.modules for m in PRELOAD), any(m in sys.modules for m in PRELOAD))"
    )
    runs = {
        name: subprocess.Popen(
            [sys.executable, "-c", code, name], stdout=subprocess.PIPE, text=True
        )
        for name in cli.SUMMARIES
    }
    for name, proc in runs.items():
        out, _ = proc.communicate()
        assert proc.returncode == 0, name
        skipped = name in cli.PRELOAD_SKIPS
        assert out.split() == (["False", "False"] if skipped else ["True", "True"]), name
    assert cli.preload_libraries("coupon") == [] and cli.preload_libraries(None) == []


def test_mechanics_contract_is_the_function_whichever_loads_first():
    # the lazy package keeps `mechanics.contract` the function, as its eager `from .contract import contract`
    # did, also once the submodule of that name is loaded (the import system sets it on the package)
    code = (
        "import sys\nimport fabkiri.mechanics as M\nfirst = M.contract\n"
        "import fabkiri.mechanics.contract\nfrom fabkiri.mechanics.contract import contract\n"
        "print(callable(first), first is M.contract is contract, 'fabkiri.mechanics.info' in sys.modules)"
    )
    assert _printed(code) == ["True", "True", "False"]
    code = (
        "from fabkiri.mechanics.contract import contract\nimport fabkiri.mechanics as M\n"
        "from fabkiri.mechanics import describe\nfrom fabkiri.mechanics.info import describe as d\n"
        "print(M.contract is contract, M.describe is describe is d, M.info.__name__)"
    )
    assert _printed(code) == ["True", "True", "fabkiri.mechanics.info"]


def test_a_design_loads_neither_the_verifier_nor_threadpoolctl(tmp_path):
    # issue #36: the closed states' overlap check reached the verifier's package (its pattern checks, the
    # deployment path and its drivers: ~25 modules a design never calls) through verify.geom; and with
    # OpenBLAS started on one thread by the CLI, the solver's threadpoolctl scan of every loaded library
    # had nothing to limit
    code = (
        "import sys\nfrom fabkiri.cli.main import main\n"
        f"main(['design', '--tiles', '4x4', '--target', 'circle', '--rigid', '--no-preview', '-o', "
        f"{str(tmp_path / 'p.json')!r}])\n"
        "print('\\n'.join(sys.modules))"
    )
    env = {k: v for k, v in os.environ.items() if k not in cli.BLAS_THREAD_VARS}
    mods = set(
        subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
        ).stdout.split()
    )
    assert (tmp_path / "p.json").exists()
    assert "fabkiri.pattern.overlap" in mods  # the overlap check ran
    assert not {m for m in mods if m == "fabkiri.verify" or m.startswith("fabkiri.verify.")}
    assert "fabkiri.mechanics.deploy" not in mods and "threadpoolctl" not in mods


def test_a_library_design_still_holds_blas_to_one_thread(monkeypatch):
    # no CLI start-up here (numpy was loaded first): the solver limits BLAS itself, and so it does where the
    # CLI's OPENBLAS_NUM_THREADS cannot reach (a BLAS other than OpenBLAS)
    from fabkiri import blas
    from fabkiri.design.quad.solve import single_thread_blas
    from threadpoolctl import threadpool_info, threadpool_limits

    def blas_threads() -> set[int]:
        return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}

    assert not blas.single_threaded()
    # the test processes run BLAS on one thread (tests/conftest.py): two here, so the limit has work to do
    with threadpool_limits(2, user_api="blas"):
        assert blas_threads() == {2}
        with single_thread_blas():
            assert blas_threads() == {1}
    monkeypatch.setattr(blas, "started_single", True)
    assert blas.single_threaded()
    monkeypatch.setattr(np.__config__, "CONFIG", {"Build Dependencies": {"blas": {"name": "mkl"}}})
    assert not blas.single_threaded()
