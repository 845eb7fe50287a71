"""``waveoptics brdf``: evaluate a BRDF model at given directions and wavelengths, or its directional albedo.

The command is shared by all BRDF models. Each model is one entry of :data:`MODELS`: a function adding its
options (in its own argument group), a function turning the parsed options into the model's keyword arguments
and calling its factory in :data:`waveoptics.brdf.BRDF_MODELS` (the library part: validation and evaluation), and
a description of its parameters; direction and wavelength parsing, looping and the text/JSON output live here
once. Adding a model (e.g. ``kirchhoff`` with ``--surface FILE --solver ...``) means adding one :class:`Model`
entry.

JSON output: ``{"model": ..., "values": [{"incident": [θ, φ], "outgoing": [θ, φ], "wavelength_nm": λ,
"brdf": f}, ...]}`` with f in 1/sr (not multiplied by cos θ_o), or with ``--albedo``
``{"model": ..., "albedo": [{"incident": [θ, φ], "wavelength_nm": λ, "albedo": E}, ...]}``.
"""
from __future__ import annotations

import argparse

import sys
from dataclasses import dataclass
from typing import Callable


from ..errors import WaveopticsError
from ..vocabulary import DIFFRACTION, DIFFUSE_ALIASES, DIFFUSE_NAMES, FRESNEL_NAMES, NDF_NAMES, POLARIZATIONS, SHADOWING_NAMES
from ..units import direction_from_angles, parse_direction, parse_wavelengths
from ._common import add_common, add_surface, emit, load_surface, progress
from ._options import option, renamed


@dataclass(frozen=True)
class Model:
    """A BRDF model offered by ``waveoptics brdf --model NAME``.

    Attributes
    ----------
    add_arguments : callable(group)
        Adds the model's options to an argparse argument group.
    build : callable(args, wavelength_nm) -> waveoptics.brdf.ModelEvaluation
        The model set up from the options at these wavelengths (its evaluation, albedo and named parts).
    describe : callable(args) -> dict
        Model parameters echoed in the JSON output.
    help : str
    """

    add_arguments: Callable
    build: Callable
    describe: Callable
    help: str
    uses: tuple = ()   #: destinations of the options this model reads (beyond the command's own)


def _bar(args):
    """The progress wrapper of the library's loops over incident directions."""
    return lambda iterable, desc: progress(iterable, desc=desc, args=args)


def _index(args, wavelength_nm, note: bool = True) -> None:
    """Refuse --material with --ior, and (with *note*) say where a material's index data are clamped."""
    if args.material is not None and args.ior is not None:
        raise WaveopticsError("give only one of --material NAME and --ior N+Kj")
    spec = args.material if args.material is not None else args.ior
    if spec is not None and note:
        _report_clamped(spec, wavelength_nm, args)

# ----------------------------------------------------------------------------------------------------------
# microfacet


def _microfacet_arguments(g) -> None:


    option(g, "--ndf", choices=sorted(NDF_NAMES), default="ggx")
    option(g, "--micro-surface", note="--spacing/--units/--channel describe it when no --surface is given")
    option(g, "--footprint", note="with --micro-surface: the NDF of that footprint only (a glint); a .npy "
                                  "file is memory-mapped")
    g.add_argument("--shadowing", choices=sorted(SHADOWING_NAMES), default="smith-correlated",
                   help="masking-shadowing term (default smith-correlated)")
    option(g, "--micro-alpha", short="--alpha", dest="alpha",
           note="in [0, 2]; α_x if anisotropic; 0 = sharpest representable")
    g.add_argument("--roughness", type=float, metavar="R", help="perceptual roughness r, α = r² (instead of --alpha)")
    option(g, "--alpha-y", note="ggx, beckmann, epd and sgd")
    option(g, "--ndf-shape")
    renamed(g, "brdf", "--abc-c", dest="ndf_shape", type=float)
    option(g, "--material", note="or --ior")
    g.add_argument("--ior", metavar="N+Kj", help="constant complex index, e.g. 1.5 or 0.2+3.1j")
    g.add_argument("--fresnel", choices=sorted(FRESNEL_NAMES), default="exact",
                   help="Fresnel factor: exact, schlick, or one (F = 1, white furnace)")
    option(g, "--diffuse", choices=sorted(DIFFUSE_NAMES + tuple(DIFFUSE_ALIASES)), default="lambert",
           note="disney is burley")
    option(g, "--kd", default=0.0, note="applied as given, to metals too")
    g.add_argument("--diffuse-sigma", dest="sigma", type=float, default=0.0, metavar="DEG",
                   help="Oren-Nayar roughness σ in degrees (--diffuse oren-nayar; separate from the specular α; "
                        "default 0)")
    renamed(g, "brdf", "--sigma", dest="sigma", type=float)
    g.add_argument("--diffuse-roughness", type=float, default=0.5, metavar="R",
                   help="Burley diffuse roughness r in [0, 1] (--diffuse burley; default 0.5)")
    option(g, "--multiple-scattering", action="store_true",
           note="microfacet, twoscale and rough-dielectric; NumPy, exact or one Fresnel; off by "
                "default")
    g.add_argument("--no-tradeoff", action="store_true",
                   help="do not weight the diffuse term by (1 - F(θi))(1 - F(θo)) / (1 - F̄)")
    option(g, "--backend", choices=["numpy", "opencl"], default="numpy", note="albedo always uses NumPy")
    option(g, "--precision", choices=["float32", "float64"], default="float32")


