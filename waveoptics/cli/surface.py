"""``waveoptics surface generate|stats|prepare|transform``: make height fields, measure them, level, crop and
deform them (logic in :mod:`waveoptics.surfaces`)."""
from __future__ import annotations

import inspect

from ..errors import WaveopticsError
from ._common import add_common, add_output, add_surface, emit, load_surface
from ._options import now_default, option, renamed

#: CLI option -> generator parameter (lengths stay strings with units; the generators parse them)
_MODEL_OPTIONS = {
    "sigma": ("--sigma", "rms height σ with unit, e.g. 5nm (gaussian, exponential, abc)"),
    "corr_length": ("--corr-length", "correlation length T with unit, e.g. 1.2um (gaussian, exponential)"),
    "A": ("--A", "ABC plateau A in m^4 (abc; alternative to --sigma)"),
    "B": ("--B", "ABC knee length B with unit, e.g. 10um (abc)"),
    "C": ("--C", "ABC fall-off exponent C > 2 (abc)"),
    "amplitude": ("--amplitude", "grating amplitude with unit, e.g. 20nm (sinusoid)"),
    "period": ("--period", "grating period with unit, e.g. 4um (sinusoid)"),
    "orientation_deg": ("--orientation", "direction in degrees from x: grating vector (sinusoid), mean scratch "
                                         "direction (scratches)"),
    "phase_deg": ("--phase", "grating phase at the patch centre, degrees (sinusoid)"),
    "count": ("--count", "number of scratches (scratches)"),
    "width": ("--width", "scratch full width at half depth with unit (scratches)"),
    "depth": ("--depth", "scratch depth with unit (scratches)"),
    "spread_deg": ("--spread", "scratch directions uniform within ± this many degrees (scratches)"),
    "length": ("--length", "scratch length with unit; default: across the patch (scratches)"),
    "variation": ("--variation", "relative spread of scratch width and depth, 0..1 (scratches)"),
    "size_flake": ("--flake-size", "mean flake diameter with unit, e.g. 5um (flakes)"),
    "tilt": ("--tilt", "rms tilt of the flakes per axis, degrees (flakes)"),
}
_FLOAT_PARAMS = {"A", "C", "orientation_deg", "phase_deg", "spread_deg", "variation", "tilt"}
#: what -o writes for the commands that write a height field
HEIGHT_FIELD_OUTPUT = "a height-field file: .npz .npy .exr .txt .csv .xyz, or .x3p .gwy .nc through SurfaceTopography"
MODELS = ("flat", "gaussian", "exponential", "abc", "sinusoid", "scratches", "flakes")
#: example fields (:data:`waveoptics.surfaces.EXAMPLES`; kept here so parsing imports nothing numerical)
EXAMPLES = ("brushed", "scratched", "flakes")


def register(sub):
    p = sub.add_parser("surface", help="generate height fields and measure their statistics",
                       description="Surface nanogeometry: generate random or deterministic height fields and "
                                   "compute rms height, slopes, correlation length, PSD fits.")
    ss = p.add_subparsers(dest="surface_command", metavar="ACTION", parser_class=type(p))
    ss.required = True

    g = ss.add_parser("generate", help="generate a height field and write it to a file",
                      description="Generate a height field (heights in metres) and write it as .npz, .npy "
                                  "(+ .json sidecar), .exr or a text grid, chosen by the extension of -o.")
    option(g, "--generator", choices=MODELS, note="its parameters follow as options")
    renamed(g, "surface generate", "--model", dest="generator")
    g.add_argument("--example", choices=EXAMPLES,
                   help="an example field for glint renders, with every generator parameter set (brushed, "
                        "scratched, flakes: 1024² samples over 51.2 µm; docs/glints.md); --seed still applies")
    option(g, "--size", default="64um")
    option(g, "--samples", default="1024", note="or NXxNY, NX,NY")
    option(g, "--seed", note="default: drawn and recorded")
    option(g, "--max-memory")
    for name, (flag, text) in _MODEL_OPTIONS.items():
        g.add_argument(flag, dest=f"m_{name}", metavar="VALUE", help=text)
    g.add_argument("--exact-rms", action="store_true",
                   help="rescale this realization to exactly σ (default: no rescale, the PSD exactly as given)")
    g.add_argument("--renormalize", action="store_true",
                   help="scale the spectrum so the ensemble rms on this grid is σ (moves the variance the grid "
                        "cannot hold into resolved frequencies; default: the PSD exactly as given)")
    now_default(g, "--no-renormalize", "use --renormalize for the old rescale to σ")
    add_output(g, metavar="FILE", note=HEIGHT_FIELD_OUTPUT)
    add_common(g, device=False)
    g.set_defaults(func=run_generate, command="surface generate")

    s = ss.add_parser("stats", help="statistics of a height-field file",
                      description="rms height, rms slope, correlation length (1/e of the autocovariance), "
                                  "Beckmann α = 2σ/T and optional PSD fits.")
    add_surface(s, positional=True)
    s.add_argument("--layout", choices=("matrix", "xyz"), help="text layout (default: detected)")
    s.add_argument("--nan-is-mask", action="store_true", help="treat NaN heights as missing samples")
    option(s, "--detrend", choices=("mean", "plane", "none"), default="mean", note="before the statistics")
    s.add_argument("--fit", action="append", choices=("gaussian", "exponential", "abc"), default=[],
                   help="fit this PSD model (repeatable)")
    s.add_argument("--plot", metavar="PNG", help="write the height map and radial PSD (with fits) as PNG")
    option(s, "--overwrite", action="store_true", note="here the --plot file")
    add_common(s, device=False)
    s.set_defaults(func=run_stats, command="surface stats")
    _register_prepare(ss)
    _register_transform(ss)


