"""JSON Schemas shipped in the package (pattern.json, material and printer presets) and one
validator that turns the first problem into a short ``where: what`` sentence."""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from typing import Any


@cache
def load_schema(package: str, name: str) -> dict[str, Any]:
    """The schema ``name`` shipped in ``package`` (e.g. ``fabkiri.exchange``, ``pattern.schema.json``)."""
    return json.loads(resources.files(package).joinpath(name).read_text("utf-8"))


def short(value: Any, limit: int = 60) -> str:
    text = json.dumps(value) if not isinstance(value, str) else repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _what(err) -> str:
    v, val, inst = err.validator, err.validator_value, err.instance
    if v in ("required", "additionalProperties", "enum", "const"):
        return err.message
    if v == "exclusiveMinimum" and val == 0:
        return f"must be positive, got {short(inst)}"
    if v in ("minimum", "maximum", "exclusiveMaximum", "exclusiveMinimum"):
        sign = {"minimum": ">=", "maximum": "<=", "exclusiveMaximum": "<", "exclusiveMinimum": ">"}[
            v
        ]
        return f"must be {sign} {val:g}, got {short(inst)}"
    if v == "type":
        return f"must be of type {val}, got {short(inst)}"
    return f"{short(inst)} fails '{v}' ({short(val, 40)})"


def schema_problem(data: Any, schema: dict[str, Any]) -> str | None:
    """The most relevant schema violation of ``data`` as one sentence, or None."""
    from jsonschema import Draft202012Validator
    from jsonschema.exceptions import best_match

    err = best_match(Draft202012Validator(schema).iter_errors(data))
    if err is None:
        return None
    where = "/".join(str(p) for p in err.absolute_path) or "top level"
    return f"{where}: {_what(err)}"[:300]
