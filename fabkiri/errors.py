"""One exception hierarchy for the whole package.

The CLI maps these to exit codes: :class:`CheckFailed` (a verification, closure
or solve that did not meet its tolerance) to 1, everything else to 2.

A message that names a parameter, or suggests a value for one, carries it as a
:class:`Param` among its parts: ``str(error)`` says it in the library's words
(``size=200``, the keyword a Python caller passes), :meth:`FabkiriError.cli_message`
in the command line's (``--size 200``), and :attr:`FabkiriError.params` holds the
suggestions as ``{name: value}``.
"""

from __future__ import annotations

from collections import namedtuple

# every command imports this module: no dataclasses or typing at run time (fabkiri --help stays cheap)
TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any


class _Named:
    """The value of a :class:`Param` that names the parameter alone (one object, also once unpickled)."""

    def __repr__(self) -> str:
        return "NAMED"

    def __reduce__(self) -> str:
        return "NAMED"


NAMED = _Named()


class Param(
    namedtuple("Param", "name value fmt shown flag cli_value", defaults=(NAMED, "", None, "", None))
):
    """A parameter named in a message, with the value it suggests (if any): an immutable record.

    ``value`` (a suggestion) is shown formatted by ``fmt``, a string quoted for a library caller;
    ``True`` is a switch (``--rigid`` on the command line). ``shown`` is the form of a value that is
    not a suggestion (``(rows, cols)``), ``flag`` the CLI's option where it is not ``--`` and the name
    with dashes, and ``cli_value`` the CLI's spelling of the value where it differs (``ROWSxCOLS``)."""

    __slots__ = ()
    name: str
    value: Any
    fmt: str
    shown: str | None
    flag: str
    cli_value: str | None

    def words(self, cli: bool = False) -> str:
        """``name=value`` (or ``name``) for a library caller; ``--flag value`` for the command line."""
        plain = self.value if isinstance(self.value, str) else format(self.value, self.fmt)
        if not cli:
            if self.shown is not None:
                return f"{self.name}={self.shown}"
            text = repr(self.value) if isinstance(self.value, str) else plain
            return self.name if self.value is NAMED else f"{self.name}={text}"
        flag = self.flag or "--" + self.name.replace("_", "-")
        if self.cli_value is not None:
            return f"{flag} {self.cli_value}"
        if self.shown is not None:
            return f"{flag} {self.shown}"
        return flag if self.value is NAMED or self.value is True else f"{flag} {plain}"


def _render(parts: tuple, cli: bool) -> str:
    return "".join(
        p.words(cli)
        if isinstance(p, Param)
        else (p.cli_message() if cli else str(p))
        if isinstance(p, FabkiriError)
        else str(p)
        for p in parts
    )


def cli_text(parts: tuple) -> str:
    """Message ``parts`` (strings and :class:`Param` s) in the command line's words."""
    return _render(parts, cli=True)


class FabkiriError(Exception):
    """Base of every error fabkiri raises on purpose.

    Built from one string as any exception, or from parts: strings, :class:`Param` s and other
    fabkiri errors (a cause quoted inside), joined in order."""

    exit_code = 2

    def __init__(self, *parts: Any):
        worded = any(isinstance(p, (Param, FabkiriError)) for p in parts)
        self.parts = parts if worded else ()
        super().__init__(*((_render(parts, cli=False),) if worded else parts))

    def cli_message(self) -> str:
        """The message in the command line's words: each parameter as its ``--flag``."""
        return _render(self.parts, cli=True) if self.parts else str(self)

    @property
    def params(self) -> dict[str, Any]:
        """The parameter values the message names (a suggestion, or the value at fault), by name; those
        named alone are left out."""
        found: dict[str, Any] = {}
        for p in self.parts:
            if isinstance(p, FabkiriError):
                found.update(p.params)
            elif isinstance(p, Param) and p.value is not NAMED:
                found[p.name] = p.value
        return found


class PatternError(FabkiriError):
    """A pattern (file or in-memory data) is malformed or inconsistent."""


class InputError(FabkiriError):
    """A parameter or a file given by the user is invalid."""


class SolveError(FabkiriError):
    """The inverse-design problem is ill-posed or impossible as stated."""


class VerifyError(FabkiriError):
    """The verifier could not read or interpret what it was given."""


class FabricationError(FabkiriError):
    """Fabrication parameters are inconsistent (kerf, sheet, materials, ...)."""


class CheckFailed(FabkiriError):
    """A measured check failed its tolerance; the input itself was fine."""

    exit_code = 1