def _microfacet_build(args, wavelength_nm):
    """:func:`waveoptics.brdf.microfacet_model` of the options."""
    from .. import brdf

    table = None
    if args.micro_surface is not None or args.ndf == "tabulated":
        table = _measured_ndf(args)
    _index(args, wavelength_nm)
    return brdf.microfacet_model(wavelengths_nm=wavelength_nm, alpha=args.alpha, roughness=args.roughness,
                                 alpha_y=args.alpha_y, ndf=args.ndf, ndf_shape=args.ndf_shape, slope_table=table,
                                 shadowing=args.shadowing, material=args.material, ior=args.ior,
                                 fresnel=args.fresnel, diffuse=args.diffuse, kd=args.kd,
                                 diffuse_sigma_deg=args.sigma, diffuse_roughness=args.diffuse_roughness,
                                 tradeoff=not args.no_tradeoff, multiple_scattering=args.multiple_scattering,
                                 backend=args.backend, precision=args.precision, device=args.device)


def _measured_ndf(args):
    """The slope table of --micro-surface (or of its --footprint): the NDF is the height field's slope law (the
    model takes its Beckmann-equivalent widths √2 × rms slope as α, α_y, which place the albedo quadrature's
    nodes)."""
    from .. import brdf, surfaces

    if args.micro_surface is None:
        raise WaveopticsError("--ndf tabulated needs --micro-surface FILE (the height field whose slopes it tabulates)")
    if args.alpha is not None or args.roughness is not None or args.ndf_shape is not None:
        raise WaveopticsError("--micro-surface sets the NDF from the file's slopes; drop --alpha, --roughness and "
                              "--ndf-shape")
    if getattr(args, "surface", None) is not None and any(getattr(args, k, None) is not None
                                                          for k in ("spacing", "units", "channel")):
        raise WaveopticsError("--spacing/--units/--channel would describe both --surface and --micro-surface; "
                              "give files that state their own metadata")
    if args.footprint is not None:   # the NDF one pixel sees (memory-mapped for a .npy)
        fp = surfaces.Footprint.parse(args.footprint)
        if getattr(args, "channel", None) is None:
            field = surfaces.open_large(args.micro_surface, spacing=spacing_from_args(args), units=getattr(args, "units", None))
        else:
            field = surfaces.load(args.micro_surface, spacing=getattr(args, "spacing", None),
                                  units=getattr(args, "units", None), channel=args.channel)
        table = brdf.footprint_ndf(field, fp)
    else:
        hf = surfaces.load(args.micro_surface, spacing=getattr(args, "spacing", None),
                           units=getattr(args, "units", None), channel=getattr(args, "channel", None))
        table = brdf.slope_table(hf)
    return table


def spacing_from_args(args):
    """--spacing as (dx, dy) in m, or None."""
    from ..units import parse_length

    sp = getattr(args, "spacing", None)
    if sp is None:
        return None
    parts = [parse_length(x, name="spacing") for x in str(sp).split(",")]
    return parts[0], parts[-1]


