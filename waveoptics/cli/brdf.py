"""``waveoptics brdf``: evaluate a BRDF model at given directions and wavelengths, or its directional albedo.

The command is shared by all BRDF models. Each model is one entry of :data:`MODELS`: a function adding its
options (in its own argument group) and evaluator functions; direction and wavelength parsing, looping and the
text/JSON output live here once. Adding a model (e.g. ``kirchhoff`` with ``--surface FILE --solver ...``)
means adding one :class:`Model` entry.

JSON output: ``{"model": ..., "values": [{"incident": [θ, φ], "outgoing": [θ, φ], "wavelength_nm": λ,
"brdf": f}, ...]}`` with f in 1/sr (not multiplied by cos θ_o), or with ``--albedo``
``{"model": ..., "albedo": [{"incident": [θ, φ], "wavelength_nm": λ, "albedo": E}, ...]}``.
"""
from __future__ import annotations

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
    evaluate : callable(args, wi, wo, wavelength_nm) -> ndarray (n_λ, n_in, n_out)
        BRDF in 1/sr for unit directions wi (n_in, 3) and wo (n_out, 3).
    albedo : callable(args, wi, wavelength_nm) -> ndarray (n_λ, n_in)
        Directional albedo ∫ f cos θ_o dω_o.
    describe : callable(args) -> dict
        Model parameters echoed in the JSON output.
    help : str
    components : callable(args, wi, wo, wavelength_nm) -> dict, optional
        Named parts of the BRDF (e.g. the polarized ss, sp, ps, pp BRDFs), listed per value in the JSON output.
    """

    add_arguments: Callable
    evaluate: Callable
    albedo: Callable
    describe: Callable
    help: str
    components: Callable | None = None   # (args, wi, wo, wavelength_nm) -> {name: ndarray (n_λ, n_in, n_out)}


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
           note="microfacet and twoscale; NumPy, exact or one Fresnel; off by default")
    g.add_argument("--no-tradeoff", action="store_true",
                   help="do not weight the diffuse term by (1 - F(θi))(1 - F(θo)) / (1 - F̄)")
    option(g, "--backend", choices=["numpy", "opencl"], default="numpy", note="albedo always uses NumPy")
    option(g, "--precision", choices=["float32", "float64"], default="float32")


def _microfacet_params(args, wavelength_nm) -> dict:
    """Keyword arguments of microfacet.brdf for these options; Fresnel inputs per wavelength (n_λ,)."""
    from .. import brdf
    import numpy as np


    ndf, ndf_shape, alpha_y = args.ndf, args.ndf_shape, args.alpha_y
    if args.micro_surface is not None or args.ndf == "tabulated":
        ndf, ndf_shape, alpha, alpha_y = _measured_ndf(args)
    else:
        alpha = _alpha(args)
    if args.material is not None and args.ior is not None:
        raise WaveopticsError("give only one of --material NAME and --ior N+Kj")
    spec = args.material if args.material is not None else args.ior
    if spec is None:
        if args.fresnel != "one":
            raise WaveopticsError("the microfacet model needs --material NAME or --ior N+Kj "
                                  "(or --fresnel one for a white furnace)")
        fi = {"fresnel": "one", "eta": None, "F0": None}
    else:
        fi = brdf.fresnel_inputs(spec, wavelength_nm, args.fresnel)
        _report_clamped(spec, wavelength_nm, args)
    if not np.isfinite(args.sigma) or not 0 <= args.sigma <= 90:
        raise WaveopticsError(f"--diffuse-sigma {args.sigma!r} is not allowed; the Oren-Nayar roughness must be in "
                              "[0, 90] degrees")
    if args.diffuse == "burley" and not 0 <= args.diffuse_roughness <= 1:
        raise WaveopticsError(f"--diffuse-roughness {args.diffuse_roughness!r} is not allowed; it must be in [0, 1]")
    sigma = args.diffuse_roughness if args.diffuse == "burley" else float(np.radians(args.sigma))
    return dict(alpha=alpha, alpha_y=alpha_y, ndf=ndf, shadowing=args.shadowing, ndf_shape=ndf_shape,
                diffuse=args.diffuse, kd=args.kd, sigma=sigma,
                tradeoff=not args.no_tradeoff, **fi)


def _measured_ndf(args):
    """(ndf, slope table, α, α_y) from --micro-surface: the NDF is the height field's slope law; α and α_y are
    the Beckmann-equivalent widths √2 × rms slope, which place the albedo quadrature's nodes."""
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
            field = surfaces.open_large(args.micro_surface, spacing=_spacing(args), units=getattr(args, "units", None))
        else:
            field = surfaces.load(args.micro_surface, spacing=getattr(args, "spacing", None),
                                  units=getattr(args, "units", None), channel=args.channel)
        table = brdf.footprint_ndf(field, fp)
    else:
        hf = surfaces.load(args.micro_surface, spacing=getattr(args, "spacing", None),
                           units=getattr(args, "units", None), channel=getattr(args, "channel", None))
        table = brdf.slope_table(hf)
    micro = brdf.Micro.from_slopes(table)
    return "tabulated", table, micro.alpha, micro.alpha_y


