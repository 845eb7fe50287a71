"""Regenerate every generated docs page: runs ``main()`` of each ``scripts/docs_*.py`` (or only those named).

Usage: ``python scripts/make_docs.py [TOPIC ...]`` (topics are the ``*`` of ``docs_*.py``).
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def generators() -> dict:
    """Topic name -> path of its ``scripts/docs_<topic>.py``."""
    return {p.stem[len("docs_"):]: p for p in sorted(HERE.glob("docs_*.py"))}


def run(topic: str, path: Path) -> None:
    spec = importlib.util.spec_from_file_location(f"docs_{topic}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.main()


def main(argv=None) -> int:
    gens = generators()
    wanted = list(argv if argv is not None else sys.argv[1:]) or list(gens)
    unknown = [t for t in wanted if t not in gens]
    if unknown:
        print(f"make_docs: unknown topic {unknown[0]!r}; allowed: {', '.join(gens)}", file=sys.stderr)
        return 2
    for topic in wanted:
        run(topic, gens[topic])
    return 0


if __name__ == "__main__":
    sys.exit(main())
