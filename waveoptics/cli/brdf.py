"""``waveoptics brdf``: evaluate a BRDF model at given directions and wavelengths, or its directional albedo.

The command is shared by all BRDF models. The models, their parameters (unit, default, meaning) and their
factories are the library's registry (:data:`waveoptics.vocabulary.BRDF_MODEL_PARAMETERS`,
:data:`waveoptics.brdf.BRDF_MODELS`): the options take their defaults from it, and a model is set up by
:func:`waveoptics.brdf.build_brdf_model` with each of its parameters read from the option of the same dest
(:data:`DEST` where they differ). Each model is one entry of :data:`MODELS`: a function adding its own options,
a function reading its input files into the parameters that are objects (a height field, a slope table, a PSD, a
table), and a description of its parameters; direction and wavelength parsing, looping and the text/JSON output
live here once.

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
from ..vocabulary import (BRDF_MODEL_HELP, BRDF_MODEL_PARAMETERS, DIFFRACTION, DIFFUSE_ALIASES, DIFFUSE_NAMES,
                          NANO_FRAMES,
                          FRESNEL_NAMES, NDF_NAMES, POLARIZATIONS, SHADOWING_NAMES)
from ..units import direction_from_angles, parse_direction, parse_wavelengths
from ._common import add_common, add_surface, angle_arg, emit, load_surface, progress
from ._options import option, renamed


#: model parameters whose option has another dest
DEST = {"tradeoff": "no_tradeoff"}
#: model parameters that are objects read from files (by the model's *inputs*), with the options they read
INPUTS = {"slope_table": ("micro_surface", "footprint", "spacing", "units", "channel"),
           "surface": ("surface", "spacing", "units", "channel"),
           "nano": ("nano",),
           "psd": ("nano", "surface", "spacing", "units", "channel"),
           "table": ("table",)}


def _default(name: str, model: str = "microfacet"):
    """The registry's default of parameter *name* of *model* (:data:`waveoptics.vocabulary.BRDF_MODEL_PARAMETERS`)."""
    return next(p.default for p in BRDF_MODEL_PARAMETERS[model] if p.name == name)


def _uses(model: str, extra: tuple = ()) -> tuple:
    """The dests of the options *model* reads: one per registry parameter (the input files' options for those
    read from files), and *extra*."""
    dests = []
    for p in BRDF_MODEL_PARAMETERS[model]:
        dests += INPUTS.get(p.name, (DEST.get(p.name, p.name),))
    return tuple(dict.fromkeys(dests + list(extra)))


def _parameters(name: str, args, inputs: dict) -> dict:
    """The parameters of model *name* from the options (:data:`DEST`) and the objects *inputs* read from files."""
    kw = {}
    for p in BRDF_MODEL_PARAMETERS[name]:
        if p.name in inputs:
            kw[p.name] = inputs[p.name]
        elif p.name == "tradeoff":
            kw[p.name] = not args.no_tradeoff
        elif p.name not in INPUTS:
            kw[p.name] = getattr(args, DEST.get(p.name, p.name))
    return kw


