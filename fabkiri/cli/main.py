"""Entry point: argument parsing, error-to-exit-code mapping, one-line errors.

Exit codes: 0 ok, 1 a check, verification or solve failed its tolerance,
2 bad input or usage, 3 an internal error (a bug; set FABKIRI_DEBUG=1 for the
traceback). Each subcommand lives in its own module listed in ``COMMANDS`` and
exposes ``register(subparsers)``.

Start-up is lazy: ``SUMMARIES`` names each command's module and one-line help,
so ``fabkiri --help`` imports no command module and ``fabkiri CMD`` imports only
CMD's (the others get a stub parser with their help line). A command module
missing from ``SUMMARIES`` is imported as before (tests check the table against
what the modules register).
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib
import os
import re
import signal
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

from .. import __version__, blas
from ..errors import FabkiriError, InputError
from ..fileio import check_output_parent, inputs_scope, note_inputs, refuse_input, written

COMMANDS = [
    "fabkiri.cli.pattern_cmds",
    "fabkiri.cli.cut_cmd",
    "fabkiri.cli.verify_cmd",
    "fabkiri.cli.design_cmd",
    "fabkiri.cli.deploy_cmd",
    "fabkiri.cli.print_cmd",
    "fabkiri.cli.tolerance_cmd",
    "fabkiri.cli.coupon_cmd",
    "fabkiri.cli.report_cmd",
    "fabkiri.cli.sweep_cmd",
    "fabkiri.cli.view_cmd",
    "fabkiri.cli.make_cmd",
]
# command -> (module, help): what `fabkiri --help` and the dispatch need without importing the modules
# (importing all of them pulls in scipy, shapely, ezdxf, trimesh: most of a command's start-up)
SUMMARIES = {
    "new": (
        "fabkiri.cli.pattern_cmds",
        "write a standard pattern (rotating squares or kagome triangles) with both closed states",
    ),
    "import": (
        "fabkiri.cli.pattern_cmds",
        "import an OBJ design (and its contracted states), a .fold file or a PyKirigami model folder "
        "into pattern.json",
    ),
    "info": (
        "fabkiri.cli.pattern_cmds",
        "counts, residuals and closure of a pattern (.json or .obj)",
    ),
    "export": (
        "fabkiri.cli.pattern_cmds",
        "write a pattern as OBJ (one state), FOLD (all states) or a PyKirigami folder",
    ),
    "cut": (
        "fabkiri.cli.cut_cmd",
        "laser-cut files (DXF, SVG, PNG, manifest) for a pattern's closed state",
    ),
    "verify": (
        "fabkiri.cli.verify_cmd",
        "prove that a pattern (and its cut layout) closes into both compact states",
    ),
    "design": (
        "fabkiri.cli.design_cmd",
        "inverse design: a reconfigurable quad kirigami fitted to a target shape",
    ),
    "deploy": (
        "fabkiri.cli.deploy_cmd",
        "deployment path from closed state 1 to closed state 2: energy, plot, GIF",
    ),
    "print": (
        "fabkiri.cli.print_cmd",
        "3D-printable hinges/tiles of a closed state (STL, 3MF, STEP)",
    ),
    "tolerance": (
        "fabkiri.cli.tolerance_cmd",
        "Monte-Carlo of cut and hinge errors: closure gaps, overlaps, outline",
    ),
    "coupon": (
        "fabkiri.cli.coupon_cmd",
        "calibration coupon: laser (--material) or print (--printer) test pieces",
    ),
    "report": (
        "fabkiri.cli.report_cmd",
        "one self-contained HTML page: design vs target, states, deployment, "
        "cut and print files, assembly, bill of materials",
    ),
    "sweep": (
        "fabkiri.cli.sweep_cmd",
        "many designs from a sweep file (TOML axes) on a local or existing Dask cluster",
    ),
    "view": (
        "fabkiri.cli.view_cmd",
        "interactive deployment viewer (slider, play, colours, target): standalone HTML or served",
    ),
    "make": (
        "fabkiri.cli.make_cmd",
        "from a target outline to cut or print files in one go: design for the process, "
        "cut or print at the size, deploy, report",
    ),
}


# numpy subpackages no command uses but scipy's array-API shim imports (``from numpy import *`` in
# scipy._lib.array_api_compat.numpy): numpy.f2py alone pulls charset_normalizer, numpy.testing unittest, and
# numpy.polynomial is large; a share of every command's start-up. They are bound lazily instead: loaded
# on first attribute access. (Not numpy.random, which scipy._lib._util uses as it loads, nor numpy.ma, which
# every np.unique call asks.) The string and record-array modules, ctypeslib (it loads ctypes) and the
# numpy.core shim: the same, for less.
DEFERRED = (
    "numpy.f2py",
    "numpy.testing",
    "numpy.polynomial",
    "numpy.strings",
    "numpy.char",
    "numpy.rec",
    "numpy.ctypeslib",
    "numpy.core",
)


def defer_unused_numpy() -> list[str]:
    """Bind the ``DEFERRED`` subpackages as lazy modules (``importlib.util.LazyLoader``) before numpy's users
    load; a no-op once scipy is imported (a library caller's process). Returns the names it deferred."""
    if "scipy" in sys.modules:
        return []
    import importlib.util

    import numpy

    done = []
    for name in DEFERRED:
        spec = importlib.util.find_spec(name) if name not in sys.modules else None
        if spec is None or spec.loader is None:
            continue
        spec.loader = importlib.util.LazyLoader(spec.loader)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        setattr(
            numpy, name.rsplit(".", 1)[1], module
        )  # as an import binds it (numpy's __getattr__ would recurse)
        done.append(name)
    return done


# what every command's modules but coupon's load through a dozen nested imports, loaded first from `main`, at the
# foot of the call stack: CPython 3.11 keeps Python frames in fixed-size chunks and unmaps a chunk as soon as the
# frame at its start returns, and the docstring processing numpy.ma and scipy.linalg run as they load crossed a
# chunk's end there thousands of times in a design's process, an mmap, a page fault and an munmap each
# (docs/speed.md, "Session 55 (imp55)"). Loaded from here they run inside the first chunk, which stays.
# (scipy.sparse.csgraph loads scipy.sparse.linalg, and it scipy.linalg.)
PRELOAD = ("numpy.ma", "scipy.sparse.csgraph")
PRELOAD_SKIPS = ("coupon",)  # its module loads no numerics


def preload_libraries(command: str | None) -> list[str]:
    """Import ``PRELOAD`` for a command in ``SUMMARIES`` but ``PRELOAD_SKIPS`` (before its modules, which load
    the same); returns the names it imported. A no-op in a process that has them (a library caller's)."""
    if command not in SUMMARIES or command in PRELOAD_SKIPS:
        return []
    done = [name for name in PRELOAD if name not in sys.modules]
    for name in done:
        importlib.import_module(name)
    return done


# commands whose work is vector-sized BLAS (``design()`` already holds BLAS to one thread, see
# design/solve.single_thread_blas; a cut's linear algebra is sparse or a few hundred unknowns): OpenBLAS's thread
# pools (numpy's and scipy's) then only cost their start and their spinning workers, a measurable share of a
# small design's or cut's process and more wall time on a loaded box.
SINGLE_THREAD_BLAS = ("design", "cut")
BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")


def single_thread_blas_process(command: str | None) -> bool:
    """Start OpenBLAS with one thread (``OPENBLAS_NUM_THREADS=1``) for a command in ``SINGLE_THREAD_BLAS``.

    Only before numpy loads (the pool size is read once, when the library loads) and only when the user set
    none of ``BLAS_THREAD_VARS``; returns whether it set it. A no-op in a library caller's process."""
    if command not in SINGLE_THREAD_BLAS or "numpy" in sys.modules:
        return False
    if any(v in os.environ for v in BLAS_THREAD_VARS):
        return False
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    blas.started_single = True
    return True


@contextlib.contextmanager
def modules_frozen(fresh: bool):
    """Load a command's modules with the cyclic garbage collector off, then freeze what they made.

    Loading numpy, scipy and the command's modules allocates a few hundred thousand long-lived objects, and
    the collector walked them all again and again (measurable in a small design's process, most of it
    one full collection); frozen (``gc.freeze``), later collections skip them. Only in a ``fresh`` process
    (numpy not yet loaded): a library caller's heap is left alone."""
    if not fresh:
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.freeze()
        gc.enable()


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, exit 2, no usage dump
        print(f"{self.prog}: error: {message} (see '{self.prog} --help')", file=sys.stderr)
        raise SystemExit(2)


def _command(argv: Sequence[str]) -> str | None:
    """The subcommand named on the command line (the first word that is not a top-level option)."""
    return next((a for a in argv if not a.startswith("-")), None)


def build_parser(command: str | None = "") -> argparse.ArgumentParser:
    """The parser; with a ``command`` known to ``SUMMARIES`` only that command's module is imported.

    ``command=""`` (the default) imports every module, ``None`` none of those in ``SUMMARIES``.
    """
    parser = _Parser(
        prog="fabkiri", description="Compact reconfigurable kirigami: design, verify, fabricate."
    )
    parser.add_argument("--version", action="version", version=f"fabkiri {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    covered = {module for module, _ in SUMMARIES.values()}
    wanted = SUMMARIES[command][0] if command in SUMMARIES else (None if command is None else "*")
    stubs = []
    for module in COMMANDS:
        if module not in covered or wanted in ("*", module):
            importlib.import_module(module).register(sub)
        else:
            stubs += [name for name, (m, _) in SUMMARIES.items() if m == module]
    for name in stubs:  # never parsed: the command given is registered for real above
        sub.add_parser(name, help=SUMMARIES[name][1])
    return parser


def named_files(args: argparse.Namespace) -> list[str]:
    """Every existing file an argument other than the output names (``STATE:FILE`` included)."""
    out = []
    for key, value in vars(args).items():
        if key in ("output", "func", "command"):
            continue
        for v in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(v, str):
                out += [c for c in (v, re.sub(r"^\s*[12]\s*:", "", v)) if c and Path(c).is_file()]
    return out


def main(argv: Sequence[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    # numpy's RuntimeWarnings (and any library warning) never reach the user: real problems are
    # refused as one-line errors by the input checks; FABKIRI_DEBUG=1 shows them
    with warnings.catch_warnings(), inputs_scope():
        if not os.environ.get("FABKIRI_DEBUG"):
            warnings.simplefilter("ignore")
        command = _command(argv)
        fresh = command in SUMMARIES and "numpy" not in sys.modules
        if fresh:  # before the modules load: their long-lived blocks then sit below the kept ones
            from . import heap  # a command's module, not `fabkiri --help`'s

            heap.keep_freed_memory(command)
        with modules_frozen(fresh):
            if command in SUMMARIES:  # a command loads numpy; `fabkiri --help` does not
                single_thread_blas_process(command)
                defer_unused_numpy()
                preload_libraries(command)
            parser = build_parser(command)
        args = parser.parse_args(argv)
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    try:
        from .. import limits  # numpy: not for `fabkiri --help`

        files = named_files(args)
        for f in files:  # targets, layouts, presets: bounded before any reader sees them
            limits.check_file_size(f)
        note_inputs(*files)
        if isinstance(getattr(args, "output", None), str):
            if args.output == "-":  # a file named '-' is never what was meant
                raise InputError("-o -: fabkiri writes files, not standard output; give a name")
            refuse_input(args.output)
            check_output_parent(args.output)  # a read-only folder: refused before the work
        code = args.func(args)
        return int(code or 0)
    except FabkiriError as exc:
        print(f"fabkiri: error: {exc.cli_message()}", file=sys.stderr)
        return exc.exit_code
    except (
        BrokenPipeError
    ):  # e.g. `fabkiri verify p.json | head`: the reader left, say nothing more
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except KeyboardInterrupt:
        print(f"fabkiri: interrupted; {_on_disk()}", file=sys.stderr)
        return 130
    except (
        MemoryError
    ):  # past the up-front estimates (fabkiri.limits): still one line, nothing written
        print(
            "fabkiri: error: out of memory; try fewer tiles or a smaller input; nothing written",
            file=sys.stderr,
        )
        return 2
    except Exception as exc:  # a bug: still one line unless asked
        if os.environ.get("FABKIRI_DEBUG"):
            raise
        print(
            f"fabkiri: internal error: {type(exc).__name__}: {exc} (FABKIRI_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return 3


def _on_disk() -> str:
    """What an interrupted command left: the files it had put in place (each complete), or nothing."""
    done = written()
    if not done:
        return "nothing was written"
    return f"{', '.join(map(str, done))} written (complete), nothing else"


def _interrupted(signum, frame) -> None:
    raise KeyboardInterrupt  # as Ctrl-C: the writer undoes a half-done move and removes its scratch


def entry() -> None:
    """The ``fabkiri`` program: a kill (TERM, HUP) stops it as Ctrl-C does, with one line."""
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), _interrupted)
    try:
        code = main()
    except KeyboardInterrupt:  # during start-up, before a command runs
        print("fabkiri: interrupted; nothing was written", file=sys.stderr)
        code = 130
    sys.exit(code)


if __name__ == "__main__":
    entry()