def _report_clamped(spec, wavelength_nm, args) -> None:

    from ..materials.database import get_material
    import numpy as np

    mat = get_material(spec)
    if mat.schlick_only:
        return
    bad = np.asarray(wavelength_nm)[mat.out_of_range(wavelength_nm)]
    if bad.size and not getattr(args, "json", False):
        lo, hi = mat.wavelength_range_nm
        print(f"waveoptics brdf: note: {mat.name} index clamped at {', '.join(f'{b:g}' for b in bad)} nm "
              f"(data range {lo:g}-{hi:g} nm)", file=sys.stderr)


def _microfacet_describe(args) -> dict:
    from .. import brdf

    d = {k: getattr(args, k) for k in ("ndf", "shadowing", "alpha", "roughness", "alpha_y", "material", "ior",
                                       "fresnel", "diffuse", "kd", "backend", "multiple_scattering")}
    spec = brdf.NDFS[args.ndf]
    if args.micro_surface is not None:
        d["ndf"] = "tabulated"
        d["micro_surface"] = args.micro_surface
        if args.footprint is not None:
            d["footprint"] = args.footprint
    elif spec.shape is not None and spec.name != "tabulated":
        d["ndf_shape"] = spec.shape_default if args.ndf_shape is None else args.ndf_shape
    if args.diffuse == "oren-nayar":
        d["sigma_deg"] = args.sigma
    d["tradeoff"] = not args.no_tradeoff
    return d


# ----------------------------------------------------------------------------------------------------------
# kirchhoff (wave optics of a height-field file; logic in waveoptics.scatter)


def _kirchhoff_arguments(g) -> None:
    add_surface(g)
    option(g, "--solver", choices=("direct", "fft"), default="direct",
           note="direct Kirchhoff sum (--backend numpy|opencl) or fft on a hemisphere grid (interpolated at the "
                "outgoing directions)")
    option(g, "--resolution", note="of the fft grid and the --albedo quadrature (default: resolves the specular "
                                   "spike; albedo 256)")
    option(g, "--realizations", default=1)
    option(g, "--window", default="hann")
    option(g, "--diffraction", default="kirchhoff", choices=DIFFRACTION)


def _kirchhoff_build(args, wavelength_nm):
    """:func:`waveoptics.brdf.kirchhoff_model` of the options."""
    from .. import brdf

    if not args.surface:
        raise WaveopticsError("--model kirchhoff needs --surface FILE")
    _index(args, wavelength_nm, note=args.fresnel != "one")
    return brdf.kirchhoff_model(wavelengths_nm=wavelength_nm, surface=load_surface(args), material=args.material,
                                ior=args.ior, fresnel=args.fresnel, solver=args.solver, backend=args.backend,
                                precision=args.precision, window=args.window, resolution=args.resolution,
                                realizations=args.realizations, diffraction=args.diffraction,
                                polarization=args.polarization, device=args.device)


def _kirchhoff_describe(args) -> dict:
    return {k: getattr(args, k) for k in ("surface", "solver", "material", "ior", "fresnel", "backend",
                                          "precision", "window", "realizations", "resolution", "diffraction")}


# ----------------------------------------------------------------------------------------------------------
# rayleigh-rice (first-order perturbation from PSD statistics; logic in waveoptics.scatter.perturbation)


def _rayleigh_rice_arguments(g) -> None:
    option(g, "--nano", note="rayleigh-rice: statistics, or --surface FILE whose periodogram is the PSD; "
                             "twoscale: default " + _default_nano())
    option(g, "--polarization", choices=POLARIZATIONS, default="unpolarized", note="rayleigh-rice and kirchhoff")


def _rayleigh_rice_build(args, wavelength_nm):
    """:func:`waveoptics.brdf.rayleigh_rice_model` of the options: the PSD is a model from --nano statistics or a
    height field's periodogram from --surface."""
    from .. import brdf, surfaces
    from ..request import parse_nano

    if bool(args.nano) == bool(args.surface):
        raise WaveopticsError("--model rayleigh-rice needs exactly one of --nano MODEL:params (height statistics) "
                              "and --surface FILE (its periodogram is the PSD)")
    if args.surface:
        psd = surfaces.PeriodogramPSD(load_surface(args))
    else:
        model, p = parse_nano(args.nano)
        if model not in surfaces.PSD_MODELS:
            raise WaveopticsError(f"--nano {args.nano!r}: rayleigh-rice needs height statistics "
                                  f"({', '.join(surfaces.PSD_MODELS)}), not {model!r}")
        psd = surfaces.PSDModel(model, sigma=p["sigma"], T=p.get("T"), B=p.get("B"), C=p.get("C"))
    _index(args, wavelength_nm)
    return brdf.rayleigh_rice_model(wavelengths_nm=wavelength_nm, psd=psd, material=args.material, ior=args.ior,
                                    polarization=args.polarization, resolution=args.resolution)


