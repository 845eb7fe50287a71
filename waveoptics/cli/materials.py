"""``waveoptics materials [QUERY]``: list presets or search the refractiveindex.info catalogue."""
from __future__ import annotations


from ._common import add_common, emit


def register(sub):
    p = sub.add_parser("materials", help="list material presets or search the optical-constants database",
                       description="Without QUERY: the named presets with their data sets, F0 at 550 nm and "
                                   "category. With QUERY: matching refractiveindex.info pages, usable as "
                                   "--material shelf/book/page.")
    p.add_argument("query", nargs="?", help="search words, e.g. 'gold' or 'TiO2'; or a thin-film stack "
                                            "SUBSTRATE|FILM:THICKNESS|..., e.g. 'Al|Al2O3:120nm', to describe it")
    p.add_argument("--limit", type=int, default=30, help="maximum number of search results (default 30)")
    add_common(p)
    p.set_defaults(func=run)


def run(args):

    from .. import materials
    import numpy as np

    if args.limit < 1:
        raise ValueError(f"--limit {args.limit} is not allowed; give a number of results >= 1")
    if args.query and "|" in args.query:   # a thin-film stack: its layers, F0 and how fast R(λ) oscillates
        m = materials.get_material(args.query)
        emit(args, *_stack_description(m))
        return 0
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


#: wavelengths (nm) at which a stack's normal-incidence reflectance is listed
STACK_REPORT_NM = (450.0, 550.0, 650.0)


def _stack_description(m) -> tuple[dict, str]:
    """(JSON, text) describing the thin-film stack *m*: each layer's data source and thickness (nm), the normal-
    incidence reflectance at :data:`STACK_REPORT_NM`, the films' optical thickness Σ n d and the spacing of R(λ)'s
    fringes at 550 nm (what the planner samples wavelengths by: docs/thin-films.md)."""
    import numpy as np

    layers = [{"role": "substrate", "material": m.substrate.name, "source": m.substrate.source}]
    layers += [{"role": f"film {i + 1}", "material": f.name, "thickness_nm": round(float(d), 9), "source": f.source}
               for i, (f, d) in enumerate(m.films)]
    lam = np.array(STACK_REPORT_NM)
    r = [float(x) for x in m.F0(lam)]
    opt, fringe = float(m.optical_thickness_nm(550.0)), float(m.fringe_spacing_nm(550.0))
    data = {"material": m.name, "layers": layers, "films_from": "substrate outwards",
            "F0": {f"{w:g}nm": v for w, v in zip(STACK_REPORT_NM, r)},
            "optical_thickness_nm_550nm": opt,
            "fringe_spacing_nm_550nm": fringe if np.isfinite(fringe) else None,   # None: no film, no fringes
            "units": {"thickness_nm": "nm", "F0": "reflectance at normal incidence from air, unpolarized",
                      "optical_thickness_nm_550nm": "nm",
                      "fringe_spacing_nm_550nm": "nm; null where the films are 0 nm thick (no fringes)"}}
    lines = [f"thin-film stack {m.name} (films from the substrate outwards, light from air)"]
    for layer in layers:
        thick = f"{layer['thickness_nm']:g} nm" if "thickness_nm" in layer else "semi-infinite"
        lines.append(f"  {layer['role']:<10} {layer['material']:<16} {thick:<14} {layer['source']}")
    lines.append("  F0 " + ", ".join(f"{v:.4f} at {w:g} nm" for w, v in zip(STACK_REPORT_NM, r)))
    spacing = "no fringes" if not np.isfinite(fringe) else f"fringes of R(λ) {fringe:.3g} nm apart"
    lines.append(f"  optical thickness Σ n d {opt:.4g} nm at 550 nm: {spacing} there")
    return data, "\n".join(lines)

