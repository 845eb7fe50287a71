"""Options and output helpers shared by all sub-commands."""
from __future__ import annotations

import argparse
import sys


from ..errors import FieldError
from ..io.files import to_json
from ..units import parse_angle
from ._options import option


def angle_arg(text) -> float:
    """argparse type of an angle option in degrees: ``30``, ``30deg``, ``30°`` or ``0.5rad``
    (:func:`waveoptics.units.parse_angle`); anything else is the option's one-line error, exit 2."""
    try:
        return parse_angle(text, name="angle")
    except FieldError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None

#: request fields whose option has another name (the dest of the option that carries the field); every other
#: field is carried by the option of the same dest (``micro_alpha`` → ``--micro-alpha``)
FIELD_DESTS = {
    "incident_deg": ("incident",),
    "wavelengths_nm": ("wavelengths",),
    "thetas_deg": ("incident_angles",),
    "phi_deg": ("phi",),
    "angles_deg": ("incident_angles",),
    "vary": ("vary",),
    "psd": ("nano",),
    "sphere": ("no_spheres",),     # the library's sphere=False: the commands that may skip the sphere renders
}


def field_flags(parser) -> dict:
    """Field name → the flag a user typed for it in *parser* (a sub-command's parser): how the CLI writes the
    fields named by :class:`waveoptics.errors.FieldError`."""
    by_dest = {}
    for action in parser._actions:
        longs = [o for o in action.option_strings if o.startswith("--")]
        if longs and action.help != argparse.SUPPRESS:   # a renamed option's hidden old name is not the name
            by_dest[action.dest] = longs[0]
    flags = dict(by_dest)
    for field, dests in FIELD_DESTS.items():
        for d in dests:
            if d in by_dest:
                flags[field] = by_dest[d]
                break
    return flags


def not_asked(flag: str) -> str:
    """Why a command skipped work a flag turned off, as its outputs' ``skipped`` entries write it
    (``"not asked: --no-spheres"``)."""
    return f"not asked: {flag}"


def spheres_skipped_text(reason: str) -> str:
    """The text-output words for sphere renders skipped for *reason*: ``spheres skipped (not asked: --no-spheres)``."""
    return f"spheres skipped ({reason})"


def add_common(parser, *, json: bool = True, device: bool = True) -> None:
    """Add ``--device``, ``--json``, ``--debug`` and ``--quiet`` to a sub-command parser."""
    if device:
        option(parser, "--device")
    if json:
        option(parser, "--json", action="store_true")
    option(parser, "--debug", action="store_true")
    option(parser, "--quiet", action="store_true")


#: what ``--surface`` reads, in every command's help
SURFACE_FORMATS_HELP = (".npz .npy .exr .txt .csv .xyz, or an instrument file (.x3p .sur .datx .sdf .opd .plu .gwy "
                        ".nc ..., read by SurfaceTopography)")


def add_surface(parser, *, group=None, required: bool = False, note: str | None = None, positional: bool = False):
    """Add the height-field file option (``--surface FILE``, or a positional FILE) and the options that complete
    a file's metadata, ``--spacing``, ``--units`` and ``--channel``, with the same meaning in every command
    (:func:`load_surface` reads them)."""
    text = SURFACE_FORMATS_HELP + (f"; {note}" if note else "")
    if positional:
        parser.add_argument("surface", metavar="FILE", help=f"height-field file: {text}")
    else:
        option(parser, "--surface", group=group, required=required, note=text)
    for flag in ("--spacing", "--units", "--channel"):
        option(parser, flag)


def load_surface(args, *, required: bool = True):
    """The height field named by ``--surface`` (or the positional FILE), read with ``--spacing``, ``--units``,
    ``--channel`` (and ``--layout``, ``--nan-is-mask`` where the command has them); None when no file is named
    and *required* is False. Metadata options without a file are refused."""
    if args.surface is None:
        given = [f"--{k}" for k in ("spacing", "units", "channel") if getattr(args, k, None) is not None]
        if given:
            from ..errors import WaveopticsError

            raise WaveopticsError(f"{' and '.join(given)} describe a --surface file; give one")
        return None
    from .. import surfaces

    return surfaces.load(args.surface, spacing=args.spacing, units=args.units, channel=args.channel,
                         layout=getattr(args, "layout", None), nan_is_mask=getattr(args, "nan_is_mask", False))


