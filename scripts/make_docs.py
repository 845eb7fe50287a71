"""Regenerate the generated docs pages.

Usage::

    python scripts/make_docs.py [TOPIC ...]              # recompute and render (default: every topic)
    python scripts/make_docs.py --render-only [TOPIC ...]  # render from the committed data only (fast)

Topics are the ``*`` of ``scripts/docs_*.py``. Every topic has a template ``docs/templates/<topic>.md``: it is
computed by its generator's ``compute()`` (written to ``docs/data/<topic>.json``; figures are written by
``compute()`` too) and rendered by ``scripts/docs_render.py``. ``--render-only`` computes nothing.
"""
from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import docs_render  # noqa: E402


def generators() -> dict:
    """Topic name -> path of its ``scripts/docs_<topic>.py``."""
    return {p.stem[len("docs_"):]: p for p in sorted(HERE.glob("docs_*.py")) if p.stem != "docs_render"}


def load(topic: str, path: Path):
    spec = importlib.util.spec_from_file_location(f"docs_{topic}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def run(topic: str, path: Path) -> None:
    """Recompute *topic*: its data from ``compute()``, then its page."""
    docs_render.write_data(topic, load(topic, path).compute())
    docs_render.write(topic)


def main(argv=None) -> int:
    args = list(argv if argv is not None else sys.argv[1:])
    render_only = "--render-only" in args
    args = [a for a in args if a != "--render-only"]
    gens = generators()
    allowed = docs_render.topics() if render_only else list(gens)
    wanted = args or allowed
    unknown = [t for t in wanted if t not in allowed]
    if unknown:
        what = "topic with a template" if render_only else "topic"
        print(f"make_docs: unknown {what} {unknown[0]!r}; allowed: {', '.join(allowed)}", file=sys.stderr)
        return 2
    for topic in wanted:
        t0 = time.perf_counter()
        if render_only:
            path = docs_render.write(topic)
        else:
            run(topic, gens[topic])
            path = docs_render.page_path(topic)
        print(f"make_docs: {topic} -> {path.relative_to(HERE.parent)} ({time.perf_counter() - t0:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
