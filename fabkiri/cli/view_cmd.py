"""``fabkiri view``: the interactive deployment viewer as a standalone HTML page, or served on localhost."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import CheckFailed, InputError
from .argtypes import bounded, load_any

_steps = bounded(
    int,
    lambda v: 2 <= v <= 2000,
    "expected a whole number of steps",
    "steps must lie in 2..2000, got {v}",
)
_port = bounded(
    int, lambda v: 0 <= v <= 65535, "expected a port number", "a port lies in 0..65535, got {v}"
)


def cmd_view(args: argparse.Namespace) -> int:
    from ..api.view import serve_page, view_pattern
    from ..fileio import atomic_write, check_output_file

    if args.output is None and args.port is None:
        raise InputError("say where the viewer goes: -o FILE.html and/or --port N")
    if args.output is not None:
        if Path(args.output).suffix.lower() not in (".html", ".htm"):
            raise InputError(f"-o {args.output}: the viewer is an .html file")
        check_output_file(args.output)
    out = view_pattern(load_any(args.file), args.steps, cut=args.cut)
    d = out.deploy.path
    print(
        f"{d.kind} path, {d.n_frames} frames, {d.corners.shape[1]} tiles: "
        f"{len(out.page) / 1e6:.2f} MB page",
        file=sys.stderr,
    )
    for problem in out.problems:
        print(f"warning: {problem}", file=sys.stderr)
    if args.output is not None:
        atomic_write(args.output, out.page)
        print(f"wrote {args.output}", file=sys.stderr)
    if args.port is not None:
        try:
            serve_page(
                out.page,
                args.port,
                lambda url: print(f"serving {url} (Ctrl-C stops)", file=sys.stderr, flush=True),
            )
        except OSError as exc:
            raise InputError(f"--port {args.port}: cannot listen ({exc.strerror})") from None
        except KeyboardInterrupt:
            print("stopped", file=sys.stderr)
    if out.problems:  # drawn either way; a path with problems is never exit 0, as in deploy
        raise CheckFailed("; ".join(out.problems))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "view",
        help="interactive deployment viewer (slider, play, colours, target): standalone HTML or served",
    )
    p.add_argument("file", help="pattern (.json or design .obj)")
    p.add_argument("-o", "--output", metavar="FILE.html", help="write the standalone page here")
    p.add_argument(
        "--port",
        type=_port,
        metavar="N",
        help="serve the page on http://127.0.0.1:N/ (0: any free port)",
    )
    p.add_argument(
        "--cut",
        metavar="DIR",
        help="a fabkiri cut folder of this pattern: its assembly pieces on hover, its sheets at true scale",
    )
    p.add_argument(
        "--steps", type=_steps, default=40, metavar="N", help="deployment path steps (default 40)"
    )
    p.set_defaults(func=cmd_view)
