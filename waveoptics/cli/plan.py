"""``waveoptics plan SCENE``: which effects a scene needs, with the reason for every decision and the cost."""
from __future__ import annotations

from ..errors import WaveopticsError
from ._common import add_common, emit


def add_force(p) -> None:
    """``--force EFFECT[=VALUE]`` (repeatable), shared with ``waveoptics run``."""
    p.add_argument("--force", action="append", default=[], metavar="EFFECT[=VALUE]",
                   help="override a decision: diffraction[=on|off], diffuse=on|off, solver=psd|fft|direct, "
                        "precision=float32|float64, directions=hemisphere|views (repeatable)")
    p.add_argument("--max-resolution", type=int, metavar="N",
                   help="cap the direction grid the planner may choose (cells per side)")


def register(sub):
    p = sub.add_parser(
        "plan", help="plan a scene: which physical effects matter, which solver, grid and wavelengths",
        description="Read a scene TOML file and decide, for every material under every light, whether nano-scale "
                    "diffraction matters, the diffuse term, the solver, the direction grid, the wavelengths and "
                    "the precision, with the physical reason for each decision and an estimated time from a cost "
                    "model calibrated on this machine. Nothing is written.")
    p.add_argument("scene", metavar="SCENE", help="scene file (.toml), see examples/scenes/")
    add_force(p)
    add_common(p)
    p.set_defaults(func=run)


def make_plan(args):
    """Load the scene and plan it from the parsed arguments (used by ``plan`` and ``run``)."""
    from .. import planning
    from ..planning import scene


    if args.max_resolution is not None and not (8 <= args.max_resolution <= 2048):
        raise WaveopticsError(f"--max-resolution {args.max_resolution} is not allowed; use 8..2048")
    force = planning.parse_force(args.force)
    sc = scene.load(args.scene)
    return planning.plan_scene(sc, force=force, device=args.device, max_resolution=args.max_resolution)


def run(args):
    plan = make_plan(args)
    emit(args, plan.as_dict(), plan.table())
    return 0