def _spacing(args):
    """--spacing as (dx, dy) in m, or None."""
    from ..units import parse_length

    sp = getattr(args, "spacing", None)
    if sp is None:
        return None
    parts = [parse_length(x, name="spacing") for x in str(sp).split(",")]
    return parts[0], parts[-1]


def _alpha(args) -> float:
    """α from --alpha or --roughness (exactly one)."""
    from .. import brdf

    if (args.alpha is None) == (args.roughness is None):
        raise WaveopticsError(f"give exactly one of --alpha A or --roughness R for --model {args.model}")
    return args.alpha if args.alpha is not None else float(brdf.alpha_from_roughness(args.roughness))


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


def _per_wavelength(kw: dict, n_axes: int) -> dict:
    """Reshape the per-wavelength arrays of *kw* to (n_λ, 1, ..., 1) for NumPy broadcasting."""
    import numpy as np

    out = dict(kw)
    for key in ("eta", "F0"):
        if out.get(key) is not None:
            out[key] = np.asarray(out[key]).reshape((-1,) + (1,) * n_axes)
    return out


def _ms_brdf(args, kw):
    """The microfacet BRDF function with multiple-scattering compensation (:class:`waveoptics.MicrofacetBRDF`)."""
    from .. import brdf

    if args.backend == "opencl":
        raise WaveopticsError("--multiple-scattering is evaluated with NumPy; drop --backend opencl")
    if args.fresnel not in ("exact", "one"):
        raise WaveopticsError(f"--multiple-scattering needs --fresnel exact or one, not {args.fresnel!r}")
    spec = args.material if args.material is not None else args.ior
    micro = brdf.Micro(alpha=kw["alpha"], alpha_y=kw["alpha_y"], ndf=kw["ndf"], shadowing=kw["shadowing"],
                       ndf_shape=kw["ndf_shape"])
    # with --fresnel one and no material the index is never used (F = 1); a dielectric keeps the diffuse term
    return brdf.MicrofacetBRDF(spec if spec is not None else "1.5", micro, kd=kw["kd"], diffuse=kw["diffuse"],
                               fresnel=args.fresnel, diffuse_sigma=kw["sigma"], multiple_scattering=True)


