"""Entry point: argument parsing, error-to-exit-code mapping, one-line errors.

Exit codes: 0 ok, 1 a check, verification or solve failed its tolerance,
2 bad input or usage, 3 an internal error (a bug; set FABKIRI_DEBUG=1 for the
traceback). Each subcommand lives in its own module listed in ``COMMANDS`` and
exposes ``register(subparsers)``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from .. import __version__
from ..errors import FabkiriError

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
]


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, exit 2, no usage dump
        print(f"{self.prog}: error: {message} (see '{self.prog} --help')", file=sys.stderr)
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="fabkiri", description="Compact reconfigurable kirigami: design, verify, fabricate.")
    parser.add_argument("--version", action="version", version=f"fabkiri {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = args.func(args)
        return int(code or 0)
    except FabkiriError as exc:
        print(f"fabkiri: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except BrokenPipeError:  # e.g. `fabkiri verify p.json | head`: the reader left, say nothing more
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except KeyboardInterrupt:
        print("fabkiri: interrupted; nothing was written", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug: still one line unless asked
        if os.environ.get("FABKIRI_DEBUG"):
            raise
        print(f"fabkiri: internal error: {type(exc).__name__}: {exc} (FABKIRI_DEBUG=1 shows the traceback)",
              file=sys.stderr)
        return 3


def entry() -> None:
    sys.exit(main())


if __name__ == "__main__":
    entry()
