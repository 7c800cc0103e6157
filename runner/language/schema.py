"""The JSON Schema of the scenario language (for editors: `# yaml-language-server: $schema=...`)."""

from __future__ import annotations

import json

from runner.language.model import Scenario
from runner.language.model_base import SCHEMA_VERSION

SCHEMA_FILE = "runner/schema/scenario.schema.json"


def schema_document() -> dict:
    schema = Scenario.model_json_schema(by_alias=True, mode="validation")
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = f"physics-scenarios scenario, language version {SCHEMA_VERSION}"
    return schema


def schema_text() -> str:
    return json.dumps(schema_document(), indent=2, sort_keys=True) + "\n"
