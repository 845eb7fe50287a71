"""The shared renderer of the generated docs pages: ``docs/templates/<topic>.md`` (Jinja2 prose) filled from
``docs/data/<topic>.json`` (the measurements that ``scripts/docs_<topic>.py`` ``compute()`` wrote).

Rendering reads only those two files, so a sentence is fixed by editing the template and running
``python scripts/make_docs.py --render-only TOPIC`` (milliseconds); ``python scripts/make_docs.py TOPIC`` recomputes
the data first (the expensive part). ``tests/test_generated_docs.py`` renders every page that has a template from
the committed data and fails if it differs from the committed page.

Template conventions: StrictUndefined (a missing number is an error, never an empty string), trailing newline
kept, ``trim_blocks``/``lstrip_blocks`` (a line holding only a ``{% ... %}`` tag leaves nothing behind). The data's
top-level keys are the template's variables. Filters:

* ``x | fmt(".3g")`` — ``format(x, spec)``; ``None`` renders as ``—``.
* ``x | pct(".0f")`` — ``100·x`` formatted, followed by ``" %"``.
* ``s | cell`` — text made safe for a markdown table cell (``|`` escaped, newlines to spaces).
* ``s | code`` — ``s`` in backticks.
* ``rows | table(header)`` — a markdown table (header row, ``|---|`` rule, one line per row of cells; no trailing
  newline); cells are written as ``str(cell)``.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import jinja2

ROOT = Path(__file__).resolve().parent.parent
TEMPLATES = ROOT / "docs" / "templates"
DATA = ROOT / "docs" / "data"
DOCS = ROOT / "docs"

#: topic (the ``*`` of ``scripts/docs_*.py``) -> page name under docs/, where they differ
PAGES = {"accuracy_cost": "accuracy-cost", "cost_defaults": "cost-defaults", "materials": "materials-fresnel",
         "measured": "measured-surfaces", "thin_films": "thin-films", "two_scale": "two-scale",
         "validity_map": "validity-map", "wave_optics": "wave-optics"}


def page_path(topic: str) -> Path:
    """The generated page of *topic*: ``docs/<page>.md``."""
    return DOCS / f"{PAGES.get(topic, topic)}.md"


def data_path(topic: str) -> Path:
    return DATA / f"{topic}.json"


def template_path(topic: str) -> Path:
    return TEMPLATES / f"{topic}.md"


def topics() -> list[str]:
    """Every topic that has a template (and so is rendered from data)."""
    return sorted(p.stem for p in TEMPLATES.glob("*.md") if not p.stem.startswith("_"))


def _fmt(value, spec: str = "") -> str:
    return "—" if value is None else format(value, spec)


def _pct(value, spec: str = ".0f") -> str:
    return f"{format(100 * value, spec)} %"


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _code(text) -> str:
    return f"`{text}`"


def _table(rows, header) -> str:
    lines = ["| " + " | ".join(map(str, header)) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    return "\n".join(lines)


def environment() -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(TEMPLATES), undefined=jinja2.StrictUndefined,
                             keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True, autoescape=False)
    env.filters.update(fmt=_fmt, pct=_pct, cell=_cell, code=_code, table=_table)
    return env


def _jsonable(obj):
    """Plain JSON values: numpy scalars and arrays, tuples; a NaN or infinity is an error naming its place."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if hasattr(obj, "tolist"):          # numpy scalar or array
        return _jsonable(obj.tolist())
    if isinstance(obj, float) and not math.isfinite(obj):
        raise ValueError(f"non-finite number {obj} in docs data")
    return obj


def dumps(data: dict) -> str:
    """The JSON text of *data* as it is committed: sorted keys, 1-space indent, UTF-8, floats as Python's shortest
    round-trip repr (so the same numbers always give the same text), a final newline."""
    return json.dumps(_jsonable(data), sort_keys=True, indent=1, ensure_ascii=False, allow_nan=False) + "\n"


def write_data(topic: str, data: dict) -> Path:
    path = data_path(topic)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(dumps(data), encoding="utf-8")
    return path


def load_data(topic: str) -> dict:
    return json.loads(data_path(topic).read_text(encoding="utf-8"))


def render(topic: str, data: dict | None = None) -> str:
    """The page text of *topic*: its template filled from *data* (default: the committed docs/data/<topic>.json)."""
    data = load_data(topic) if data is None else json.loads(dumps(data))
    return environment().get_template(f"{topic}.md").render(topic=topic, **data)


def write(topic: str, data: dict | None = None) -> Path:
    """Render *topic* and write its page under docs/."""
    path = page_path(topic)
    path.write_text(render(topic, data), encoding="utf-8")
    return path
