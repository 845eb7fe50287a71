"""``waveoptics materials [QUERY]``: list presets or search the refractiveindex.info catalogue."""
from __future__ import annotations


from ._common import add_common, emit


def register(sub):
    p = sub.add_parser("materials", help="list material presets or search the optical-constants database",
                       description="Without QUERY: the named presets with their data sets, F0 at 550 nm and "
                                   "category. With QUERY: matching refractiveindex.info pages, usable as "
                                   "--material shelf/book/page.")
    p.add_argument("query", nargs="?", help="search words, e.g. 'gold' or 'TiO2'")
    p.add_argument("--limit", type=int, default=30, help="maximum number of search results (default 30)")
    add_common(p)
    p.set_defaults(func=run)


def run(args):

    from .. import materials
    import numpy as np

    if args.limit < 1:
        raise ValueError(f"--limit {args.limit} is not allowed; give a number of results >= 1")
    if args.query:
        hits, total = materials.search(args.query, limit=args.limit, with_total=True)
        if not hits:
            raise ValueError(f"no material matches {args.query!r}; try a chemical formula such as Au or SiO2")
        text = "\n".join(f"{h['spec']:<45} {h['name']}" for h in hits)
        if total > len(hits):
            text += f"\n(showing {len(hits)} of {total} matches; --limit {total} shows all)"
        emit(args, {"query": args.query, "matches": hits, "total_matches": total}, text)
        return 0
    rows = []
    for name, p in materials.PRESETS.items():
        m = materials.get_material(name)
        rows.append({"name": name, "aliases": list(p.aliases), "category": p.category,
                     "spec": f"{p.shelf}/{p.book}/{p.page}", "source": p.description,
                     "range_nm": list(m.wavelength_range_nm), "f0_550nm": float(m.F0(np.array(550.0)))})
    text = "\n".join(f"{r['name']:<14} {r['category']:<13} F0(550nm)={r['f0_550nm']:.3f}  {r['source']}"
                     for r in rows)
    text += ("\nthin-film stacks: SUBSTRATE|FILM:THICKNESS|... (films from the substrate outwards), e.g. "
             "'Al|Al2O3:120nm' (docs/thin-films.md)")
    emit(args, {"presets": rows}, text)
    return 0
