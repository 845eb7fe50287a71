"""``waveoptics run SCENE -o OUTDIR``: execute a scene's plan and write the outputs it asks for."""
from __future__ import annotations

import os

from ._common import add_common, add_output, emit, progress
from .plan import add_force, make_plan


def register(sub):
    p = sub.add_parser(
        "run", help="plan a scene and simulate only what it needs; writes its outputs and plan.json",
        description="Plan the scene (see 'waveoptics plan'), run the plan and write the outputs the scene asks "
                    "for (spectral/RGB OpenEXR and PNG of the BRDF, sphere renders, tables at the view "
                    "directions), results.json (colours at the view directions, albedos) and plan.json (the plan "
                    "with the measured time beside the estimate).")
    p.add_argument("scene", metavar="SCENE", help="scene file (.toml), see examples/scenes/")
    add_force(p)
    add_output(p)
    add_common(p)
    p.set_defaults(func=run)


def run(args):

    from .. import io
    from .. import planning

    planning.parse_force(args.force)   # a contradictory --force is refused before the output directory exists
    io.prepare_outdir(args.output, overwrite=args.overwrite, expected=["plan.json", "results.json"])  # before work
    plan = make_plan(args)
    io.prepare_outdir(args.output, overwrite=args.overwrite, expected=planning.output_files(plan))
    bar = progress(total=sum(e.evaluations for e in plan.entries), desc="run", args=args)
    try:
        data = planning.execute(plan, args.output, overwrite=args.overwrite, device=args.device,
                                progress=bar.update)
    finally:
        bar.close()
    lines = [plan.table(), ""]
    for m in data["materials"]:
        lines.append(f"{m['name']} under {m['light']}: estimated {m['estimated_time_s']:.3g} s, measured "
                     f"{m['measured_time_s']:.3g} s (+ {m['outputs_time_s']:.3g} s writing)")
    lines.append(f"outputs in {os.path.join(os.path.normpath(args.output), '')}: " + ", ".join(data["files"]))
    emit(args, data, "\n".join(lines))
    return 0