def _rayleigh_rice_describe(args) -> dict:
    return {k: getattr(args, k) for k in ("nano", "surface", "material", "ior", "polarization")}


# ----------------------------------------------------------------------------------------------------------
# twoscale (micro NDF carrying PSD nano-roughness, as a function; logic in waveoptics.brdf.pointwise)


def _default_nano() -> str:
    from ..vocabulary import DEFAULT_NANO

    return DEFAULT_NANO


def _twoscale_arguments(g) -> None:
    """The two-scale model takes the microfacet options (micro roughness, material, diffuse), --nano and
    --diffraction; nothing of its own."""


def _twoscale_build(args, wavelength_nm):
    """:func:`waveoptics.brdf.twoscale_model` of the options, built once per command (evaluation, parts and albedo
    share it)."""
    from .. import brdf
    from ..request import make_nano

    if args.surface and args.nano:
        raise WaveopticsError("give only one of --nano MODEL:params and --surface FILE for --model twoscale")
    if args.polarization != "unpolarized":
        raise WaveopticsError(f"--polarization {args.polarization} is not available for --model twoscale "
                              "(unpolarized only; polarized two-scale lobes: 'waveoptics simulate --polarization')")
    table = None
    if args.micro_surface is not None or args.ndf == "tabulated":   # the NDF of a micro height field's slopes
        table = _measured_ndf(args)
    _index(args, wavelength_nm)
    surface = load_surface(args) if args.surface else None
    nano = None if surface is not None else make_nano(args.nano or _default_nano(), wavelength_nm)
    return brdf.twoscale_model(wavelengths_nm=wavelength_nm, nano=nano, surface=surface, alpha=args.alpha,
                               roughness=args.roughness, alpha_y=args.alpha_y, ndf=args.ndf,
                               ndf_shape=args.ndf_shape, slope_table=table, shadowing=args.shadowing,
                               material=args.material, ior=args.ior, fresnel=args.fresnel, diffuse=args.diffuse,
                               kd=args.kd, diffuse_sigma_deg=args.sigma, diffraction=args.diffraction,
                               multiple_scattering=args.multiple_scattering, resolution=args.resolution)


def _twoscale_describe(args) -> dict:
    d = {k: getattr(args, k) for k in ("ndf", "shadowing", "alpha", "roughness", "alpha_y", "material", "ior",
                                       "fresnel", "diffuse", "kd", "diffraction", "multiple_scattering")}
    if args.surface:
        d["surface"] = args.surface
    else:
        d["nano"] = args.nano or _default_nano()
    if args.micro_surface is not None:
        d["micro_surface"] = args.micro_surface
    return d


# ----------------------------------------------------------------------------------------------------------
# rough-dielectric (reflection + transmission of a rough dielectric interface; logic in waveoptics.brdf.btdf)


def _rough_dielectric_arguments(g) -> None:
    """The rough dielectric takes the microfacet options (--alpha, --ndf, --shadowing, --material or --ior,
    --multiple-scattering); nothing of its own."""


def _rough_dielectric_build(args, wavelength_nm):
    """:func:`waveoptics.brdf.rough_dielectric_model` of the options."""
    from .. import brdf

    _index(args, wavelength_nm)
    return brdf.rough_dielectric_model(wavelengths_nm=wavelength_nm, alpha=args.alpha, roughness=args.roughness,
                                       alpha_y=args.alpha_y, ndf=args.ndf, ndf_shape=args.ndf_shape,
                                       shadowing=args.shadowing, material=args.material, ior=args.ior,
                                       fresnel=args.fresnel, multiple_scattering=args.multiple_scattering)


def _rough_dielectric_describe(args) -> dict:
    return {k: getattr(args, k) for k in ("ndf", "shadowing", "alpha", "roughness", "alpha_y", "material", "ior",
                                          "multiple_scattering")}


# ----------------------------------------------------------------------------------------------------------
# table (a BRDF table file as a function; logic in waveoptics.distributed.table.open_table)


def _table_arguments(g) -> None:
    g.add_argument("--table", metavar="FILE", help="BRDF table written by 'waveoptics table' (.h5)")


