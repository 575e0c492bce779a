"""JSON-Schema validation with errors that name the file and the JSON path of the field."""
from __future__ import annotations

from functools import lru_cache
from typing import Any, Optional

from robodesign.core.errors import InputError, describe_value
from robodesign.core.jsonio import load_json
from robodesign.core.paths import schemas_dir


@lru_cache(maxsize=None)
def _validator(name: str):
    import jsonschema
    path = schemas_dir() / f"{name}.schema.json"
    schema = load_json(path)
    cls = jsonschema.validators.validator_for(schema)
    return cls(schema)


def load_schema(name: str) -> dict:
    """The JSON Schema ``schemas/<name>.schema.json`` (a fresh copy, free to extend)."""
    return load_json(schemas_dir() / f"{name}.schema.json")


@lru_cache(maxsize=32)
def _validator_of(text: str):
    import json

    import jsonschema
    schema = json.loads(text)
    return jsonschema.validators.validator_for(schema)(schema)


def validate(instance: Any, schema_name: str, file: str, schema: Optional[dict] = None) -> None:
    """Raise :class:`InputError` for the most specific schema violation, if any. ``schema``: validate against
    this schema (e.g. ``schema_name``'s extended by plugins) instead of the file's."""
    if schema is None:
        v = _validator(schema_name)
    else:
        import json
        v = _validator_of(json.dumps(schema, sort_keys=True))
    errors = sorted(v.iter_errors(instance), key=lambda e: (-len(e.absolute_path), str(e.message)))
    if not errors:
        return
    import jsonschema
    best = jsonschema.exceptions.best_match(errors) or errors[0]
    # Prefer the deepest error path: it names the offending field most precisely.
    deepest = max(errors, key=lambda e: len(e.absolute_path))
    if len(deepest.absolute_path) > len(best.absolute_path):
        best = deepest
    msg = _friendly(best)
    raise InputError(msg, file=file, path=list(best.absolute_path))


def _friendly(err) -> str:
    v = err.validator
    if v == "type":
        exp = err.validator_value
        exp = " or ".join(exp) if isinstance(exp, list) else exp
        article = "an" if str(exp)[0] in "aeiou" else "a"
        return f"expected {article} {exp}, got {describe_value(err.instance)}"
    if v == "additionalProperties":
        return f"unknown key(s): {err.message.split('(')[-1].rstrip(')')}" if "(" in err.message else err.message
    if v == "required":
        return err.message.replace("is a required property", "is required but missing")
    if v == "enum":
        return f"{describe_value(err.instance)} is not one of {err.validator_value}"
    return err.message