def _microfacet_evaluate(args, wi, wo, wavelength_nm):

    from .. import brdf
    from ..runtime import get_runtime
    import numpy as np

    kw = _microfacet_params(args, wavelength_nm)
    n_w = len(wavelength_nm)
    if args.multiple_scattering:
        lam = np.asarray(wavelength_nm, dtype=float)
        return _ms_brdf(args, kw).eval(wi[None, :, None, :], wo[None, None, :, :], lam[:, None, None])
    if args.backend == "opencl":

        a = np.repeat(wi, len(wo), axis=0)
        b = np.tile(wo, (len(wi), 1))
        fk = dict(kw)
        for key in ("eta", "F0"):
            if fk.get(key) is None:
                fk.pop(key)
        f = brdf.brdf_cl(a, b, runtime=get_runtime(args.device), precision=args.precision, **fk)
        return np.broadcast_to(f, (n_w, a.shape[0])).reshape(n_w, len(wi), len(wo))
    f = brdf.brdf(wi[None, :, None, :], wo[None, None, :, :], **_per_wavelength(kw, 2))
    return np.broadcast_to(f, (n_w, len(wi), len(wo)))


def _microfacet_albedo(args, wi, wavelength_nm):

    from .. import brdf
    import numpy as np

    kw = _microfacet_params(args, wavelength_nm)
    if args.multiple_scattering:
        b = _ms_brdf(args, kw)
        lam = np.asarray(wavelength_nm, dtype=float)
        out = [b.albedo(w[None, :], lam) for w in progress(wi, desc="albedo", args=args)]
        return np.stack(out, axis=-1)
    kw = _per_wavelength(kw, 1)
    out = [brdf.albedo(w, **kw) for w in progress(wi, desc="albedo", args=args)]
    return np.broadcast_to(np.stack(out, axis=-1), (len(wavelength_nm), len(wi)))


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


def _kirchhoff_setup(args, wavelength_nm):

    from ..materials.database import get_material
    from ..materials.fresnel import F_schlick
    from ..runtime import get_runtime

    if not args.surface:
        raise WaveopticsError("--model kirchhoff needs --surface FILE")
    if args.material is not None and args.ior is not None:
        raise WaveopticsError("give only one of --material NAME and --ior N+Kj")
    spec = args.material if args.material is not None else args.ior
    if args.fresnel == "one" or spec is None:
        if args.fresnel != "one":
            raise WaveopticsError("the kirchhoff model needs --material NAME or --ior N+Kj (or --fresnel one)")
        F = None
    else:

        mat = get_material(spec)
        _report_clamped(spec, wavelength_nm, args)
        if args.fresnel == "schlick":

            def F(c, w, _m=mat):
                return F_schlick(c, _m.F0(w))
        else:
            F = mat
    hf = load_surface(args)
    rt = None
    if args.backend == "opencl" and args.solver == "direct":

        rt = get_runtime(args.device)
    return hf, F, rt


def _kirchhoff_evaluate(args, wi, wo, wavelength_nm):

    from .. import scatter
    import numpy as np

    hf, F, rt = _kirchhoff_setup(args, wavelength_nm)
    out = [scatter.brdf(hf, w, wo, wavelength_nm, F, solver=args.solver, backend=args.backend,
                            precision=args.precision, window_name=args.window, resolution=args.resolution,
                            realizations=args.realizations, runtime=rt, diffraction=args.diffraction,
                            polarization=args.polarization)
           for w in progress(wi, desc="kirchhoff", args=args)]
    return np.stack(out, axis=1)


def _kirchhoff_albedo(args, wi, wavelength_nm):

    from .. import scatter
    import numpy as np

    hf, F, rt = _kirchhoff_setup(args, wavelength_nm)
    out = [scatter.scatter(hf, w, wavelength_nm, F, solver=args.solver, backend=args.backend,
                               precision=args.precision, window_name=args.window,
                               resolution=args.resolution or 256, realizations=args.realizations,
                               runtime=rt, diffraction=args.diffraction,
                               polarization=args.polarization).albedo
           for w in progress(wi, desc="albedo", args=args)]
    return np.stack(out, axis=1)


def _kirchhoff_describe(args) -> dict:
    return {k: getattr(args, k) for k in ("surface", "solver", "material", "ior", "fresnel", "backend",
                                          "precision", "window", "realizations", "resolution", "diffraction")}


