"""Error types shared by the library and the CLI.

Every error a user can cause derives from :class:`ValueError` or :class:`TypeError`
so that Python callers can catch the standard types; the CLI turns any of them into
one line on stderr and exit code 2 (see :mod:`waveoptics.cli`).
"""
from __future__ import annotations

import difflib


class WaveopticsError(ValueError):
    """A bad value given by the user: the message names the value and what is allowed."""


class NoOpenCLError(WaveopticsError):
    """No OpenCL platform or no device matching the request."""


class OutputExistsError(WaveopticsError):
    """An output already exists and ``overwrite`` was not requested."""


def did_you_mean(word: str, choices) -> str:
    """Return ``" (did you mean 'x'?)"`` for the closest of *choices*, or ``""``."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=0.5)
    if not close:
        low = {str(c).lower(): str(c) for c in choices}
        close = [low[str(word).lower()]] if str(word).lower() in low else []
    return f" (did you mean '{close[0]}'?)" if close else ""


def unknown(kind: str, value, choices) -> WaveopticsError:
    """Build the standard 'unknown X' error with a did-you-mean suggestion."""
    shown = ", ".join(sorted(map(str, choices)))
    return WaveopticsError(f"unknown {kind} {value!r}{did_you_mean(value, choices)}; allowed: {shown}")