@dataclass(frozen=True)
class Model:
    """A BRDF model offered by ``waveoptics brdf --model NAME`` (a model of the library's registry).

    Attributes
    ----------
    name : str
        The model (a key of :data:`waveoptics.brdf.BRDF_MODELS`).
    add_arguments : callable(group)
        Adds the model's own options to an argparse argument group.
    inputs : callable(args, wavelength_nm) -> dict
        Checks the options and reads the model's input files: the parameters that are objects.
    describe : callable(args) -> dict
        Model parameters echoed in the JSON output.
    extra : tuple
        Options the model reads beyond its parameters' (to refuse them with a message of its own).
    """

    name: str
    add_arguments: Callable
    inputs: Callable
    describe: Callable
    extra: tuple = ()

    @property
    def help(self) -> str:
        return BRDF_MODEL_HELP[self.name]

    @property
    def uses(self) -> tuple:
        """Destinations of the options this model reads (beyond the command's own)."""
        return _uses(self.name, self.extra)

    def build(self, args, wavelength_nm):
        """The model set up from the options at these wavelengths (:func:`waveoptics.brdf.build_brdf_model`)."""
        from .. import brdf

        inputs = self.inputs(args, wavelength_nm)
        return brdf.build_brdf_model(self.name, wavelength_nm, **_parameters(self.name, args, inputs))


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


    option(g, "--ndf", choices=sorted(NDF_NAMES), default=_default("ndf"))
    option(g, "--micro-surface", note="--spacing/--units/--channel describe it when no --surface is given")
    option(g, "--footprint", note="with --micro-surface: the NDF of that footprint only (a glint); a .npy "
                                  "file is memory-mapped")
    g.add_argument("--shadowing", choices=sorted(SHADOWING_NAMES), default=_default("shadowing"),
                   help=f"masking-shadowing term (default {_default('shadowing')})")
    option(g, "--micro-alpha", short="--alpha", dest="alpha",
           note="in [0, 2]; α_x if anisotropic; 0 = sharpest representable")
    g.add_argument("--roughness", type=float, metavar="R", help="perceptual roughness r, α = r² (instead of --alpha)")
    option(g, "--alpha-y", note="ggx, beckmann, epd and sgd")
    option(g, "--ndf-shape")
    renamed(g, "brdf", "--abc-c", dest="ndf_shape", type=float)
    option(g, "--material", note="or --ior")
    g.add_argument("--ior", metavar="N+Kj", help="constant complex index, e.g. 1.5 or 0.2+3.1j")
    g.add_argument("--fresnel", choices=sorted(FRESNEL_NAMES), default=_default("fresnel"),
                   help="Fresnel factor: exact, schlick, or one (F = 1, white furnace)")
    option(g, "--diffuse", choices=sorted(DIFFUSE_NAMES + tuple(DIFFUSE_ALIASES)), default=_default("diffuse"),
           note="disney is burley")
    option(g, "--kd", default=_default("kd"), note="applied as given, to metals too")
    g.add_argument("--diffuse-sigma", dest="diffuse_sigma_deg", type=angle_arg, default=_default("diffuse_sigma_deg"),
                   metavar="ANGLE", help="Oren-Nayar roughness σ, an angle: 20, 20deg or 0.35rad (--diffuse "
                                         "oren-nayar; separate from the specular α; default "
                                         f"{_default('diffuse_sigma_deg'):g} deg)")
    renamed(g, "brdf", "--sigma", dest="diffuse_sigma_deg")
    g.add_argument("--diffuse-roughness", type=float, default=_default("diffuse_roughness"), metavar="R",
                   help=f"Burley diffuse roughness r in [0, 1] (--diffuse burley; default "
                        f"{_default('diffuse_roughness'):g})")
    option(g, "--multiple-scattering", action="store_true",
           note="microfacet, twoscale and rough-dielectric; NumPy, exact or one Fresnel; off by "
                "default")
    g.add_argument("--no-tradeoff", action="store_true",
                   help="do not weight the diffuse term by (1 - F(θi))(1 - F(θo)) / (1 - F̄)")
    option(g, "--backend", choices=["numpy", "opencl"], default=_default("backend"), note="albedo always uses NumPy")
    option(g, "--precision", choices=["float32", "float64"], default=_default("precision"))


def _microfacet_inputs(args, wavelength_nm) -> dict:
    """The slope table of :func:`waveoptics.brdf.microfacet_model` (--micro-surface or --ndf tabulated)."""
    table = None
    if args.micro_surface is not None or args.ndf == "tabulated":
        table = _measured_ndf(args)
    _index(args, wavelength_nm)
    return {"slope_table": table}


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
        d["diffuse_sigma_deg"] = args.diffuse_sigma_deg
    d["tradeoff"] = not args.no_tradeoff
    return d


# ----------------------------------------------------------------------------------------------------------
# kirchhoff (wave optics of a height-field file; logic in waveoptics.scatter)


def _kirchhoff_arguments(g) -> None:
    add_surface(g)
    option(g, "--solver", choices=("direct", "fft"), default=_default("solver", "kirchhoff"),
           note="direct Kirchhoff sum (--backend numpy|opencl) or fft on a hemisphere grid (interpolated at the "
                "outgoing directions)")
    option(g, "--resolution", note="of the fft grid and the --albedo quadrature (default: resolves the specular "
                                   "spike; albedo 256)")
    option(g, "--realizations", default=_default("realizations", "kirchhoff"))
    option(g, "--window", default=_default("window", "kirchhoff"))
    option(g, "--diffraction", default=_default("diffraction", "kirchhoff"), choices=DIFFRACTION)


def _kirchhoff_inputs(args, wavelength_nm) -> dict:
    """The height field of :func:`waveoptics.brdf.kirchhoff_model` (--surface)."""
    if not args.surface:
        raise WaveopticsError("--model kirchhoff needs --surface FILE")
    _index(args, wavelength_nm, note=args.fresnel != "one")
    return {"surface": load_surface(args)}


def _kirchhoff_describe(args) -> dict:
    return {k: getattr(args, k) for k in ("surface", "solver", "material", "ior", "fresnel", "backend",
                                          "precision", "window", "realizations", "resolution", "diffraction")}


# ----------------------------------------------------------------------------------------------------------
# rayleigh-rice (first-order perturbation from PSD statistics; logic in waveoptics.scatter.perturbation)