# ----------------------------------------------------------------------------------------------------------
# rayleigh-rice (first-order perturbation from PSD statistics; logic in waveoptics.scatter.perturbation)


def _rayleigh_rice_arguments(g) -> None:
    option(g, "--nano", note="rayleigh-rice: statistics, or --surface FILE whose periodogram is the PSD; "
                             "twoscale: default " + _default_nano())
    option(g, "--polarization", choices=POLARIZATIONS, default="unpolarized", note="rayleigh-rice and kirchhoff")


def _rayleigh_rice_setup(args, wavelength_nm):
    """(PSD: a model from --nano statistics or a height field's periodogram from --surface, permittivity ε (n_λ,))."""
    from .. import surfaces
    from ..materials.database import get_material
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
    if args.material is not None and args.ior is not None:
        raise WaveopticsError("give only one of --material NAME and --ior N+Kj")
    spec = args.material if args.material is not None else args.ior
    if spec is None:
        raise WaveopticsError("--model rayleigh-rice needs --material NAME or --ior N+Kj (the substrate's index)")
    mat = get_material(spec)
    if mat.schlick_only:
        raise WaveopticsError(f"--material {spec!r} gives only F0; rayleigh-rice needs a complex index "
                              "(a preset, shelf/book/page or --ior)")
    _report_clamped(spec, wavelength_nm, args)
    return psd, mat.eta(wavelength_nm) ** 2


def _rayleigh_rice_evaluate(args, wi, wo, wavelength_nm):
    from .. import scatter

    psd, eps = _rayleigh_rice_setup(args, wavelength_nm)
    return scatter.rayleigh_rice_brdf(wi[None, :, None, :], wo[None, None, :, :],
                                      wavelength_nm[:, None, None], psd, eps[:, None, None], args.polarization)


def _rayleigh_rice_components(args, wi, wo, wavelength_nm) -> dict:
    from .. import scatter

    psd, eps = _rayleigh_rice_setup(args, wavelength_nm)
    return scatter.rayleigh_rice_components(wi[None, :, None, :], wo[None, None, :, :],
                                            wavelength_nm[:, None, None], psd, eps[:, None, None])


def _rayleigh_rice_albedo(args, wi, wavelength_nm):
    import numpy as np

    from .. import scatter

    psd, eps = _rayleigh_rice_setup(args, wavelength_nm)
    grid = scatter.DirectionGrid.hemisphere(args.resolution or 512)
    wo = grid.directions()
    out = np.empty((len(wavelength_nm), len(wi)))
    for i, w in enumerate(wi):
        f = scatter.rayleigh_rice_brdf(w, wo[None], wavelength_nm[:, None, None], psd, eps[:, None, None],
                                       args.polarization)
        out[:, i] = scatter.integrate(np.where(grid.inside, f, 0.0), grid)
    return out


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


def _twoscale_setup(args, wavelength_nm, wi=None):
    """The two-scale BRDF function of the options, built once per command (evaluation, parts and albedo share it).

    With ``--nano`` statistics it is :class:`waveoptics.brdf.TwoScaleBRDF` (exact at any direction pair); with a
    ``--surface`` height field, :class:`waveoptics.brdf.TabulatedTwoScaleBRDF` with its incidence nodes at the
    requested incident angles (so nothing is interpolated in θ_i) and 4 light azimuths."""
    import numpy as np

    key = (tuple(np.asarray(wavelength_nm, dtype=float).tolist()),
           None if wi is None else tuple(np.round(np.degrees(np.arccos(np.clip(wi[:, 2], -1, 1))), 9)))
    cache = args.__dict__.setdefault("_brdf_functions", {})
    if key not in cache:
        cache[key] = _twoscale_build(args, wavelength_nm, wi)
    return cache[key]


