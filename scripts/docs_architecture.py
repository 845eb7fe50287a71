"""Data of docs/architecture.md (docs/data/architecture.json; prose in docs/templates/architecture.md) and
docs/img/architecture.png, from the package itself: the layer table of tests/architecture_layers.py (the
architecture is test data), each module's first docstring sentence (where each physical idea lives) and the imports
between sub-packages (read from the code, not typed by hand).

Run:  python scripts/make_docs.py architecture
"""
from __future__ import annotations

import ast
import collections
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import waveoptics  # noqa: E402

PKG = Path(waveoptics.__file__).resolve().parent
ROOT = PKG.parent
sys.path.insert(0, str(ROOT / "tests"))
from architecture_layers import LAYERS, waveoptics_imports  # noqa: E402
IMG = ROOT / "docs" / "img" / "architecture.png"


def _name(p: Path) -> str:
    parts = p.relative_to(PKG).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


#: a full stop followed by a space ends a sentence, except after an abbreviation ("Yan et al. 2018", "e.g. x")
_SENTENCE_END = re.compile(r"(?<!\bet al)(?<!\be\.g)(?<!\bi\.e)(?<!\bcf)\. ")


def _first_line(p: Path) -> str:
    """The first sentence of the module docstring's first paragraph."""
    doc = ast.get_docstring(ast.parse(p.read_text())) or ""
    para = doc.strip().split("\n\n")[0].replace("\n", " ")
    return _SENTENCE_END.split(para, maxsplit=1)[0].rstrip(".") + "." if para else ""


def _unit(module: str) -> str:
    """The sub-package (or top-level module) a module belongs to."""
    return module.split(".")[0] or "waveoptics"


def modules():
    return sorted((p for p in PKG.rglob("*.py")), key=_name)


def edges() -> dict:
    """{(from unit, to unit): number of import statements}, between different units."""
    count = collections.Counter()
    for p in modules():
        src = _unit(_name(p))
        for target, _ in waveoptics_imports(p):
            dst = _unit(target)
            if dst != src and src not in ("cli", "waveoptics", "__main__"):
                count[(src, dst)] += 1
    return count


def figure(count: dict) -> None:
    units = [(i, m) for i, (_, members) in enumerate(LAYERS) for m in members
             if m and m not in ("kernels", "__main__", "architecture")]
    row = collections.defaultdict(list)
    for i, m in units:
        row[i].append(m)
    pos = {}
    for i, ms in row.items():
        shift = 0.0 if len(ms) > 1 else (1.3 if i % 2 else -1.3)  # zig-zag single members: edges stay apart
        for j, m in enumerate(ms):
            pos[m] = ((j - (len(ms) - 1) / 2) * 1.6 + shift, i)
    core = set(LAYERS[0][1])
    fig, ax = plt.subplots(figsize=(9, 8))
    for (a, b), n in count.items():
        if a in pos and b in pos and b not in core:
            (x0, y0), (x1, y1) = pos[a], pos[b]
            ax.annotate("", xy=(x1, y1 + 0.18), xytext=(x0, y0 - 0.18),
                        arrowprops=dict(arrowstyle="->", color="0.55", lw=0.6 + 0.15 * min(n, 10),
                                        shrinkA=4, shrinkB=4, connectionstyle="arc3,rad=0.08"))
    for m, (x, y) in pos.items():
        ax.text(x, y, m, ha="center", va="center", fontsize=10,
                bbox=dict(boxstyle="round,pad=0.35", fc="#e8f0fb", ec="#3b6ea8"))
    for i, (name, _) in enumerate(LAYERS):
        ax.text(-5.2, i, name, ha="left", va="center", fontsize=9, color="0.35", style="italic")
    ax.set_xlim(-5.4, 4.6)
    ax.set_ylim(-0.7, len(LAYERS) - 0.3)
    ax.axis("off")
    ax.set_title("waveoptics: layers (bottom to top) and the imports between them\n"
                 "(arrow: 'imports from', width ~ number of import statements; every layer also uses core; from the code)", fontsize=10)
    fig.tight_layout()
    IMG.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(IMG, dpi=110)
    plt.close(fig)


def layers(count: dict) -> list:
    """One row per layer of tests/architecture_layers.py: its name, its members and the units it imports from."""
    return [{"name": name, "members": [m or "waveoptics" for m in members],
             "imports": sorted({b for (a, b), _ in count.items() if a in members and b not in members})}
            for name, members in LAYERS]


def compute() -> dict:
    """The layer table, each module's first docstring sentence (``cli.*`` sub-command modules left out) and the
    figure."""
    count = edges()
    figure(count)
    mods = [{"name": "waveoptics" + ("." + _name(p) if _name(p) else ""), "doc": _first_line(p)} for p in modules()
            if not (_name(p).startswith("cli.") and _name(p) != "cli")]
    return {"layers": layers(count), "modules": mods}


def main() -> None:
    import make_docs

    make_docs.main(["architecture"])


if __name__ == "__main__":
    main()
