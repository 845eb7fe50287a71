"""Command-line interface: ``waveoptics <command> ...`` (also ``python -m waveoptics``).

Each sub-command lives in its own module in this package and exposes ``register(subparsers)``, which adds
its parser and sets ``func`` to the function that runs it. Modules are discovered automatically, so adding
a command means adding one file. Any :class:`ValueError` / :class:`TypeError` raised while running (every
user mistake is one) is printed as one line on stderr with exit code 2; ``--debug`` shows the traceback.
"""
from __future__ import annotations

import argparse
import functools
import importlib
import pkgutil
import sys
import warnings

from .. import __version__
from ..errors import FieldError
from ._common import HELD_WARNINGS, field_flags
from ._options import deprecations


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage dump) and exit code 2, and no abbreviated options: a prefix could
    silently mean another option (``--alpha`` would be taken for ``--alpha-y`` where no ``--alpha`` exists)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message):  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="waveoptics",
                     description="Spectral wave-optics diffraction simulator (Kirchhoff scattering + microfacets).")
    parser.add_argument("--version", action="version", version=f"waveoptics {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        if hasattr(mod, "register"):
            mod.register(sub)
    return parser


def command_parser(parser, words) -> argparse.ArgumentParser:
    """The parser of the (possibly nested) sub-command named by *words* (``"surface generate"`` or argv): the
    parser whose options the user typed."""
    words = words.split() if isinstance(words, str) else list(words)
    for word in words:
        sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
        if sub is None or word not in sub.choices:
            break
        parser = sub.choices[word]
    return parser


def _check_device(args) -> None:
    """A device named by ``--device`` or ``WAVEOPTICS_DEVICE`` must exist, for every command (it was ignored by
    all but the direct solver): resolved once, before any work, with a one-line error listing the devices."""
    import os

    given = getattr(args, "device", None)
    if given is not None and not given.strip():   # '' or ' ' names no device: refused, not taken as "the default"
        from ..errors import WaveopticsError

        raise WaveopticsError(f"--device {given!r} names no device; give a substring of 'platform device' or P:D "
                              "indices (see 'waveoptics info'), or leave --device out for the default")
    spec = given or os.environ.get("WAVEOPTICS_DEVICE")
    if spec:
        from ..runtime import select_device

        select_device(spec)


@functools.lru_cache(maxsize=1)
def shared_parser() -> argparse.ArgumentParser:
    """The parser :func:`main` uses, built once per process (building it imports every command module and adds
    some 600 options: ~40 ms, paid once by a process that runs many commands). Parsing leaves it unchanged:
    argparse makes a fresh namespace per call and copies ``append`` defaults. Code that edits a parser builds
    its own with :func:`build_parser`."""
    return build_parser()


def main(argv=None) -> int:
    """Entry point of the ``waveoptics`` console script."""
    parser = shared_parser()
    args = parser.parse_args(argv)
    debug = getattr(args, "debug", False)
    with warnings.catch_warnings():
        _warning_channel(args)
        HELD_WARNINGS.hold()
        try:
            for note in deprecations(args):   # renamed options (cli/_options.py RENAMED): one line each
                warnings.warn(note, UserWarning, stacklevel=1)
            rc = _run(args, parser, debug)
        except BaseException:
            HELD_WARNINGS.drop()
            raise
        if rc == 2:   # a refusal is one line: the warnings that came before it are dropped (the error names its cause)
            HELD_WARNINGS.drop()
        else:
            HELD_WARNINGS.release()
        return rc


def _warning_channel(args) -> None:
    """Every warning of a command as one stderr line ``waveoptics CMD: warning: ...`` (each distinct text once,
    no source lines), or none with ``--quiet``."""
    if getattr(args, "quiet", False):
        warnings.simplefilter("ignore")
        return
    warnings.simplefilter("always")   # repeats are dropped below by text, not by code location
    for category in (DeprecationWarning, PendingDeprecationWarning, FutureWarning, ImportWarning, ResourceWarning):
        warnings.simplefilter("ignore", category)   # other libraries' notices to developers, not to users
    seen = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = " ".join(str(message).split())
        if text not in seen:
            seen.add(text)
            HELD_WARNINGS.emit(f"waveoptics {args.command}: warning: {text}")

    warnings.showwarning = show


def _memory_budget(args) -> None:
    """``--max-memory``, where a command has it, is the budget of every estimate this process makes (also those
    deep in the library, e.g. a generated surface's): validated once and set as ``WAVEOPTICS_MAX_MEMORY``."""
    import os

    spec = getattr(args, "max_memory", None)
    if spec is not None:
        from ..runtime import parse_size

        os.environ["WAVEOPTICS_MAX_MEMORY"] = str(parse_size(spec))


def _run(args, parser, debug) -> int:
    try:
        _check_device(args)
        _memory_budget(args)
        rc = args.func(args)
    except KeyboardInterrupt:
        print("waveoptics: interrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError) as exc:
        if debug:
            raise
        text = exc.render(field_flags(command_parser(parser, args.command))) if isinstance(exc, FieldError) else str(exc)
        msg = text.strip().splitlines()
        first = msg[0] if msg else type(exc).__name__
        print(f"waveoptics {args.command}: error: {first}", file=sys.stderr)
        if len(msg) > 1 and "build" in first:
            print("\n".join(msg[1:]), file=sys.stderr)
        return 2
    except MemoryError:
        if debug:
            raise
        print(f"waveoptics {args.command}: error: not enough memory for this request; use fewer samples, "
              "wavelengths or a coarser --resolution", file=sys.stderr)
        return 2
    except OSError as exc:
        if debug:
            raise
        print(f"waveoptics {args.command}: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "),
              file=sys.stderr)
        return 2
    return int(rc or 0)
