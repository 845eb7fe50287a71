"""Generated docs pages are current.

Every page that has a template (docs/templates/<topic>.md) is rendered from its committed data
(docs/data/<topic>.json) by scripts/docs_render.py and must equal the committed page: a page edited by hand, or a
template edited without re-rendering, fails here. Rendering computes nothing, so this is fast. The reference pages
(cli, json) are cheap to compute as well: their data must also equal what the parsers and the JSON Schemas give now.
"""
import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))

import docs_render  # noqa: E402

TOPICS = docs_render.topics()


def _generator(topic):
    spec = importlib.util.spec_from_file_location(f"docs_{topic}", ROOT / "scripts" / f"docs_{topic}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_reference_pages_have_templates():
    assert {"cli", "json"} <= set(TOPICS)


def test_every_generator_is_data_and_template():
    """Every scripts/docs_<topic>.py has a template and committed data, and defines compute() (make_docs calls it)."""
    gens = {p.stem[len("docs_"):]: p for p in (ROOT / "scripts").glob("docs_*.py") if p.stem != "docs_render"}
    assert set(gens) == set(TOPICS)
    for topic, path in gens.items():
        assert docs_render.data_path(topic).exists(), topic
        assert "\ndef compute(" in path.read_text(encoding="utf-8"), f"{path.name} has no compute()"


@pytest.mark.parametrize("topic", TOPICS)
def test_page_renders_from_committed_data(topic):
    page = docs_render.page_path(topic)
    assert page.read_text(encoding="utf-8") == docs_render.render(topic), \
        f"{page.relative_to(ROOT)} is not its template rendered from docs/data/{topic}.json: " \
        f"run python scripts/make_docs.py --render-only {topic}"


@pytest.mark.parametrize("topic", TOPICS)
def test_data_is_canonical_json(topic):
    """Committed data is written as docs_render.dumps writes it (sorted keys, stable floats), so a recompute that
    finds the same numbers leaves the file unchanged."""
    text = docs_render.data_path(topic).read_text(encoding="utf-8")
    assert text == docs_render.dumps(json.loads(text)), f"run python scripts/make_docs.py {topic}"


@pytest.mark.parametrize("topic", ["cli", "json"])
def test_reference_data_is_current(topic):
    assert docs_render.load_data(topic) == json.loads(docs_render.dumps(_generator(topic).compute())), \
        f"run python scripts/make_docs.py {topic}"


def test_template_missing_value_is_an_error(tmp_path, monkeypatch):
    monkeypatch.setattr(docs_render, "TEMPLATES", tmp_path)
    monkeypatch.setattr(docs_render, "DATA", tmp_path)
    (tmp_path / "t.md").write_text("{{ x | fmt('.2f') }} and {{ y }}\n")
    (tmp_path / "t.json").write_text('{"x": 1.234}\n')
    with pytest.raises(Exception, match="'y' is undefined"):
        docs_render.render("t")
    assert docs_render.render("t", {"x": 1.234, "y": "z"}) == "1.23 and z\n"


def test_filters():
    env = docs_render.environment()
    out = env.from_string("{{ 0.123 | pct('.1f') }}|{{ none | fmt('.2g') }}|{{ 'a|b' | cell }}|"
                          "{{ [[1, 'x'], [2, 'y']] | table(['n', 's']) }}").render()
    assert out == "12.3 %|—|a\\|b|| n | s |\n|---|---|\n| 1 | x |\n| 2 | y |"
