"""``waveoptics scatter``: per-wavelength Kirchhoff lobes of a height-field file: the options build a
:class:`~waveoptics.scatter_job.ScatterRequest` (whose fields own their defaults) and
:func:`~waveoptics.scatter_job.scatter_job` runs it (logic in :mod:`waveoptics.scatter`).

Writes ``OUTDIR/lobes.exr`` (spectral OpenEXR, one ``T.<λ>nm`` layer per wavelength: the BRDF in 1/sr over the
direction-cosine plane u = sinθ cosφ, v = sinθ sinφ), ``OUTDIR/summary.json`` (``wavelengths_nm``, ``albedo``,
``coherent_specular_fraction``, ``scattered_fraction``: lists, one entry per wavelength; ``timings_s``) and a
``lobes.png`` preview.
"""
from __future__ import annotations

import sys

from ..scatter_job import ScatterRequest, scatter_default
from ..vocabulary import DETRENDS, DIFFRACTION, FIELD_BACKENDS, FIELD_SOLVERS, POLARIZATIONS, PRECISIONS
from ._common import add_common, add_output, add_surface, emit, progress, warn_if_long
from ._options import option

#: option dest → request field, where the two are spelled differently
DEST_FIELD = {"incident": "incident_deg", "wavelengths": "wavelengths_nm"}


def register(sub) -> None:
    d = scatter_default
    p = sub.add_parser("scatter", help="Kirchhoff scattering lobes of a surface, per wavelength",
                       description="Compute the Kirchhoff (wave-optics) BRDF of a height-field patch over the "
                                   "whole projected hemisphere for each wavelength, with its directional albedo "
                                   "and the coherent (specular) and scattered fractions.")
    add_surface(p, required=True)
    option(p, "--material", required=True, note="or 'one' for F = 1")
    option(p, "--incident", required=True)
    option(p, "--wavelengths", default=d("wavelengths_nm"))
    option(p, "--diffraction", default=d("diffraction"), choices=DIFFRACTION)
    option(p, "--polarization", default=d("polarization"), choices=POLARIZATIONS,
           note="each facet reflects its own s/p split; needs a material with a complex index")
    option(p, "--solver", choices=FIELD_SOLVERS, default=d("solver"),
           note="fft: chirp-z transforms with a banded Taylor series in v_z; direct: the Kirchhoff sum")
    option(p, "--resolution", default=d("resolution"))
    option(p, "--max-memory", default=d("max_memory"))
    option(p, "--realizations", default=d("realizations"), note="1: the whole patch")
    p.add_argument("--order", default=d("order"), metavar="K",
                   help="fft solver: 'auto' (exact to 1e-8) or a fixed Taylor order about the specular v_z; "
                        "0 freezes v_z (paraxial)")
    option(p, "--window", default=d("window"), note="gaussian:SIGMA (a length) is a Gaussian of that width "
                                                    "centred on the patch")
    option(p, "--footprint", default=d("footprint"),
           note="the BRDF of that footprint only (its Gaussian is the window; a .npy file is memory-mapped and "
                "only the footprint's patch is read)")
    option(p, "--coherence", default=d("coherence"), note="with --footprint; default: the whole footprint is "
                                                          "coherent")
    option(p, "--detrend", choices=DETRENDS, default=d("detrend"), note="of each patch, weighted by the window")
    option(p, "--precision", choices=PRECISIONS, default=d("precision"), note="direct solver")
    option(p, "--backend", choices=FIELD_BACKENDS, default=d("backend"), note="direct solver")
    add_output(p)
    add_common(p)
    p.set_defaults(func=run)


def request_from_args(args) -> ScatterRequest:
    """The :class:`~waveoptics.scatter_job.ScatterRequest` of the options (its fields validate them)."""
    names = [f for f in ScatterRequest.__dataclass_fields__ if f not in DEST_FIELD.values()]
    return ScatterRequest(incident_deg=args.incident, wavelengths_nm=args.wavelengths,
                          **{f: getattr(args, f) for f in names})


def run(args) -> int:

    from ..scatter_job import scatter_job

    req = request_from_args(args)

    def estimate(hf):
        """Announce (or refuse) a long run by this machine's cost model, before the output directory is made."""
        if req.solver != "direct" or req.backend == "opencl":
            from ..planning.estimate import scatter_time

            warn_if_long(scatter_time(hf, req.incident_deg, req.wavelengths_nm, req.resolution, req.solver,
                                      realizations=req.realizations, device=req.device, precision=req.precision),
                         "lower --resolution, the number of --wavelengths or --realizations")

    run_ = scatter_job(req, args.output, overwrite=args.overwrite, estimate=estimate,
                       progress=lambda **kw: progress(**kw, args=args))
    res = run_.result
    if not args.json:
        for w in run_.warnings:
            print(f"waveoptics scatter: warning: {w}", file=sys.stderr)
    rows = "\n".join(f"{w:8.2f} nm  albedo {a:.6f}  coherent {c:.6f}  scattered {s:.6f}"
                     for w, a, c, s in zip(res.wavelengths_nm, res.albedo, res.coherent_specular_fraction,
                                           res.scattered_fraction))
    text = (f"{rows}\nwrote {', '.join(str(p) for p in run_.paths.values())} "
            f"({res.timings_s['total']:.3g} s, solver {res.solver})")
    emit(args, run_.summary(), text)
    return 0
