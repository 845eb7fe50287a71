"""``waveoptics scatter``: per-wavelength Kirchhoff lobes of a height-field file (logic in
:mod:`waveoptics.scatter`).

Writes ``OUTDIR/lobes.exr`` (spectral OpenEXR, one ``T.<λ>nm`` layer per wavelength: the BRDF in 1/sr over the
direction-cosine plane u = sinθ cosφ, v = sinθ sinφ), ``OUTDIR/summary.json`` (``wavelengths_nm``, ``albedo``,
``coherent_specular_fraction``, ``scattered_fraction``: lists, one entry per wavelength; ``timings_s``) and a
``lobes.png`` preview.
"""
from __future__ import annotations

import sys
import warnings

from ..errors import WaveopticsError
from ..io.files import prepare_outdir
from ..vocabulary import DIFFRACTION, POLARIZATIONS
from ..units import parse_direction, parse_wavelengths
from ._common import add_common, add_output, add_surface, emit, load_surface, progress, warn_if_long
from ._options import option


def register(sub) -> None:
    p = sub.add_parser("scatter", help="Kirchhoff scattering lobes of a surface, per wavelength",
                       description="Compute the Kirchhoff (wave-optics) BRDF of a height-field patch over the "
                                   "whole projected hemisphere for each wavelength, with its directional albedo "
                                   "and the coherent (specular) and scattered fractions.")
    add_surface(p, required=True)
    option(p, "--material", required=True, note="or 'one' for F = 1")
    option(p, "--incident", required=True)
    option(p, "--wavelengths", default="400:700:10")
    option(p, "--diffraction", default="kirchhoff", choices=DIFFRACTION)
    option(p, "--polarization", default="unpolarized", choices=POLARIZATIONS,
           note="each facet reflects its own s/p split; needs a material with a complex index")
    option(p, "--solver", choices=("fft", "direct"), default="fft",
           note="fft: chirp-z transforms with a banded Taylor series in v_z; direct: the Kirchhoff sum")
    option(p, "--resolution", default=256)
    option(p, "--max-memory")
    option(p, "--realizations", default=1, note="1: the whole patch")
    p.add_argument("--order", default="auto", metavar="K",
                   help="fft solver: 'auto' (exact to 1e-8) or a fixed Taylor order about the specular v_z; "
                        "0 freezes v_z (paraxial)")
    option(p, "--window", default="hann", note="gaussian:SIGMA (a length) is a Gaussian of that width centred on "
                                                "the patch")
    option(p, "--footprint", note="the BRDF of that footprint only (its Gaussian is the window; a .npy file is "
                                  "memory-mapped and only the footprint's patch is read)")
    option(p, "--coherence", note="with --footprint; default: the whole footprint is coherent")
    option(p, "--detrend", choices=("mean", "plane", "none"), default="mean",
           note="of each patch, weighted by the window")
    option(p, "--precision", choices=("float32", "float64"), default="float32", note="direct solver")
    option(p, "--backend", choices=("opencl", "numpy"), default="opencl", note="direct solver")
    add_output(p)
    add_common(p)
    p.set_defaults(func=run)


def _order(text):

    if str(text) == "auto":
        return "auto"
    try:
        return int(text)
    except ValueError:
        raise WaveopticsError(f"--order {text!r} is not allowed; use 'auto' or an integer >= 0") from None


def _footprint(args):
    """(Footprint or None, the surface): with --footprint a .npy file is memory-mapped."""
    from .. import surfaces

    if args.footprint is None:
        if args.coherence is not None:
            raise WaveopticsError("--coherence is the coherence area inside a --footprint; give one")
        return None, load_surface(args)
    if args.realizations != 1:
        raise WaveopticsError("--footprint is one patch; drop --realizations")
    if args.window != "hann":
        raise WaveopticsError("--footprint sets the window (its Gaussian); drop --window")
    fp = surfaces.Footprint.parse(args.footprint)
    if str(args.surface).lower().endswith(".npy") and args.channel is None:
        from .brdf import spacing_from_args

        return fp, surfaces.open_large(args.surface, spacing=spacing_from_args(args), units=args.units)
    return fp, load_surface(args)


def _coherence(args):
    from ..units import parse_length

    return None if args.coherence is None else parse_length(args.coherence, name="coherence")


def _field_info(field, res) -> dict:
    """What the output says about a footprint's surface: the file, its grid and the footprint."""
    return {"source": str(getattr(field, "path", field.meta.get("source") if hasattr(field, "meta") else "")),
            "samples": list(field.shape[::-1]), "spacing_m": [field.dx, field.dy],
            "memory_mapped": not hasattr(field, "heights"), "footprint": res.info.get("footprint")}


def run(args) -> int:

    from .. import scatter
    from ..materials.database import fresnel_function
    from ..runtime import get_runtime

    wl = parse_wavelengths(args.wavelengths)
    theta, phi = parse_direction(args.incident, name="--incident")
    order = _order(args.order)
    fp, field = _footprint(args)
    hf = field if fp is None else None
    fresnel_function(args.material)      # refuse a bad material before computing
    if fp is None:
        scatter.tile_layout(hf.shape, args.realizations)   # before the time estimate: an error is its only line
    scatter.check_request_memory(args.resolution, len(wl), field.shape if fp is None else (0, 0), args.max_memory)
    if fp is None and (args.solver != "direct" or args.backend == "opencl"):
        from ..planning.estimate import scatter_time

        warn_if_long(scatter_time(hf, (theta, phi), wl, args.resolution, args.solver, realizations=args.realizations,
                                  device=args.device, precision=args.precision),
                     "lower --resolution, the number of --wavelengths or --realizations")
    prepare_outdir(args.output, overwrite=args.overwrite, expected=scatter.SCATTER_FILES)
    rt = get_runtime(args.device) if args.solver == "direct" and args.backend == "opencl" else None
    bar = progress(total=len(wl) * max(1, args.realizations), desc="scatter", args=args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", scatter.DiffractionWarning)
        common = dict(solver=args.solver, resolution=args.resolution, order=order, detrend=args.detrend,
                      precision=args.precision, backend=args.backend, diffraction=args.diffraction,
                      polarization=args.polarization, runtime=rt, max_memory=args.max_memory)
        if fp is None:
            res = scatter.scatter(hf, (theta, phi), wl, args.material, realizations=args.realizations,
                                  window_name=args.window, progress=bar.update, **common)
        else:
            res = scatter.footprint_scatter(field, fp, (theta, phi), wl, args.material, coherence_m=_coherence(args),
                                            **common)
    surface_info = hf.provenance() if hf is not None else _field_info(field, res)
    bar.close()
    extra = {"surface": str(args.surface), "material": str(args.material)}
    if rt is not None:
        extra["device"] = rt.name
    paths = scatter.write_scatter(res, args.output, overwrite=args.overwrite, header=extra,
                                  surface_info=surface_info)
    if not args.json:
        for w in caught:
            print(f"waveoptics scatter: warning: {w.message}", file=sys.stderr)
    rows = "\n".join(f"{w:8.2f} nm  albedo {a:.6f}  coherent {c:.6f}  scattered {s:.6f}"
                     for w, a, c, s in zip(res.wavelengths_nm, res.albedo, res.coherent_specular_fraction,
                                           res.scattered_fraction))
    text = (f"{rows}\nwrote {', '.join(str(p) for p in paths.values())} "
            f"({res.timings_s['total']:.3g} s, solver {res.solver})")
    emit(args, {**res.summary(), **extra, "surface_info": surface_info, "outputs": {k: str(v) for k, v in paths.items()}}, text)
    return 0
