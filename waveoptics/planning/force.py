"""Forcing a planning decision: the decisions a user may override (``waveoptics plan --force``, scene runs) and the
parser of ``["diffraction", "diffuse=off", "solver=direct"]``.
"""
from __future__ import annotations

from ..errors import FieldError, unknown

__all__ = ['FORCEABLE', 'parse_force']

FORCEABLE = {"diffraction": ("on", "off"), "diffuse": ("on", "off"), "solver": ("psd", "fft", "direct"),
             "precision": ("float32", "float64"), "directions": ("hemisphere", "views")}
_ON = {"on": True, "true": True, "yes": True, "1": True, "off": False, "false": False, "no": False, "0": False}


def parse_force(items) -> dict:
    """``["diffraction", "diffuse=off", "solver=direct"]`` -> {"diffraction": True, "diffuse": False, ...}."""
    out = {}
    for item in items or ():
        key, eq, val = str(item).partition("=")
        key, val = key.strip().lower(), (val.strip().lower() if eq else "on")
        if key not in FORCEABLE:
            raise unknown("effect", key, FORCEABLE, field='force')
        if key in ("diffraction", "diffuse"):
            if val not in _ON:
                raise FieldError(f"{{force}} {item!r}: {key} takes on or off", 'force')
            value = _ON[val]
        elif val not in FORCEABLE[key]:
            raise FieldError(f"{{force}} {item!r} is not allowed; {key} takes {', '.join(FORCEABLE[key])}", 'force')
        else:
            value = val
        if key in out and out[key] != value:   # two settings of one decision: neither may win silently
            raise FieldError(f"{{force}} sets {key} twice, to {_word(out[key])} and {_word(value)}; give it once",
                             'force')
        out[key] = value
    return out


def _word(value) -> str:
    return {True: "on", False: "off"}.get(value, str(value)) if isinstance(value, bool) else str(value)