def _register_prepare(ss) -> None:
    q = ss.add_parser("prepare", help="level and crop a measured height field and write it in any format",
                      description="Prepare a measured height field for simulation: read it (any instrument format, "
                                  "with --units/--spacing/--channel where the file lacks them), remove the mean or "
                                  "the least-squares plane, crop a region, and write it (heights in metres, "
                                  "provenance kept).")
    add_surface(q, positional=True)
    q.add_argument("--layout", choices=("matrix", "xyz"), help="text layout (default: detected)")
    q.add_argument("--nan-is-mask", action="store_true", help="treat NaN heights as missing samples")
    option(q, "--detrend", choices=("plane", "mean", "none"), default="plane")
    q.add_argument("--crop", metavar="X,Y,W,H",
                   help="keep the region X..X+W, Y..Y+H (lengths with units from the first sample, e.g. "
                        "0um,0um,40um,40um)")
    add_output(q, metavar="FILE", note=HEIGHT_FIELD_OUTPUT)
    add_common(q, device=False)
    q.set_defaults(func=run_prepare, command="surface prepare")


def _register_transform(ss) -> None:
    q = ss.add_parser("transform", help="stretch, rotate or scale a height field and write it",
                      description="Deform a height field: stretch it laterally (spacings scale, the samples stay), "
                                  "rotate it about the patch centre (cubic resampling; what the turned patch does "
                                  "not cover is masked), scale its heights, and write it with its provenance. "
                                  "Stretching by s scales the slopes, and an NDF's α, by 1/s along that axis.")
    add_surface(q, positional=True)
    q.add_argument("--stretch", default="1", metavar="SX[,SY]",
                   help="lateral stretch factors > 0 (one number: both axes; default 1)")
    q.add_argument("--rotate", type=float, default=0.0, metavar="DEG",
                   help="counter-clockwise rotation in degrees (default 0)")
    q.add_argument("--height-scale", type=float, default=1.0, metavar="S", help="factor on the heights (default 1)")
    add_output(q, metavar="FILE", note=HEIGHT_FIELD_OUTPUT)
    add_common(q, device=False)
    q.set_defaults(func=run_transform, command="surface transform")


def run_transform(args):

    from .. import surfaces
    from ..units import parse_number_list

    stretch = parse_number_list(args.stretch, name="stretch")
    if stretch.size not in (1, 2):
        raise WaveopticsError(f"--stretch {args.stretch!r} is not allowed; give SX or SX,SY")
    hf = load_surface(args)
    before = surfaces.stats(hf)
    out = surfaces.transform(hf, stretch=tuple(stretch) if stretch.size == 2 else float(stretch[0]),
                             rotate_deg=args.rotate, height_scale=args.height_scale)
    out = surfaces.HeightField(out.heights, out.dx, out.dy, out.mask,
                               {**out.meta, "prepared_from": hf.meta.get("source")})
    path = surfaces.save(out, args.output, overwrite=args.overwrite)
    after = surfaces.stats(out)
    keys = ("rms_height_m", "rms_slope_x", "rms_slope_y", "beckmann_alpha")
    data = {"output": str(path), "surface_info": out.provenance(), "before": {k: before[k] for k in keys},
            "after": {k: after[k] for k in keys}}

    def num(v):
        return "n/a" if v is None else f"{v:.4g}"

    text = (f"wrote {path}: rms slope x {num(before['rms_slope_x'])} -> {num(after['rms_slope_x'])}, "
            f"y {num(before['rms_slope_y'])} -> {num(after['rms_slope_y'])}, valid {after['valid_fraction']:.1%}")
    emit(args, data, text)
    return 0


def run_prepare(args):

    from .. import surfaces

    hf = load_surface(args)
    if args.crop is not None:
        hf = surfaces.crop_region(hf, *surfaces.parse_region(args.crop))
    hf = surfaces.level(hf, args.detrend)
    hf = surfaces.HeightField(hf.heights, hf.dx, hf.dy, hf.mask, {**hf.meta, "prepared_from": hf.meta.get("source")})
    path = surfaces.save(hf, args.output, overwrite=args.overwrite)
    st = surfaces.stats(hf, detrend="none")
    data = {"output": str(path), "surface_info": hf.provenance(), "stats": st}
    text = (f"wrote {path}: {st['samples'][0]} x {st['samples'][1]} samples at {hf.dx * 1e9:.4g} x "
            f"{hf.dy * 1e9:.4g} nm, rms height {st['rms_height_m'] * 1e9:.4g} nm after {args.detrend} removal"
            + (f", region {args.crop}" if args.crop else ""))
    emit(args, data, text)
    return 0


