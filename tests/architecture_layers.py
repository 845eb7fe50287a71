"""The layers of the package, bottom to top: a module imports only from its own layer or below.

``tests/test_architecture.py`` enforces the order and ``scripts/docs_architecture.py`` draws docs/architecture.md
from this table and from the imports themselves.
"""
from __future__ import annotations

import ast
from pathlib import Path

__all__ = ["LAYERS", "layer_of", "waveoptics_imports"]

#: (layer name, modules or sub-packages of waveoptics in it), bottom first
LAYERS = (
    ("core", ("errors", "units", "vocabulary", "runtime", "io", "cache", "schemas")),
    ("materials", ("materials",)),
    ("colour", ("colour",)),
    ("surfaces", ("surfaces",)),
    ("scatter", ("scatter",)),
    ("brdf", ("brdf",)),
    ("request", ("request",)),
    ("jobs", ("simulate", "compare", "study", "bench", "renderers", "scatter_job")),
    ("planning", ("planning",)),
    ("distributed", ("distributed",)),
    ("interface", ("cli", "__main__", "")),
)


def layer_of(module: str) -> int | None:
    """Index in :data:`LAYERS` of a module named relative to the package (``"scatter.fft"``, ``""`` for the
    package itself); None for a name outside the table."""
    head = module.split(".")[0] if module else ""
    for i, (_, members) in enumerate(LAYERS):
        if head in members:
            return i
    return None


def waveoptics_imports(path: Path) -> list[tuple[str, int]]:
    """(module relative to the package, line) of every waveoptics import in the file *path* (inside functions
    too), with relative imports resolved; ``from . import x`` names ``x``."""
    path = Path(path)
    pkg_root = Path(__file__).resolve().parent.parent / "waveoptics"
    here = path.resolve().relative_to(pkg_root).with_suffix("").parts
    package = list(here[:-1])  # the package the file lives in (its own name for __init__ is dropped too)
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if not (node.module or "").startswith("waveoptics"):
                    continue
                base = (node.module or "").split(".")[1:]
            else:
                base = package[:len(package) - (node.level - 1)] + (node.module.split(".") if node.module else [])
            if node.module is None or (node.level == 0 and not base):  # "from . import x": x is a module
                out += [(".".join(base + [a.name]), node.lineno) for a in node.names]
            else:
                out.append((".".join(base), node.lineno))
        elif isinstance(node, ast.Import):
            out += [(".".join(a.name.split(".")[1:]), node.lineno) for a in node.names
                    if a.name.split(".")[0] == "waveoptics"]
    return out
