"""Error types shared by the library and the CLI.

Every error a user can cause derives from :class:`ValueError` or :class:`TypeError`
so that Python callers can catch the standard types; the CLI turns any of them into
one line on stderr and exit code 2 (see :mod:`waveoptics.cli`).
"""
from __future__ import annotations

import difflib
import functools

__all__ = ['WaveopticsError', 'FieldError', 'RenamedWarning', 'NoOpenCLError', 'OutputExistsError', 'did_you_mean', 'unknown',
           'renamed_keywords']


class WaveopticsError(ValueError):
    """A bad value given by the user: the message names the value and what is allowed."""


class RenamedWarning(UserWarning):
    """An old spelling in a user's input that still works for one release (e.g. the nano parameter ``T=``, now
    ``corr_length=``): shown to users (the CLI prints it as one line), unlike :class:`DeprecationWarning`."""


class FieldError(WaveopticsError):
    """A bad value of a named field of a request (a keyword argument, a scene key, a command-line option).

    The message is a template in which ``{name}`` stands for the field *name*. The library writes it as the
    Python name (``str(error)``: "micro_alpha -1 is not allowed ..."); the command line writes the flag a user
    typed (:meth:`render` with the CLI's field → flag map: "--micro-alpha -1 is not allowed ..."), so a Python
    caller is never told about flags it did not use.

    Parameters
    ----------
    template : str
        The message, with ``{field}`` placeholders for the fields named in *fields*.
    *fields : str
        The fields the message is about, the first being the one whose value is wrong.
    python : dict, optional
        How the library writes a field where the plain name would read badly (``{"overwrite": "overwrite=True"}``).

    Examples
    --------
    >>> e = FieldError("{micro_alpha} -1 is not allowed; α must be >= 0", "micro_alpha")
    >>> str(e)
    'micro_alpha -1 is not allowed; α must be >= 0'
    >>> e.render({"micro_alpha": "--micro-alpha"})
    '--micro-alpha -1 is not allowed; α must be >= 0'
    """

    def __init__(self, template: str, *fields: str, python: dict | None = None):
        self.template = template
        self.fields = fields
        super().__init__(self.render(python or {}))

    @property
    def field(self) -> str:
        """The field whose value is wrong."""
        return self.fields[0]

    def render(self, names: dict) -> str:
        """The message with each field written as ``names.get(field, field)``."""
        out = self.template
        for f in self.fields:
            out = out.replace("{" + f + "}", str(names.get(f, f)))
        return out


class NoOpenCLError(WaveopticsError):
    """No OpenCL platform or no device matching the request."""


class OutputExistsError(FieldError):
    """An output already exists and ``overwrite`` was not requested."""

    def __init__(self, path, template: str = "output {path} already exists; pass {overwrite} to replace it"):
        super().__init__(template.replace("{path}", repr(str(path))), "overwrite", "resume",
                         python={"overwrite": "overwrite=True", "resume": "resume=True"})


def did_you_mean(word: str, choices) -> str:
    """Return ``" (did you mean 'x'?)"`` for the closest of *choices*, or ``""``."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=0.5)
    if not close:
        low = {str(c).lower(): str(c) for c in choices}
        close = [low[str(word).lower()]] if str(word).lower() in low else []
    return f" (did you mean '{close[0]}'?)" if close else ""


def unknown(kind: str, value, choices, *, field: str | None = None) -> WaveopticsError:
    """Build the standard 'unknown X' error with a did-you-mean suggestion (a :class:`FieldError` of *field*, whose
    name the CLI writes as its flag, when given)."""
    shown = ", ".join(sorted(map(str, choices)))
    tail = f" {value!r}{did_you_mean(value, choices)}; allowed: {shown}"
    if field is not None:
        if kind == field:   # "unknown solver 'x'" in Python, "unknown --solver 'x'" on the command line
            return FieldError("unknown {" + field + "}" + tail, field)
        return FieldError("{" + field + "}: unknown " + kind + tail, field)
    return WaveopticsError(f"unknown {kind}" + tail)


def renamed_keywords(**hints):
    """Decorator: a call that passes a keyword argument removed by a rename is refused in one line naming its new
    name, instead of Python's plain "unexpected keyword argument". The old name is not accepted: Python keywords are
    renamed outright (the command line's old flags keep working until 0.3 with a warning, :mod:`waveoptics.cli`).

    Parameters
    ----------
    **hints : str or callable
        Old keyword → what to use now, as text (``"diffuse_sigma="``) or as a function of the call's keyword
        arguments returning that text (where the new name depends on another argument).

    Examples
    --------
    >>> @renamed_keywords(sigma="diffuse_sigma=")
    ... def f(*, diffuse_sigma=0.0):
    ...     return diffuse_sigma
    >>> f(sigma=0.3)
    Traceback (most recent call last):
    ...
    TypeError: f() got an unexpected keyword argument 'sigma': it was renamed; use diffuse_sigma=
    """
    def wrap(fn):
        @functools.wraps(fn)
        def call(*args, **kwargs):
            for old, hint in hints.items():
                if old in kwargs:
                    new = hint(kwargs) if callable(hint) else hint
                    raise TypeError(f"{fn.__name__}() got an unexpected keyword argument {old!r}: it was renamed; "
                                    f"use {new}")
            return fn(*args, **kwargs)
        return call
    return wrap
