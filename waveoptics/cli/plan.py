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
    p.add_argument("--recalibrate", action="store_true",
                   help="time this machine's cost model again (it is timed once and cached; also after an "
                        "upgrade), and plan afresh instead of answering from the cache of earlier plans")
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
    return planning.plan_scene(sc, force=force, device=args.device, max_resolution=args.max_resolution,
                               recalibrate=getattr(args, "recalibrate", False))


def plan_key(args) -> str | None:
    """Cache key of a plan: the scene's bytes, the bytes of every file it names (surfaces, spectra), the options
    and the device; None when the scene cannot be read (the planner then says why)."""
    import hashlib
    import json
    import os
    import tomllib
    from pathlib import Path

    from ..cache import file_digest

    scene = Path(args.scene)
    try:
        raw = scene.read_bytes()
        doc = tomllib.loads(raw.decode("utf-8"))
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    named = []

    def walk(v):
        if isinstance(v, dict):
            for x in v.values():
                walk(x)
        elif isinstance(v, list):
            for x in v:
                walk(x)
        elif isinstance(v, str) and len(v) < 4096:
            p = (scene.parent / os.path.expanduser(v))
            if p.is_file():
                named.append((v, file_digest(p)))

    walk(doc)
    key = {"scene": hashlib.sha256(raw).hexdigest(), "files": sorted(named), "force": sorted(args.force),
           "max_resolution": args.max_resolution,
           "device": args.device or os.environ.get("WAVEOPTICS_DEVICE", "")}
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()


def run(args):
    from .. import cache

    key = plan_key(args)
    hit = cache.get("plans", key) if key and not args.recalibrate else None
    if isinstance(hit, dict) and "data" in hit and "text" in hit:
        emit(args, {**hit["data"], "from_cache": True},
             hit["text"] + "\n(the plan of this scene made earlier on this machine; --recalibrate plans afresh)")
        return 0
    import json

    from ..io.files import to_json

    plan = make_plan(args)
    data, text = json.loads(to_json(plan.as_dict())), plan.table()
    if key:
        cache.put("plans", key, {"data": data, "text": text})
    emit(args, data, text)
    return 0
