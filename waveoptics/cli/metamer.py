"""``waveoptics metamer``: three laser lines mixed to the same colour (XYZ) as a broadband light."""
from __future__ import annotations

from ..units import parse_wavelengths
from ._common import add_colour, add_common, add_output, emit


def register(sub):
    p = sub.add_parser(
        "metamer", help="laser-line powers whose mix matches a light's XYZ (RGB laser projector vs daylight)",
        description="Solve for the powers of three laser lines whose mix has the same CIE XYZ as the target "
                    "light (a metamer: same colour, very different spectrum) and optionally plot both spectra.")
    p.add_argument("--target", default="D65", metavar="SPD",
                   help="light to match: D65 (default), D50, A, F1..F12, E, blackbody:5500K or a CSV")
    p.add_argument("--lines", default="467,532,630", metavar="NM,NM,NM",
                   help="three laser wavelengths in nm (default: the BT.2020 primaries 467,532,630)")
    add_colour(p, illuminant=False)
    add_output(p, required=False, metavar="PNG", note="a PNG file: a plot of both spectra")
    add_common(p, device=False)
    p.set_defaults(func=run)


def run(args):

    from .. import colour

    target = colour.illuminant(args.target)
    observer = colour.observer_name(args.observer)
    lines = parse_wavelengths(args.lines, name="--lines")
    data = colour.metamer_summary(target, lines, observer)
    if args.output:
        colour.plot_metamers(target, lines, data["powers"], args.output, observer=observer,
                               overwrite=args.overwrite)
        data["plot"] = str(args.output)
    parts = [f"{lam:g} nm: {f:.4f}" for lam, f in zip(data["lines_nm"], data["power_fractions"])]
    text = (f"{target.name} is matched by lasers with power fractions {', '.join(parts)}\n"
            f"XYZ target {_fmt(data['XYZ_target'])}  mix {_fmt(data['XYZ_mix'])}  "
            f"xy ({data['xy'][0]:.4f}, {data['xy'][1]:.4f})")
    if args.output:
        text += f"\nplot: {args.output}"
    emit(args, data, text)
    return 0


def _fmt(v):
    return "(" + ", ".join(f"{x:.5f}" for x in v) + ")"
