"""Data of docs/json.md (docs/data/json.json; prose in docs/templates/json.md): the JSON outputs of waveoptics, their
fields, types and units, from the shipped JSON Schemas (waveoptics/schemas; tests/test_json_schema.py validates real
outputs against them, tests/test_generated_docs.py checks that the data and the page are current)."""
from __future__ import annotations

import sys
from pathlib import Path

from waveoptics.schemas import SCHEMAS, schema

sys.path.insert(0, str(Path(__file__).resolve().parent))


def _type(spec: dict) -> str:
    if "$ref" in spec:
        return spec["$ref"].split("/")[-1].replace("_", " ")
    if "oneOf" in spec:
        return " or ".join(_type(s) for s in spec["oneOf"])
    t = spec.get("type", "")
    t = "/".join(t) if isinstance(t, list) else t
    if t == "array" and "items" in spec:
        t = f"array of {_type(spec['items'])}"
    if "enum" in spec:
        t += " (" + ", ".join(map(str, spec["enum"])) + ")"
    return t


def compute() -> dict:
    """Every schema in the order of ``SCHEMAS``, with its properties in the schema's own order."""
    out = []
    for name, fname in SCHEMAS.items():
        sch = schema(name)
        req = set(sch.get("required", []))
        out.append({"name": name, "file": fname, "title": sch["title"], "description": sch.get("description", ""),
                    "properties": [{"key": key, "type": _type(spec), "required": key in req,
                                    "description": spec.get("description", "")}
                                   for key, spec in sch.get("properties", {}).items()]})
    return {"schemas": out}


def main() -> None:
    import make_docs

    make_docs.main(["json"])


if __name__ == "__main__":
    main()