def _table_build(args, wavelength_nm):
    """A BRDF table file as a function (:func:`waveoptics.distributed.table.open_table`)."""
    from .. import brdf
    from ..distributed.table import open_table

    if not args.table:
        raise WaveopticsError("--model table needs --table FILE (a table written by 'waveoptics table')")
    table = open_table(args.table)
    return brdf.function_evaluation(lambda wi: table, wavelength_nm)


def _table_describe(args) -> dict:
    return {"table": args.table}


#: options of the micro-scale facets (NDF, index, diffuse term) and of a file's metadata
_MICRO = ("ndf", "micro_surface", "footprint", "shadowing", "alpha", "roughness", "alpha_y", "ndf_shape", "material",
          "ior", "fresnel", "diffuse", "kd", "sigma", "multiple_scattering", "spacing", "units", "channel")
_INDEX = ("material", "ior", "fresnel")

#: BRDF models offered by ``waveoptics brdf --model``
MODELS: dict[str, Model] = {
    "microfacet": Model(_microfacet_arguments, _microfacet_build, _microfacet_describe,
                        "geometric-optics microfacet BRDF (Cook-Torrance / Walter et al. 2007) with a diffuse term",
                        _MICRO + ("diffuse_roughness", "no_tradeoff", "backend", "precision")),
    "kirchhoff": Model(_kirchhoff_arguments, _kirchhoff_build, _kirchhoff_describe,
                       "wave-optics Kirchhoff BRDF of a height-field file (waveoptics.scatter)",
                       _INDEX + ("surface", "spacing", "units", "channel", "solver", "resolution", "realizations",
                                 "window", "diffraction", "backend", "precision", "polarization")),
    "rayleigh-rice": Model(_rayleigh_rice_arguments, _rayleigh_rice_build, _rayleigh_rice_describe,
                           "first-order Rayleigh-Rice BRDF of a smooth rough surface from its PSD, with the "
                           "polarization factor Q (s, p, unpolarized; JSON also gives ss, sp, ps, pp)",
                           ("material", "ior", "nano", "surface", "spacing", "units", "channel", "polarization",
                            "resolution")),
    "twoscale": Model(_twoscale_arguments, _twoscale_build, _twoscale_describe,
                      "two-scale BRDF: micro NDF carrying PSD nano-roughness (Holzschuch & Pacanowski "
                      "2017), evaluated at the given directions; JSON also gives its coherent, diffraction "
                      "and diffuse parts",
                      _MICRO + ("nano", "surface", "diffraction", "resolution", "polarization")),
    "rough-dielectric": Model(_rough_dielectric_arguments, _rough_dielectric_build, _rough_dielectric_describe,
                              "BSDF of a rough dielectric interface (Walter et al. 2007): reflection and "
                              "transmission (air above, the material below; the command's directions are above "
                              "the surface, so it gives the reflection and the albedo R + T); JSON also gives its "
                              "reflection, transmission and multiple parts",
                              ("ndf", "shadowing", "alpha", "roughness", "alpha_y", "ndf_shape", "material", "ior",
                               "fresnel", "multiple_scattering")),
    "table": Model(_table_arguments, _table_build, _table_describe,
                   "a BRDF table file (waveoptics table) as a function: its diffracted lobes interpolated "
                   "between incidences relative to the specular direction, coherent and diffuse parts "
                   "exact; at the table's wavelengths", ("table",)),
}

#: options every model takes (the command's own)
_COMMON = {"model", "wavelengths", "incident", "outgoing", "albedo", "device", "json", "debug", "quiet", "func",
           "command"}


def _refuse_unused(args) -> None:
    """An option that the chosen model does not read is refused in one line, naming the models that take it: a
    value given and silently ignored (``--model microfacet --surface F``) reads as if it had been used."""
    model = args.model
    uses = set(MODELS[model].uses) | _COMMON
    for dest, default in args._brdf_defaults.items():
        if dest in uses or dest.startswith("_"):
            continue
        value = getattr(args, dest, default)
        if value is not None and value != default:
            takers = [m for m, spec in MODELS.items() if dest in spec.uses]
            flag = args._brdf_flags.get(dest, dest)
            raise WaveopticsError(f"{flag} is not used by --model {model}" + (
                f" (it is an option of --model {', '.join(takers)})" if takers else "") + "; drop it")


