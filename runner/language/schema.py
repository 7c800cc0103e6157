"""The JSON Schema of the scenario language (for editors: `# yaml-language-server: $schema=...`).

Generated from the pydantic models, then made to say what the loader accepts rather than what the models
see after loading:

* strict JSON: no ``Infinity``/``NaN`` (``mu``'s default ``inf`` is written as the string ``"inf"``, which
  the loader reads as infinity, and ``"inf"`` is accepted wherever such a default is);
* ``"${name}"`` (a whole parameter) wherever a number, a boolean or a fixed word is expected, since the
  loader substitutes parameters before validating (a string field accepts them anyway);
* times as numbers or expressions (the models' own schema for them, see runner.language.model_base).
"""

from __future__ import annotations

import json
import math
from typing import Any

from runner.language.model import Scenario
from runner.language.model_base import SCHEMA_VERSION

SCHEMA_FILE = "runner/schema/scenario.schema.json"
PARAM_DEF = "Param"
PARAM_SCHEMA = {
    "type": "string",
    "pattern": r"\$\{[A-Za-z_][A-Za-z0-9_]*\}",
    "description": "Text with a parameter, `${name}` (e.g. `${h}` or `-${v}`): params.name's value is put in "
    "its place when the scenario is loaded, then the result is read as the field's value.",
}
_META = ("title", "description", "default", "examples")
_SCALAR_TYPES = ("number", "integer", "boolean")


def _strict_number(node: dict[str, Any]) -> dict[str, Any]:
    """A schema whose default is infinite: the default becomes "inf", and "inf" is accepted."""
    default = node.get("default")
    if not (isinstance(default, float) and math.isinf(default)):
        return node
    word = "inf" if default > 0 else "-inf"
    inner = {k: v for k, v in node.items() if k not in _META}
    outer = {k: v for k, v in node.items() if k in _META}
    outer["default"] = word
    outer["anyOf"] = [inner, {"const": word}, {"$ref": f"#/$defs/{PARAM_DEF}"}]
    return outer


def _with_params(node: dict[str, Any]) -> dict[str, Any]:
    """A scalar schema that also accepts a whole `${param}`."""
    scalar = node.get("type") in _SCALAR_TYPES or "enum" in node or "const" in node
    if not scalar:
        return node
    inner = {k: v for k, v in node.items() if k not in _META}
    outer = {k: v for k, v in node.items() if k in _META}
    outer["anyOf"] = [inner, {"$ref": f"#/$defs/{PARAM_DEF}"}]
    return outer


def _rewrite(node: Any) -> Any:
    if isinstance(node, list):
        return [_rewrite(item) for item in node]
    if not isinstance(node, dict):
        return node
    node = {k: (v if k in ("default", "examples", "const", "enum") else _rewrite(v)) for k, v in node.items()}
    node = _strict_number(node)
    if "anyOf" in node and not any(k in node for k in ("type", "enum", "const")):
        return node  # the alternatives were each rewritten
    return _with_params(node)


def schema_document() -> dict[str, Any]:
    schema = Scenario.model_json_schema(by_alias=True, mode="validation")
    defs = {name: _rewrite(d) for name, d in schema.pop("$defs", {}).items()}
    schema = _rewrite(schema)
    defs[PARAM_DEF] = PARAM_SCHEMA
    schema["$defs"] = defs
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = f"physics-scenarios scenario, language version {SCHEMA_VERSION}"
    return schema


def schema_text() -> str:
    return json.dumps(schema_document(), indent=2, sort_keys=True, allow_nan=False) + "\n"
