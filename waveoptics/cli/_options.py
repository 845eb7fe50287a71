"""One vocabulary for the command line: every option that more than one command takes is defined here once — its
flag, the quantity it means (with its unit), its metavar and type — and each command adds it with its own default
and, where needed, a note on what that command does with it. A test holds every parser to these definitions, and
``docs/cli.md`` is generated from the parsers.

Renamed options keep working for one release as hidden aliases that print a one-line deprecation warning
(:data:`RENAMED`; the changelog lists them), also those renamed so that a quantity has one name everywhere.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass

__all__ = ["Option", "OPTIONS", "RENAMED", "REMOVED_IN", "option", "renamed", "now_default",
           "deprecations"]

#: the release that drops the aliases of :data:`RENAMED`
REMOVED_IN = "0.3"


@dataclass(frozen=True)
class Option:
    """A command-line option shared by several commands: *meaning* starts its help in every command."""

    flag: str
    meaning: str
    metavar: str | None = None
    type: type | None = None
    unit: str = ""


OPTIONS = {o.flag: o for o in (
    Option("--wavelengths", "wavelengths in nm: 550, 450,550,650 or 400:700:10 (a unit may follow: 550nm, 0.55um)",
           "NM", unit="nm"),
    Option("--incident", "direction to the light: θ from the normal, φ about it, in degrees", "THETA[,PHI]",
           unit="deg"),
    Option("--incident-angles", "incident angles θ in degrees: 0:80:10 or 0,30,60", "DEG", unit="deg"),
    Option("--delta-e", "colour accuracy (ΔE2000) that picks the wavelength step", "DE", float, "ΔE2000"),
    Option("--material", "material: a name (see 'waveoptics materials'), shelf/book/page, a constant index n+kj "
                         "(1.5, 0.2+3.1j), f0:VALUE, or a thin-film stack SUBSTRATE|FILM:THICKNESS|... (films "
                         "from the substrate outwards, e.g. 'Al|Al2O3:120nm')", "M"),
    Option("--illuminant", "light: D65, D50, A, F1..F12, E, blackbody:5500K, laser:465,532,638, rgb-laser or a CSV "
                           "file", "SPD"),
    Option("--kd", "diffuse albedo kd in [0, 1]", "KD", float, "1"),
    Option("--micro-alpha", "micro-scale NDF roughness α (slope scale; 0 = smooth)", "A", float, "1"),
    Option("--alpha-y", "micro-scale α_y of an anisotropic NDF (α_x is --micro-alpha)", "A", float, "1"),
    Option("--ndf", "microfacet normal distribution"),
    Option("--micro-surface", "micro-scale height field whose slopes are the NDF (tabulated, Heitz 2014; "
                              "replaces --ndf and the micro α)", "FILE"),
    Option("--diffuse", "diffuse term of a dielectric's substrate"),
    Option("--multiple-scattering", "add the light single scattering loses between micro facets (Kulla & Conty "
                                    "2017 energy compensation)"),
    Option("--ndf-shape", "shape parameter of the NDFs that have one: abc's tail exponent C (default 2), epd's and "
                          "sgd's exponent p (default 1)", "S", float, "1"),
    Option("--nano", "nano-roughness MODEL:key=value,... with units, e.g. abc:sigma=10nm,B=2um,C=2.6, "
                     "gaussian:sigma=5nm,corr_length=1um, sinusoid:amplitude=40nm,period=2um",
           "MODEL:PARAMS"),
    Option("--nano-frame", "frame of the --nano lobes of the nano-rough glass: macro (about the macro normal, "
                           "right as α → 0) or facet (each micro facet's: the two-scale glass, right at any α, "
                           "~200x slower)"),
    Option("--diffraction", "diffraction model of the nano lobe: kirchhoff, ghs, rghs, ohs, rohs or rayleigh-rice "
                            "(first-order perturbation, two-scale lobes only) (docs/physics.md §10)"),
    Option("--polarization", "polarization of the incident light relative to the plane of incidence: unpolarized, "
                             "s or p (the scattered light is not analyzed)"),
    Option("--roughness-correlation", "correlation of the interface roughness of a thin-film stack under "
                                      "rayleigh-rice: correlated (a film replicating its substrate), uncorrelated "
                                      "or a coefficient in [0, 1] (Elson, Rahn & Bennett 1983)", "C"),
    Option("--model", "BRDF model"),
    Option("--precision", "OpenCL floating-point precision of the height-field solvers"),
    Option("--solver", "solver of the diffracted (nano) lobe"),
    Option("--backend", "where the direct Kirchhoff sum runs: the OpenCL kernel or its float64 NumPy twin"),
    Option("--resolution", "cells per side of the direction-cosine grid over the projected hemisphere", "N", int),
    Option("--realizations", "surface realizations averaged (tiles of a height-field file, or seeds of a generated "
                             "surface)", "N", int),
    Option("--samples", "grid samples of a generated surface: N per side", "N"),
    Option("--size", "patch size of a generated surface with unit: L or LX,LY", "L", unit="m"),
    Option("--seed", "random seed of generated surfaces", "SEED", int),
    Option("--sphere-size", "size of the sphere renders in pixels", "PX", int, "px"),
    Option("--no-spheres", "skip the sphere renders and the diffracted-lobe table over incidence behind them: no "
                           "sphere_* files and no sphere ΔE2000; the summary says they were skipped"),
    Option("--environment", "environment light: sky, studio, constant or an equirectangular .exr (+y up)", "MAP"),
    Option("--spp", "samples per pixel", "N", int),
    Option("--budget", "time budget in seconds ('none': no limit)", "SECONDS", unit="s"),
    Option("--window", "taper over the patch: a scipy.signal.windows name (boxcar = none)", "NAME"),
    Option("--detrend", "what to remove from the heights first: mean, plane (least squares: levelling) or none"),
    Option("--generator", "surface generator"),
    Option("--surface", "height-field file", "FILE"),
    Option("--footprint", "a pixel footprint: Gaussian centred at X,Y (from the first sample) of width SIGMA "
                          "(SIGMA_Y, turned by ANGLE degrees for an ellipse), lengths with units", "X,Y,SIGMA"),
    Option("--coherence", "width of the light's coherence area with unit (Yan et al. 2018): windows of this width "
                          "inside a footprint add as intensities", "L", unit="m"),
    Option("--spacing", "grid spacing of the height field with unit, e.g. 50nm or 50nm,80nm: needed when the "
                        "file does not state it, and overrides it when it does", "D[,DY]", unit="m"),
    Option("--units", "unit of heights and lengths in a height-field file that does not state it: m, mm, um, nm, "
                      "pm or A", "UNIT"),
    Option("--channel", "data channel of an instrument file, by index or name (default: the file's height "
                        "channel)", "N|NAME"),
    Option("--output", "where the outputs go"),
    Option("--overwrite", "replace outputs that already exist"),
    Option("--max-memory", "memory budget of the request, e.g. 4GB or 500MiB (default: half the machine's memory, "
                           "or $WAVEOPTICS_MAX_MEMORY); a larger estimate is refused before any work", "SIZE"),
    Option("--device", "OpenCL device: substring of 'platform device' or P:D indices (default: "
                       "$WAVEOPTICS_DEVICE, else first GPU, else PoCL CPU)", "NAME"),
    Option("--json", "print machine-readable JSON (with units) on stdout"),
    Option("--debug", "show the Python traceback on errors"),
    Option("--quiet", "do not print warnings"),
    Option("--observer", "CIE observer: CIE 1931 2 Degree Standard Observer or CIE 1964 10 Degree Standard "
                         "Observer (aliases 2, 10)", "NAME"),
)}

#: (command, old flag) → new flag: options renamed for one vocabulary, accepted until :data:`REMOVED_IN`
RENAMED = {
    ("brdf", "--wavelength"): "--wavelengths",
    ("brdf", "--sigma"): "--diffuse-sigma",
    ("brdf", "--abc-c"): "--ndf-shape",
    ("compare", "--angles"): "--incident-angles",
    ("cost", "--model"): "--generator",
    ("cost", "--realizations"): "--realization-counts",
    ("surface generate", "--model"): "--generator",
    # one name per quantity (issue 30): colour accuracy is ΔE2000, --delta-e, in every command
    **{(cmd, "--accuracy"): "--delta-e" for cmd in ("simulate", "compare", "table", "sweep")},
    ("cost", "--colour-accuracy"): "--delta-e",
}

def _help(meaning: str, note: str | None, default) -> str:
    text = meaning + (f"; {note}" if note else "")
    if default not in (None, False, argparse.SUPPRESS) and "default" not in (note or ""):
        text += f" (default {default})"
    return text


def option(parser, flag: str, *, default=None, note: str | None = None, group=None, **kwargs):
    """Add the shared option *flag* (:data:`OPTIONS`) to *parser* (or its *group*) with this command's *default*
    and *note*; ``kwargs`` (choices, action, required, dest, ...) pass to argparse. Short forms (``-o``) go in
    ``kwargs["short"]``."""
    o = OPTIONS[flag]
    short = kwargs.pop("short", None)
    args = (short, flag) if short else (flag,)
    spec = {"help": _help(o.meaning, note, default), "default": default}
    if kwargs.get("action") not in ("store_true", "store_false"):
        if o.metavar and "choices" not in kwargs:
            spec["metavar"] = o.metavar
        if o.type is not None:
            spec["type"] = o.type
    spec.update(kwargs)
    return (group or parser).add_argument(*args, **spec)


class _Renamed(argparse.Action):
    """A renamed option's old flag: stores into the new option's destination and records the deprecation."""

    def __init__(self, option_strings, dest, new_flag=None, store=None, **kwargs):
        self.new_flag = new_flag
        self.store = store
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        if self.store == "append":
            items = list(getattr(namespace, self.dest, None) or [])
            items.append(values)
            values = items
        setattr(namespace, self.dest, values)
        notes = list(getattr(namespace, "_deprecations", []))
        notes.append(f"{option_string} is deprecated and will be removed in waveoptics {REMOVED_IN}; use "
                     f"{self.new_flag}")
        namespace._deprecations = notes


def renamed(parser, command: str, old: str, *, dest: str, type=None, append: bool = False) -> None:
    """Accept the old flag *old* of *command* (:data:`RENAMED`) as a hidden alias storing into *dest*."""
    new = RENAMED[(command, old)]
    # the alias takes exactly what the new flag takes: its type and its choices (added first, so it is known)
    target = next((a for a in parser._actions if new in a.option_strings), None)
    choices = target.choices if target is not None else None
    if type is None and target is not None:
        type = target.type
    parser.add_argument(old, dest=dest, action=_Renamed, new_flag=new, type=type, default=argparse.SUPPRESS,
                        store="append" if append else None, help=argparse.SUPPRESS, choices=choices)


class _NowDefault(argparse.Action):
    """A switch whose behaviour became the default: accepted, changes nothing, records a deprecation line."""

    def __init__(self, option_strings, dest, hint=None, **kwargs):
        self.hint = hint
        super().__init__(option_strings, dest, nargs=0, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        notes = list(getattr(namespace, "_deprecations", []))
        notes.append(f"{option_string} is deprecated and will be removed in waveoptics {REMOVED_IN}: it is the "
                     f"default now; {self.hint}")
        namespace._deprecations = notes


def now_default(parser, old: str, hint: str) -> None:
    """Accept the switch *old*, whose behaviour is now the default, as a hidden no-op with a deprecation line."""
    parser.add_argument(old, dest="_now_default_" + old.strip("-").replace("-", "_"), action=_NowDefault,
                        hint=hint, default=argparse.SUPPRESS, help=argparse.SUPPRESS)


def deprecations(args) -> list[str]:
    """The deprecation notes recorded while parsing *args* (printed as one-line warnings by the CLI)."""
    return list(getattr(args, "_deprecations", []))