def _rayleigh_rice_arguments(g) -> None:
    option(g, "--nano", note="rayleigh-rice: statistics, or --surface FILE whose periodogram is the PSD; "
                             "twoscale: default " + _default_nano())
    option(g, "--polarization", choices=POLARIZATIONS, default=_default("polarization", "rayleigh-rice"),
           note="rayleigh-rice and kirchhoff")
    option(g, "--roughness-correlation", default=_default("roughness_correlation", "rayleigh-rice"),
           note="of a --material stack's interfaces")


def _psd_statistics(args, model_name):
    """The PSDModel of --nano height statistics (first-order models need statistics, not a generator)."""
    from .. import surfaces
    from ..request import parse_nano

    model, p = parse_nano(args.nano)
    if model not in surfaces.PSD_MODELS:
        raise WaveopticsError(f"--nano {args.nano!r}: {model_name} needs height statistics "
                              f"({', '.join(surfaces.PSD_MODELS)}), not {model!r}")
    return surfaces.PSDModel(model, sigma=p["sigma"], T=p.get("corr_length"), B=p.get("B"), C=p.get("C"))


def _rayleigh_rice_inputs(args, wavelength_nm) -> dict:
    """The PSD of :func:`waveoptics.brdf.rayleigh_rice_model`: a model from --nano statistics or a height field's
    periodogram from --surface."""
    from .. import surfaces

    if bool(args.nano) == bool(args.surface):
        raise WaveopticsError("--model rayleigh-rice needs exactly one of --nano MODEL:params (height statistics) "
                              "and --surface FILE (its periodogram is the PSD)")
    psd = surfaces.PeriodogramPSD(load_surface(args)) if args.surface else _psd_statistics(args, "rayleigh-rice")
    _index(args, wavelength_nm)
    return {"psd": psd}


def _rayleigh_rice_describe(args) -> dict:
    return {k: getattr(args, k) for k in ("nano", "surface", "material", "ior", "polarization",
                                          "roughness_correlation")}


# ----------------------------------------------------------------------------------------------------------
# twoscale (micro NDF carrying PSD nano-roughness, as a function; logic in waveoptics.brdf.pointwise)


def _default_nano() -> str:
    from ..vocabulary import DEFAULT_NANO

    return DEFAULT_NANO


def _twoscale_arguments(g) -> None:
    """The two-scale model takes the microfacet options (micro roughness, material, diffuse), --nano and
    --diffraction; nothing of its own."""


def _twoscale_inputs(args, wavelength_nm) -> dict:
    """The nano-roughness (--nano statistics or a --surface height field) and the slope table of
    :func:`waveoptics.brdf.twoscale_model`."""
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
    return {"nano": nano, "surface": surface, "slope_table": table}


