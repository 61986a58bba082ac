"""How a refused ``cut`` or ``print`` was asked for, so that its checked options print as lines that run."""

from __future__ import annotations

import argparse
import contextlib

from ..api.advice import Ask, Refused


@contextlib.contextmanager
def options_on_stdout():
    """A refusal's checked options on stdout, one runnable line each (the error stays one line on stderr)."""
    try:
        yield
    except Refused as exc:
        print("\n".join(exc.option_lines()))
        raise


def kept_flags(args: argparse.Namespace, spec) -> tuple[str, ...]:
    """The command-line words of the options in ``spec`` that differ from their defaults."""
    out: list[str] = []
    for dest, flag, default in spec:
        v = getattr(args, dest, None)
        if v is None or v is False or v == default:
            continue
        for x in v if isinstance(v, list) else [v]:
            out += [flag] if x is True else [flag, f"{x:g}" if isinstance(x, float) else str(x)]
    return tuple(out)


def asked(args: argparse.Namespace, flags, process_flags, given: str | None) -> Ask:
    """How the command was given: its file and output, the options of ``flags`` kept in every
    suggestion and those of ``process_flags`` (the material's or printer's overrides) kept only for
    ``given``, the material or printer as typed; each a (dest, flag, default) spec."""
    return Ask(
        file=args.file,
        output=args.output,
        flags=kept_flags(args, flags),
        process_flags=kept_flags(args, process_flags),
        given=given,
    )
