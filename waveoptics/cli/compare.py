"""``waveoptics compare``: both models over a range of incident angles (table + plot)."""
from __future__ import annotations

import os

from ..errors import WaveopticsError
from ..units import ANGLE_UNITS, check_theta, parse_number_list
from ._common import add_common, add_output, angle_arg, emit
from ._options import option, renamed


def register(sub):
    from .simulate import add_scene_options

    p = sub.add_parser("compare", help="two-scale vs microfacet over incident angles: energy, lobe width, tail, ΔE",
                       description="Runs the two-scale model and the plain microfacet model on one configuration "
                                   "over a range of incident angles and reports albedo, lobe FWHM, the energy in the "
                                   "tail beyond --tail degrees from the mirror direction, and ΔE2000 of the albedo "
                                   "colour and of rendered spheres. Same surface options as 'simulate'.")

    add_scene_options(p)
    renamed(p, "compare", "--accuracy", dest="delta_e")
    option(p, "--incident-angles", default="0:80:10")
    renamed(p, "compare", "--angles", dest="incident_angles")
    p.add_argument("--tail", type=angle_arg, default=10.0, metavar="DEG",
                   help="tail = energy farther than this from the mirror direction (default 10°)")
    add_output(p, required=False, note="a directory: also write compare.json, compare.csv and compare.png")
    option(p, "--max-memory")
    add_common(p)
    p.set_defaults(func=run)


def run(args):


    from .. import compare as cmp
    from .. import io
    from .. import simulate as sim_mod
    from .simulate import request_from_args, simulation_from_args

    angles = parse_number_list(args.incident_angles, name="angles_deg", units=ANGLE_UNITS)
    check_theta(angles, name="--incident-angles")
    if (angles >= 90).any():
        raise WaveopticsError("--incident-angles must stay below 90 degrees (the light must be above the horizon)")
    if not (0 < args.tail < 90):
        raise WaveopticsError(f"--tail {args.tail!r} is not allowed; use an angle in (0, 90) degrees")
    req = request_from_args(args)
    sim_mod.check_request_memory(req, max_memory=args.max_memory, sphere_needed=True)   # before anything is created
    if args.output:
        io.prepare_outdir(args.output, overwrite=args.overwrite, expected=cmp.OUTPUTS)
    sim = simulation_from_args(args, req=req)
    rows = cmp.compare(sim, angles, tail_deg=args.tail)
    data = {"parameters": sim.params, "tail_deg": args.tail, "rows": rows,
            "units": {"theta_i_deg": "deg", "albedo_Y_wave": "1 (luminance Y of the albedo's colour)",
                      "albedo_Y_microfacet": "1", "fwhm_deg_wave": "deg (in the plane of incidence)",
                      "fwhm_deg_microfacet": "deg", "tail_fraction_wave": "1 (share of the albedo)",
                      "tail_fraction_microfacet": "1", "delta_e2000_albedo": "CIEDE2000",
                      "delta_e2000_sphere_mean": "CIEDE2000", "delta_e2000_sphere_max": "CIEDE2000"}}
    if args.output:   # the three files appear as a set, compare.json (the manifest) last
        cmp.write_outputs(rows, data, args.output, tail_deg=args.tail,
                          title=f"{sim.params['material']}: two-scale vs microfacet ({sim.params['illuminant']})")
    emit(args, data, cmp.table_text(rows, args.tail) + (f"\nwrote {os.path.join(os.path.normpath(args.output), 'compare')}.{{json,csv,png}}"
                                                         if args.output else ""))
    return 0