def add_workers(parser, *, group=None) -> None:
    """``--workers N`` (a local Dask cluster of N single-threaded processes) and ``--scheduler ADDRESS`` (an existing
    one), mutually exclusive; neither: run in this process."""
    g = group if group is not None else parser
    x = g.add_mutually_exclusive_group()
    x.add_argument("--workers", type=int, metavar="N",
                   help="start a local Dask cluster of N single-threaded worker processes on 127.0.0.1 "
                        "(default: run in-process)")
    x.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="use an existing Dask scheduler")


def add_output(parser, *, required: bool = True, note: str = "a directory", metavar: str = "OUTDIR",
               overwrite_note: str | None = None) -> None:
    """Add ``-o/--output`` and ``--overwrite``."""
    option(parser, "--output", short="-o", required=required, metavar=metavar, note=note)
    option(parser, "--overwrite", action="store_true", note=overwrite_note)


def emit(args, data, text: str | None = None) -> None:
    """Print *data* as JSON with ``--json``, else *text* (or the JSON if no text is given)."""
    if getattr(args, "json", False) or text is None:
        print(to_json(data, indent=2))
    else:
        print(text)


def _duration(seconds: float) -> str:
    return f"{seconds / 60:.1f} min" if seconds < 5400 else f"{seconds / 3600:.1f} h"


def warn_if_long(seconds: float, reduce: str) -> None:
    """Announce a request the cost model expects to run beyond :data:`waveoptics.planning.LONG_REQUEST_S`, with
    its estimate and what to reduce (one warning line; ``--quiet`` silences it), and refuse one beyond the time
    budget (:func:`waveoptics.planning.estimate.time_budget`, default a day) before any work, in one line."""
    import warnings

    from ..errors import WaveopticsError
    from ..planning.estimate import LONG_REQUEST_S, time_budget

    budget = time_budget()
    if seconds > budget:
        raise WaveopticsError(f"this request would take about {_duration(seconds)} by this machine's cost model, "
                              f"beyond the time budget of {_duration(budget)}; {reduce} (or set "
                              "WAVEOPTICS_MAX_TIME, e.g. 48h)")
    if seconds > LONG_REQUEST_S:
        when = _duration(seconds)
        warnings.warn(f"this request will take about {when} by this machine's cost model ('waveoptics plan "
                      f"--recalibrate' re-times it); {reduce} to shorten it", UserWarning, stacklevel=2)


class _HeldWarnings:
    """The warning lines of a command, held back until it either starts long work (a progress bar), or ends: on
    success they are printed, on an error dropped, so that a refused command prints its one error line and nothing
    else (its error names the cause), while a long run still shows its warnings before the wait."""

    def __init__(self):
        self.lines: list[str] | None = None   # None: print at once

    def hold(self) -> None:
        self.lines = []

    def emit(self, line: str) -> None:
        if self.lines is None:
            print(line, file=sys.stderr)
        else:
            self.lines.append(line)

    def release(self) -> None:
        lines, self.lines = self.lines or [], None
        for line in lines:
            print(line, file=sys.stderr)

    def drop(self) -> None:
        self.lines = None


HELD_WARNINGS = _HeldWarnings()


def progress(iterable=None, *, total=None, desc=None, args=None):
    """A tqdm progress bar on stderr, silent under ``--json`` or when stderr is not a terminal. Long work starts
    here, so the warnings held so far are printed first."""
    from tqdm.auto import tqdm

    HELD_WARNINGS.release()

    quiet = (args is not None and getattr(args, "json", False)) or not sys.stderr.isatty()
    return tqdm(iterable, total=total, desc=desc, disable=quiet, file=sys.stderr, leave=False)


def add_colour(parser, *, illuminant: bool = True) -> None:
    """Add ``--illuminant`` (unless *illuminant* is False) and ``--observer`` (see :mod:`waveoptics.colour`)."""
    if illuminant:
        option(parser, "--illuminant", default="D65")
    option(parser, "--observer", default="CIE 1931 2 Degree Standard Observer", note="default the 1931 2° observer")


def parse_budget(text):
    """``--budget`` in seconds, or None for 'none'."""
    from ..errors import WaveopticsError

    if str(text).strip().lower() in ("none", "inf", "unlimited"):
        return None
    try:
        v = float(text)
    except ValueError:
        raise WaveopticsError(f"--budget {text!r} is not allowed; give seconds > 0 or 'none'") from None
    if not v > 0 or v != v:
        raise WaveopticsError(f"--budget {text!r} is not allowed; give seconds > 0 or 'none'")
    return v