# ----------------------------------------------------------------------------------------------------------
# the command


def register(sub) -> None:
    p = sub.add_parser("brdf", help="evaluate a BRDF model (or its directional albedo) at given directions",
                       description="Evaluate a BRDF f (1/sr, not times cosine) for incident and outgoing "
                                   "directions at one or more wavelengths. Angles in degrees: θ from the "
                                   "normal, φ about it. Models: " +
                                   "; ".join(f"{k}: {m.help}" for k, m in MODELS.items()))
    p.add_argument("--model", choices=sorted(MODELS), default="microfacet", help="BRDF model (default microfacet)")
    option(p, "--wavelengths", default="550")
    renamed(p, "brdf", "--wavelength", dest="wavelengths")
    option(p, "--incident", action="append", required=True, note="repeat for several")
    p.add_argument("--outgoing", action="append", metavar="THETA,PHI",
                   help="direction to the viewer in degrees (repeat for several)")
    p.add_argument("--albedo", action="store_true",
                   help="print the directional albedo ∫ f cos θo dωo of each incident direction instead")
    for name, model in MODELS.items():
        model.add_arguments(p.add_argument_group(f"--model {name}"))
    add_common(p)
    shown = [a for a in p._actions if a.option_strings and a.help != argparse.SUPPRESS]
    p.set_defaults(func=run, _brdf_defaults={a.dest: a.default for a in shown},
                   _brdf_flags={a.dest: next(o for o in a.option_strings if o.startswith("--")) for a in shown})


def run(args) -> int:

    import numpy as np

    model = MODELS[args.model]
    _refuse_unused(args)
    if getattr(args, "diffuse", None) in DIFFUSE_ALIASES:
        args.diffuse = DIFFUSE_ALIASES[args.diffuse]
    if getattr(args, "multiple_scattering", False) and args.model not in ("microfacet", "twoscale",
                                                                                 "rough-dielectric"):
        raise WaveopticsError("--multiple-scattering applies to --model microfacet, twoscale and rough-dielectric, "
                              f"not {args.model!r}")
    wl = parse_wavelengths(args.wavelengths, name="--wavelengths")
    inc = [parse_direction(t, name="--incident") for t in args.incident]
    wi = direction_from_angles([t for t, _ in inc], [p for _, p in inc])
    head = {"model": args.model, "parameters": model.describe(args),
            "units": {"brdf": "1/sr", "albedo": "1", "wavelength_nm": "nm", "incident": "deg", "outgoing": "deg"}}
    if args.albedo:
        E = np.asarray(model.build(args, wl).albedo(wi, progress=_bar(args)))
        rows = [{"incident": list(inc[i]), "wavelength_nm": float(wl[j]), "albedo": float(E[j, i])}
                for i in range(len(inc)) for j in range(len(wl))]
        text = "\n".join(f"incident θ={r['incident'][0]:g}° φ={r['incident'][1]:g}°  λ={r['wavelength_nm']:g} nm  "
                         f"albedo={r['albedo']:.6g}" for r in rows)
        emit(args, {**head, "albedo": rows}, text)
        return 0
    if not args.outgoing:
        raise WaveopticsError("give at least one --outgoing THETA,PHI (or --albedo)")
    out = [parse_direction(t, name="--outgoing", need_phi=True) for t in args.outgoing]
    wo = direction_from_angles([t for t, _ in out], [p for _, p in out])
    m = model.build(args, wl)
    f = np.asarray(m.evaluate(wi, wo, progress=_bar(args)))
    parts = m.components(wi, wo) if m.components is not None else {}
    rows = [{"incident": list(inc[i]), "outgoing": list(out[k]), "wavelength_nm": float(wl[j]),
             "brdf": float(f[j, i, k]),
             **({"components": {c: float(v[j, i, k]) for c, v in parts.items()}} if parts else {})}
            for i in range(len(inc)) for k in range(len(out)) for j in range(len(wl))]
    text = "\n".join(f"incident θ={r['incident'][0]:g}° φ={r['incident'][1]:g}°  "
                     f"outgoing θ={r['outgoing'][0]:g}° φ={r['outgoing'][1]:g}°  λ={r['wavelength_nm']:g} nm  "
                     f"f={r['brdf']:.6g} 1/sr" for r in rows)
    emit(args, {**head, "values": rows}, text)
    return 0
