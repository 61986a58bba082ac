"""One exception hierarchy for the whole package.

The CLI maps these to exit codes: :class:`CheckFailed` (a verification, closure
or solve that did not meet its tolerance) to 1, everything else to 2.
"""

from __future__ import annotations


class FabkiriError(Exception):
    """Base of every error fabkiri raises on purpose."""

    exit_code = 2


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
