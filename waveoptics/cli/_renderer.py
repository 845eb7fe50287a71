"""Options shared by the commands that hand the BRDF to a renderer (``export``, ``render``): the two-scale model
of :func:`waveoptics.renderers.renderer_brdf`, with one meaning in both."""
from __future__ import annotations

from ..vocabulary import DEFAULT_NANO, DIFFRACTION, DIFFUSE_ALIASES, DIFFUSE_NAMES, PARAMETRIC_NDF_NAMES
from ._common import add_surface, load_surface
from ._options import option

__all__ = ["add_model", "model_parameters", "model_from_args", "plugin_parameters", "model_description"]


def add_model(parser) -> None:
    """Add the model options to *parser* (one argument group)."""
    from ..vocabulary import RENDER_WAVELENGTH_STEP_NM as DEFAULT_WAVELENGTH_STEP_NM

    g = parser.add_argument_group("two-scale BRDF")
    option(g, "--material", default="aluminium", note="a metal gets no diffuse term")
    option(g, "--micro-alpha", dest="alpha", default=0.1)
    option(g, "--alpha-y", note="ggx, beckmann, epd and sgd")
    option(g, "--ndf", choices=sorted(PARAMETRIC_NDF_NAMES), default="ggx")
    option(g, "--nano", note=f"'none' for no nano-roughness (the microfacet model); default {DEFAULT_NANO}")
    add_surface(g, note="the nano-scale height field, instead of --nano statistics")
    option(g, "--diffraction", choices=DIFFRACTION, default="kirchhoff")
    option(g, "--kd", default=0.0, note="dielectrics only")
    option(g, "--diffuse", choices=sorted(DIFFUSE_NAMES + tuple(DIFFUSE_ALIASES)), default="lambert",
           note="disney is burley")
    option(g, "--multiple-scattering", action="store_true", note="off by default")
    g.add_argument("--wavelength-step", default=f"{DEFAULT_WAVELENGTH_STEP_NM:g}nm", metavar="L",
                   help="largest spacing of the wavelength nodes over 360-830 nm, with unit "
                        f"(default {DEFAULT_WAVELENGTH_STEP_NM:g}nm); between nodes the BRDF is linear in λ")
    option(g, "--resolution", default=128, note="of the tabulated diffracted lobes")
    g.add_argument("--scene", metavar="FILE.toml",
                   help="take the model from a scene file's material (waveoptics plan/run format: material, "
                        "roughness, ndf, diffuse_albedo, nano) instead of the options above")
    g.add_argument("--scene-material", metavar="NAME",
                   help="which [[materials]] entry of --scene (default the first)")
    g.add_argument("--exact", action="store_true",
                   help="evaluate the diffracted part pointwise (PSD statistics only; ~200x slower)")


#: model options a --scene replaces, with their defaults
_SCENE_REPLACES = {"material": "aluminium", "alpha": 0.1, "alpha_y": None, "ndf": "ggx", "nano": None,
                   "surface": None, "kd": 0.0}


def _scene_parameters(args) -> dict:
    """Model keywords from the --scene material (its nano as statistics text, a height-field file or a generated
    height field)."""
    from ..errors import WaveopticsError
    from ..planning import scene as scenes

    given = [k for k, v in _SCENE_REPLACES.items() if getattr(args, k) != v]
    if given:
        raise WaveopticsError(f"--scene sets the model; do not also give --{given[0].replace('_', '-')}")
    sc = scenes.load(args.scene)
    mats = {m.name: m for m in sc.materials}
    name = args.scene_material or sc.materials[0].name
    if name not in mats:
        raise WaveopticsError(f"--scene-material {name!r} is not in {args.scene}; it has: {', '.join(mats)}")
    m = mats[name]
    kw = dict(material=m.material, alpha=m.roughness, alpha_y=None, ndf=m.ndf, nano="none", surface=None,
              kd=m.diffuse_albedo, diffraction=args.diffraction if m.diffraction == "auto" else m.diffraction)
    if m.nano is not None:
        if m.nano.kind == "statistics":
            kw["nano"] = m.nano.text
        else:
            kw.update(nano=None, surface=m.nano.height_field(sc.seed))
    return kw


def model_parameters(args) -> dict:
    """Keywords of :func:`waveoptics.renderers.renderer_brdf` from the options (the surface as a file name, or a
    height field a --scene generates)."""
    from ..errors import WaveopticsError
    from ..units import parse_length

    if getattr(args, "scene_material", None) and not getattr(args, "scene", None):
        raise WaveopticsError("--scene-material names a material of a --scene file; give one")
    if getattr(args, "scene", None):
        step = parse_length(args.wavelength_step, name="wavelength_step") * 1e9
        return dict(_scene_parameters(args), diffuse=args.diffuse, wavelength_step_nm=step,
                    resolution=args.resolution, exact=args.exact, multiple_scattering=args.multiple_scattering)
    if args.surface is not None and args.nano is not None:
        raise WaveopticsError("give only one of --nano MODEL:params and --surface FILE")
    step = parse_length(args.wavelength_step, name="wavelength_step") * 1e9
    return dict(material=args.material, alpha=args.alpha, alpha_y=args.alpha_y, ndf=args.ndf, nano=args.nano,
                surface=args.surface, diffraction=args.diffraction, kd=args.kd, diffuse=args.diffuse,
                wavelength_step_nm=step, resolution=args.resolution, exact=args.exact,
                multiple_scattering=args.multiple_scattering)


def model_from_args(args):
    """(the :class:`waveoptics.brdf.SpectralNodes` model of the options, its :func:`model_parameters`)."""
    from ..renderers import renderer_brdf

    kw = model_parameters(args)
    built = dict(kw)
    if not getattr(args, "scene", None):
        built["surface"] = load_surface(args, required=False)
    return renderer_brdf(**built), kw


def plugin_parameters(args, kw: dict) -> dict:
    """The model of :func:`model_parameters` *kw* as parameters of the Mitsuba plugin
    (:mod:`waveoptics.renderers.mitsuba`)."""
    from ..errors import WaveopticsError

    if args.surface is not None and any(getattr(args, k, None) is not None for k in ("spacing", "units",
                                                                                        "channel")):
        raise WaveopticsError("the waveoptics plugin reads --surface itself and cannot take --spacing, --units or "
                              "--channel; use a file that states them (e.g. .npz, .x3p) or --bsdf measured")
    if kw["surface"] is not None and not isinstance(kw["surface"], str):
        raise WaveopticsError("the waveoptics plugin reads a nano height field from a file; this scene generates "
                              "one: use --bsdf measured")
    names = {"wavelength_step_nm": "wavelength_step"}
    return {names.get(k, k): v for k, v in kw.items() if v is not None}


def model_description(args, kw: dict) -> dict:
    """The model's parameters *kw* (:func:`model_parameters`) as given, for summaries and file descriptions."""
    if getattr(args, "scene", None):
        d = {k: v for k, v in kw.items() if k not in ("surface", "nano")}
        d.update(scene=str(args.scene), scene_material=args.scene_material,
                 nano=kw["nano"] if kw["nano"] is not None else "height field of the scene")
        return d
    d = {k: getattr(args, k) for k in ("material", "alpha", "alpha_y", "ndf", "diffraction", "kd", "diffuse",
                                       "wavelength_step", "resolution", "exact", "multiple_scattering")}
    if args.surface:
        d["surface"] = args.surface
    else:
        d["nano"] = args.nano or DEFAULT_NANO
    return d