def _twoscale_describe(args) -> dict:
    d = {k: getattr(args, k) for k in ("ndf", "shadowing", "alpha", "roughness", "alpha_y", "material", "ior",
                                       "fresnel", "diffuse", "kd", "diffraction", "multiple_scattering",
                                       "roughness_correlation")}
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
    --multiple-scattering), --nano statistics (nano-rough glass) and the frame of their lobes."""
    option(g, "--nano-frame", choices=NANO_FRAMES, default=_default("nano_frame", "rough-dielectric"))


def _rough_dielectric_inputs(args, wavelength_nm) -> dict:
    """:func:`waveoptics.brdf.rough_dielectric_model` reads no file; --nano statistics become its PSD."""
    if args.surface:
        raise WaveopticsError("--surface is not used by --model rough-dielectric (its nano-roughness is --nano "
                              "height statistics); drop it")
    _index(args, wavelength_nm)
    return {"psd": _psd_statistics(args, "rough-dielectric")} if args.nano else {}


def _rough_dielectric_describe(args) -> dict:
    return {k: getattr(args, k) for k in ("ndf", "shadowing", "alpha", "roughness", "alpha_y", "material", "ior",
                                          "multiple_scattering", "nano", "nano_frame")}


# ----------------------------------------------------------------------------------------------------------
# table (a BRDF table file as a function; logic in waveoptics.distributed.table.open_table)


def _table_arguments(g) -> None:
    g.add_argument("--table", metavar="FILE", help="BRDF table written by 'waveoptics table' (.h5; a glass table "
                                                   "of 'table --transmission' is a BSDF over the sphere)")


def _table_inputs(args, wavelength_nm) -> dict:
    """A BRDF table file as a function (:func:`waveoptics.distributed.table.open_table`)."""
    from ..distributed.table import open_table

    if not args.table:
        raise WaveopticsError("--model table needs --table FILE (a table written by 'waveoptics table')")
    return {"table": open_table(args.table)}


def _table_describe(args) -> dict:
    return {"table": args.table}


#: BRDF models offered by ``waveoptics brdf --model`` (the library's registry, in its order)
MODELS: dict[str, Model] = {m.name: m for m in (
    Model("microfacet", _microfacet_arguments, _microfacet_inputs, _microfacet_describe),
    Model("kirchhoff", _kirchhoff_arguments, _kirchhoff_inputs, _kirchhoff_describe),
    Model("rayleigh-rice", _rayleigh_rice_arguments, _rayleigh_rice_inputs, _rayleigh_rice_describe),
    Model("twoscale", _twoscale_arguments, _twoscale_inputs, _twoscale_describe, extra=("polarization",)),
    Model("rough-dielectric", _rough_dielectric_arguments, _rough_dielectric_inputs, _rough_dielectric_describe),
    Model("table", _table_arguments, _table_inputs, _table_describe),
)}

#: models whose --outgoing directions cover the whole sphere (θ > 90°: transmitted, inside the material; the
#: first-order model only where the material is transparent)
SPHERE_MODELS = ("rough-dielectric", "rayleigh-rice")

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
                   help="direction to the viewer in degrees (repeat for several); θ up to 180 for "
                        "--model rough-dielectric (θ > 90: transmitted into the dielectric)")
    p.add_argument("--albedo", action="store_true",
                   help="print the directional albedo ∫ f cos θo dωo of each incident direction instead")
    for name, model in MODELS.items():
        model.add_arguments(p.add_argument_group(f"--model {name}"))
    add_common(p)
    shown = [a for a in p._actions if a.option_strings and a.help != argparse.SUPPRESS]
    p.set_defaults(func=run, _brdf_defaults={a.dest: a.default for a in shown},
                   _brdf_flags={a.dest: next(o for o in a.option_strings if o.startswith("--")) for a in shown})


def _reflected_transmitted(parts: dict) -> dict:
    """The albedo of a BSDF over the sphere split into ``reflection`` and ``transmission``: the sums of its parts
    named ``*reflection`` and ``*transmission`` (:meth:`waveoptics.brdf.RoughDielectricBSDF.albedo_parts`)."""
    return {side: sum(v for k, v in parts.items() if k.endswith(side)) for side in ("reflection", "transmission")}


def _over_sphere(args) -> bool:
    """Whether the model is a BSDF over the whole sphere: :data:`SPHERE_MODELS`, or a glass table file."""
    if args.model == "table" and args.table:
        from ..distributed.table import GLASS_TABLE_FORMAT, table_info

        return table_info(args.table)["format"] == GLASS_TABLE_FORMAT
    return args.model in SPHERE_MODELS


def _print_albedo(args, ev, wi, inc, wl, head) -> int:
    """--albedo: ∫ f cos θo dωo per incident direction and λ; a BSDF over the sphere also prints its reflected
    and transmitted parts (R, T)."""
    import numpy as np

    if _over_sphere(args) and ev.albedo_components is not None:
        split = {k: np.asarray(v) for k, v in _reflected_transmitted(ev.albedo_components(wi)).items()}
        E = split["reflection"] + split["transmission"]
    else:
        split, E = {}, np.asarray(ev.albedo(wi, progress=_bar(args)))
    rows = [{"incident": list(inc[i]), "wavelength_nm": float(wl[j]), "albedo": float(E[j, i]),
             **{k: float(v[j, i]) for k, v in split.items()}} for i in range(len(inc)) for j in range(len(wl))]
    text = "\n".join(f"incident θ={r['incident'][0]:g}° φ={r['incident'][1]:g}°  λ={r['wavelength_nm']:g} nm  "
                     f"albedo={r['albedo']:.6g}" + (f"  R={r['reflection']:.6g}  T={r['transmission']:.6g}"
                                                    if split else "") for r in rows)
    units = dict(head["units"], **{k: "1" for k in split})
    emit(args, {**head, "units": units, "albedo": rows}, text)
    return 0


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
    # a BSDF over the whole sphere also takes light from inside the material: θ > 90°
    sphere = _over_sphere(args)
    inc = [parse_direction(t, name="--incident", max_theta_deg=180.0 if sphere else 90.0) for t in args.incident]
    wi = direction_from_angles([t for t, _ in inc], [p for _, p in inc])
    head = {"model": args.model, "parameters": model.describe(args),
            "units": {"brdf": "1/sr", "albedo": "1", "wavelength_nm": "nm", "incident": "deg", "outgoing": "deg"}}
    if args.albedo:
        return _print_albedo(args, model.build(args, wl), wi, inc, wl, head)
    if not args.outgoing:
        raise WaveopticsError("give at least one --outgoing THETA,PHI (or --albedo)")
    # a BSDF over the whole sphere (the rough dielectric) is also evaluated below the surface: θ > 90°
    out = [parse_direction(t, name="--outgoing", need_phi=True, max_theta_deg=180.0 if sphere else 90.0)
           for t in args.outgoing]
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