def _twoscale_build(args, wavelength_nm, wi):
    import numpy as np

    from .. import brdf
    from ..request import make_nano

    if args.surface and args.nano:
        raise WaveopticsError("give only one of --nano MODEL:params and --surface FILE for --model twoscale")
    if args.polarization != "unpolarized":
        raise WaveopticsError(f"--polarization {args.polarization} is not available for --model twoscale "
                              "(unpolarized only; polarized two-scale lobes: 'waveoptics simulate --polarization')")
    if args.material is not None and args.ior is not None:
        raise WaveopticsError("give only one of --material NAME and --ior N+Kj")
    spec = args.material if args.material is not None else args.ior
    if spec is None and args.fresnel != "one":
        raise WaveopticsError("the twoscale model needs --material NAME or --ior N+Kj (or --fresnel one)")
    if args.fresnel == "schlick":
        raise WaveopticsError("--fresnel schlick is not available for --model twoscale; use exact or one")
    if spec is not None:
        _report_clamped(spec, wavelength_nm, args)
    if not np.isfinite(args.sigma) or not 0 <= args.sigma <= 90:
        raise WaveopticsError(f"--diffuse-sigma {args.sigma!r} is not allowed; the Oren-Nayar roughness must be in "
                              "[0, 90] degrees")
    if args.micro_surface is not None or args.ndf == "tabulated":   # the NDF of a micro height field's slopes
        _, table, _, _ = _measured_ndf(args)
        micro = brdf.Micro.from_slopes(table, args.shadowing)
    else:
        micro = brdf.Micro(alpha=_alpha(args), alpha_y=args.alpha_y, ndf=args.ndf, shadowing=args.shadowing,
                           ndf_shape=args.ndf_shape)
    common = dict(material=spec if spec is not None else "aluminium", micro=micro, kd=args.kd,
                  diffuse=args.diffuse, fresnel=args.fresnel,
                  diffuse_sigma=float(np.radians(args.sigma)), diffraction=args.diffraction,
                  multiple_scattering=args.multiple_scattering)
    if args.surface:
        nano = brdf.Nano(surface=load_surface(args))
        thetas = (0.0,) if wi is None else tuple(sorted(set(
            float(t) for t in np.round(np.degrees(np.arccos(np.clip(wi[:, 2], -1, 1))), 9))))
        return brdf.TabulatedTwoScaleBRDF(nano=nano, wavelengths_nm=tuple(np.asarray(wavelength_nm, dtype=float)),
                                          resolution=args.resolution or 128, thetas_deg=thetas, solver="fft",
                                          **common)
    return brdf.TwoScaleBRDF(nano=make_nano(args.nano or _default_nano(), wavelength_nm), **common)


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
# table (a BRDF table file as a function; logic in waveoptics.distributed.table.open_table)


def _table_arguments(g) -> None:
    g.add_argument("--table", metavar="FILE", help="BRDF table written by 'waveoptics table' (.h5)")


def _table_setup(args, wavelength_nm, wi=None):
    from ..distributed.table import open_table

    if not args.table:
        raise WaveopticsError("--model table needs --table FILE (a table written by 'waveoptics table')")
    return open_table(args.table)


def _table_describe(args) -> dict:
    return {"table": args.table}


# ----------------------------------------------------------------------------------------------------------
# models that are BRDF functions (waveoptics.brdf.protocol): evaluation, parts and albedo come from the object


def _function_model(add_arguments, setup, describe, help_text) -> Model:
    """A :class:`Model` whose *setup(args, wavelength_nm, wi)* returns a BRDF function with ``eval``, ``eval_parts``
    and ``albedo`` (directions (n, 3), wavelengths (n_λ,); results (n_λ, n_in, n_out) and (n_λ, n_in))."""

    def evaluate(args, wi, wo, wavelength_nm):
        return setup(args, wavelength_nm, wi).eval(wi[None, :, None, :], wo[None, None, :, :],
                                                   wavelength_nm[:, None, None])

    def components(args, wi, wo, wavelength_nm):
        return setup(args, wavelength_nm, wi).eval_parts(wi[None, :, None, :], wo[None, None, :, :],
                                                         wavelength_nm[:, None, None])

    def albedo(args, wi, wavelength_nm):
        return setup(args, wavelength_nm, wi).albedo(wi[None, :, :], wavelength_nm[:, None])

    return Model(add_arguments, evaluate, albedo, describe, help_text, components=components)


