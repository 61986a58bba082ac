"""``json.dumps(value, indent=2, sort_keys=True)``, the same text, for the plain JSON values a pattern file
stores (dicts with string keys, lists, strings, numbers, booleans, None).

With ``indent`` the standard library encodes in Python, one generator step per value; a design's stored
target is thousands of coordinates, each on a line of its own, and that was most of writing its
``pattern.json``. A list of numbers (or of lists of numbers) is encoded here by the C encoder in one call
and laid out on its lines by string replacement; everything else takes the same layout rules in Python.
"""

from __future__ import annotations

import json
from json.encoder import encode_basestring_ascii
from typing import Any

_COMPACT = json.JSONEncoder(separators=(", ", ": "))
# a letter of true, false, null, NaN or Infinity, a string's quote, an object's brace: not a list of numbers
_NOT_NUMBERS = ('"', "{", "a", "n", "u", "N")
_INF = float("inf")


class _Unplain(Exception):
    """A value the shortcut does not lay out (a key that is not a string): the standard library's turn."""


def indented(value: Any) -> str:
    """``json.dumps(value, indent=2, sort_keys=True)``."""
    out: list[str] = []
    try:
        _put(value, "\n", out)
    except _Unplain:
        return json.dumps(value, indent=2, sort_keys=True)
    return "".join(out)


def _put(v: Any, nl: str, out: list[str]) -> None:
    """``v`` at the line break and indentation ``nl`` of its parent, checked in the standard library's order."""
    if isinstance(v, str):
        out.append(encode_basestring_ascii(v))
    elif v is None:
        out.append("null")
    elif v is True:
        out.append("true")
    elif v is False:
        out.append("false")
    elif isinstance(v, int):
        out.append(int.__repr__(v))
    elif isinstance(v, float):
        out.append(_float(v))
    elif isinstance(v, (list, tuple)):
        _put_list(v, nl, out)
    elif isinstance(v, dict):
        _put_dict(v, nl, out)
    else:
        raise TypeError(f"Object of type {type(v).__name__} is not JSON serializable")


def _float(v: float) -> str:
    if v != v:
        return "NaN"
    if v in (_INF, -_INF):
        return "Infinity" if v > 0 else "-Infinity"
    return float.__repr__(v)


def _put_list(v: list | tuple, nl: str, out: list[str]) -> None:
    if not v:
        out.append("[]")
        return
    inner = nl + "  "
    numbers = _numbers(v, nl, inner)
    if numbers is not None:
        out.append(numbers)
        return
    out.append("[")
    for i, x in enumerate(v):
        out.append(("," if i else "") + inner)
        _put(x, inner, out)
    out.append(nl + "]")


def _put_dict(v: dict, nl: str, out: list[str]) -> None:
    if not v:
        out.append("{}")
        return
    if not all(isinstance(k, str) for k in v):
        raise _Unplain
    inner = nl + "  "
    out.append("{")
    for i, k in enumerate(sorted(v)):
        out.append(("," if i else "") + inner + encode_basestring_ascii(k) + ": ")
        _put(v[k], inner, out)
    out.append(nl + "}")


def _numbers(v: list | tuple, nl: str, inner: str) -> str | None:
    """A non-empty list of numbers, or of non-empty lists of numbers, laid out; None for any other list."""
    if isinstance(v[0], (str, dict)):  # (not worth encoding to find out)
        return None
    text = _COMPACT.encode(v)
    if any(c in text for c in _NOT_NUMBERS) or "[]" in text:
        return None
    body = text[1:-1]
    if "[" not in body:
        return "[" + inner + body.replace(", ", "," + inner) + nl + "]"
    # lists of numbers only: "[..], [..], ..., [..]", each opening bracket after the first one "], ["
    if not (body[0] == "[" and body[-1] == "]") or "[[" in body or "]]" in body:
        return None
    if body.count("[") != body.count("], [") + 1:
        return None
    deeper = inner + "  "
    rows = body[1:-1].replace("], [", "\0").replace(", ", "," + deeper)
    rows = rows.replace("\0", inner + "]," + inner + "[" + deeper)
    return "[" + inner + "[" + deeper + rows + inner + "]" + nl + "]"
