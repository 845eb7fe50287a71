"""JSON Schemas (draft 2020-12) of waveoptics' JSON outputs, shipped with the package: one file per output
(:data:`SCHEMAS`), with the shared definitions in ``_defs.schema.json``. docs/json.md lists their fields and units.

>>> from waveoptics.schemas import SCHEMAS
>>> sorted(SCHEMAS)[:2]
['brdf', 'compare']
"""
from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

__all__ = ["SCHEMAS", "schema", "validate"]

HERE = Path(__file__).resolve().parent

#: output → schema file
SCHEMAS = {
    "simulate_summary": "simulate_summary.schema.json",
    "scatter_summary": "scatter_summary.schema.json",
    "brdf": "brdf.schema.json",
    "surface_stats": "surface_stats.schema.json",
    "compare": "compare.schema.json",
    "cost": "cost.schema.json",
}


@lru_cache(maxsize=None)
def schema(name: str) -> dict:
    """The JSON Schema of output *name* (a key of :data:`SCHEMAS`)."""
    return json.loads((HERE / SCHEMAS[name]).read_text(encoding="utf-8"))


def validate(data, name: str) -> None:
    """Validate *data* against schema *name* with the ``jsonschema`` package (raises its ValidationError)."""
    import jsonschema
    from referencing import Registry, Resource

    resources = [(f"https://waveoptics.invalid/schemas/{p.name}", Resource.from_contents(json.loads(p.read_text())))
                 for p in HERE.glob("*.schema.json")]
    registry = Registry().with_resources(resources)
    jsonschema.Draft202012Validator(schema(name), registry=registry).validate(data)