#: BRDF models offered by ``waveoptics brdf --model``
MODELS: dict[str, Model] = {
    "microfacet": Model(_microfacet_arguments, _microfacet_evaluate, _microfacet_albedo, _microfacet_describe,
                        "geometric-optics microfacet BRDF (Cook-Torrance / Walter et al. 2007) with a diffuse term"),
    "kirchhoff": Model(_kirchhoff_arguments, _kirchhoff_evaluate, _kirchhoff_albedo, _kirchhoff_describe,
                       "wave-optics Kirchhoff BRDF of a height-field file (waveoptics.scatter)"),
    "rayleigh-rice": Model(_rayleigh_rice_arguments, _rayleigh_rice_evaluate, _rayleigh_rice_albedo,
                           _rayleigh_rice_describe,
                           "first-order Rayleigh-Rice BRDF of a smooth rough surface from its PSD, with the "
                           "polarization factor Q (s, p, unpolarized; JSON also gives ss, sp, ps, pp)",
                           components=_rayleigh_rice_components),
    "twoscale": _function_model(_twoscale_arguments, _twoscale_setup, _twoscale_describe,
                                "two-scale BRDF: micro NDF carrying PSD nano-roughness (Holzschuch & Pacanowski "
                                "2017), evaluated at the given directions; JSON also gives its coherent, diffraction "
                                "and diffuse parts"),
    "table": _function_model(_table_arguments, _table_setup, _table_describe,
                             "a BRDF table file (waveoptics table) as a function: its diffracted lobes interpolated "
                             "between incidences relative to the specular direction, coherent and diffuse parts "
                             "exact; at the table's wavelengths"),
}


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
    p.set_defaults(func=run)


def run(args) -> int:

    import numpy as np

    model = MODELS[args.model]
    if getattr(args, "diffuse", None) in DIFFUSE_ALIASES:
        args.diffuse = DIFFUSE_ALIASES[args.diffuse]
    if getattr(args, "multiple_scattering", False) and args.model not in ("microfacet", "twoscale"):
        raise WaveopticsError(f"--multiple-scattering applies to --model microfacet and twoscale, not {args.model!r}")
    wl = parse_wavelengths(args.wavelengths, name="--wavelengths")
    inc = [parse_direction(t, name="--incident") for t in args.incident]
    wi = direction_from_angles([t for t, _ in inc], [p for _, p in inc])
    head = {"model": args.model, "parameters": model.describe(args),
            "units": {"brdf": "1/sr", "albedo": "1", "wavelength_nm": "nm", "incident": "deg", "outgoing": "deg"}}
    if args.albedo:
        E = np.asarray(model.albedo(args, wi, wl))
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
    f = np.asarray(model.evaluate(args, wi, wo, wl))
    parts = model.components(args, wi, wo, wl) if model.components is not None else {}
    rows = [{"incident": list(inc[i]), "outgoing": list(out[k]), "wavelength_nm": float(wl[j]),
             "brdf": float(f[j, i, k]),
             **({"components": {c: float(v[j, i, k]) for c, v in parts.items()}} if parts else {})}
            for i in range(len(inc)) for k in range(len(out)) for j in range(len(wl))]
    text = "\n".join(f"incident θ={r['incident'][0]:g}° φ={r['incident'][1]:g}°  "
                     f"outgoing θ={r['outgoing'][0]:g}° φ={r['outgoing'][1]:g}°  λ={r['wavelength_nm']:g} nm  "
                     f"f={r['brdf']:.6g} 1/sr" for r in rows)
    emit(args, {**head, "values": rows}, text)
    return 0