def _model_params(args) -> dict:

    from .. import surfaces

    if args.generator is None:
        raise WaveopticsError(f"surface generate needs --generator ({', '.join(MODELS)})")
    accepted = inspect.signature(surfaces.GENERATORS[args.generator]).parameters
    params = {"size": args.size, "samples": args.samples}
    for name, (flag, _) in _MODEL_OPTIONS.items():
        value = getattr(args, f"m_{name}")
        if value is None:
            continue
        if name not in accepted:
            raise WaveopticsError(f"{flag} is not an option of generator {args.generator!r}")
        if name in _FLOAT_PARAMS or name == "count":
            try:
                value = float(value)
            except ValueError:
                raise WaveopticsError(f"{flag} {value!r} is not a number") from None
        params[name] = value
    for name, par in accepted.items():
        if par.default is inspect.Parameter.empty and name not in params:
            raise WaveopticsError(f"generator {args.generator!r} needs {_MODEL_OPTIONS[name][0]}")
    if "seed" in accepted:
        params["seed"] = args.seed
    elif args.seed is not None:
        raise WaveopticsError(f"--seed is not an option of generator {args.generator!r} (it is deterministic)")
    if "exact_rms" in accepted:
        params["exact_rms"] = args.exact_rms
        params["renormalize"] = args.renormalize
    elif args.exact_rms or args.renormalize:
        raise WaveopticsError(f"--exact-rms/--renormalize apply to random spectral models, not {args.generator!r}")
    return params


def run_generate(args):

    from .. import surfaces

    if args.example is not None:
        given = [flag for name, (flag, _) in _MODEL_OPTIONS.items() if getattr(args, f"m_{name}") is not None]
        if args.generator is not None or given:
            raise WaveopticsError(f"--example {args.example} sets the generator and its parameters; drop "
                                  f"{(['--generator'] if args.generator is not None else given)[0]}")
        hf = surfaces.example(args.example, seed=0 if args.seed is None else args.seed)
        args.generator = surfaces.EXAMPLES[args.example].model
    else:
        hf = surfaces.generate(args.generator, **_model_params(args))
    path = surfaces.save(hf, args.output, overwrite=args.overwrite)
    st = surfaces.stats(hf)
    data = {"output": str(path), "model": args.generator, "meta": hf.meta, "stats": st}
    text = (f"wrote {path}: {args.generator}, {st['samples'][0]}x{st['samples'][1]} samples at "
            f"{st['spacing_m'][0] * 1e9:.4g} x {st['spacing_m'][1] * 1e9:.4g} nm, rms height "
            f"{st['rms_height_m'] * 1e9:.4g} nm, rms slope {st['rms_slope']:.4g}")
    emit(args, data, text)
    return 0


def run_stats(args):

    from .. import surfaces

    hf = load_surface(args)
    st = surfaces.stats(hf, detrend=args.detrend)
    st["surface_info"] = hf.provenance()
    fits = [surfaces.fit_psd(hf, m, detrend=args.detrend) for m in dict.fromkeys(args.fit)]
    if fits:
        st["psd_fit"] = {f["model"]: f for f in fits}
    if args.plot:
        surfaces.plot(hf, args.plot, fits=fits, overwrite=args.overwrite)
        st["plot"] = args.plot

    def nm(v):
        return "n/a" if v is None else f"{v * 1e9:.4g} nm"

    def num(v):
        return "n/a" if v is None else f"{v:.4g}"

    lines = [f"file            {args.surface}",
             f"samples         {st['samples'][0]} x {st['samples'][1]}"
             f"{' (profile)' if st['profile'] else ''}, valid {st['valid_fraction']:.1%}",
             f"spacing         {nm(st['spacing_m'][0])} x {nm(st['spacing_m'][1])}",
             f"rms height      {nm(st['rms_height_m'])}",
             f"rms slope       {num(st['rms_slope'])} (x {num(st['rms_slope_x'])}, y {num(st['rms_slope_y'])})",
             f"corr. length    {nm(st['corr_length_m'])} (1/e of the autocovariance)",
             f"Beckmann alpha  {num(st['beckmann_alpha'])} (2 sigma / corr_length)"]
    for f in fits:
        if f["model"] == "abc":
            lines.append(f"fit abc         A {f['A_m4']:.4g} m^4, B {nm(f['B_m'])}, C {f['C']:.4g}, "
                         f"sigma {nm(f['sigma_m'])}")
        else:
            lines.append(f"fit {f['model']:<12}sigma {nm(f['sigma_m'])}, corr_length {nm(f['corr_length_m'])}")
    info = st["surface_info"]
    if "source_format" in info:
        inst = info.get("instrument", {}).get("name") if isinstance(info.get("instrument"), dict) else None
        lines.insert(1, f"format          {info['source_format']}, channel {info['channel']!r}, unit {info['file_unit']}"
                        + (f", instrument {inst}" if inst else ""))
    if args.plot:
        lines.append(f"plot            {args.plot}")
    emit(args, st, "\n".join(lines))
    return 0
