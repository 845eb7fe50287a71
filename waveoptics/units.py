"""Parsing of quantities with units, as typed on the command line or in scene files.

Lengths carry an SI suffix (``5nm``, ``1.2um``, ``64 µm``, ``0.5mm``, ``1e-6m``); wavelengths are
in nanometres; angles are in degrees. Every parser raises :class:`~waveoptics.errors.WaveopticsError`
naming the bad text and the accepted forms.
"""
from __future__ import annotations

import math
import re
import unicodedata

import numpy as np

from .errors import FieldError

__all__ = ['LENGTH_UNITS', 'LENGTH_UNIT_NAMES', 'ANGLE_UNITS', 'length_unit', 'unit_factor', 'parse_angle',
           'MAX_LIST_VALUES', 'parse_length', 'parse_number_list', 'parse_wavelengths', 'check_wavelengths', 'OPTICAL_RANGE_NM', 'WAVELENGTH_UNITS', 'check_optical_range', 'parse_direction', 'check_theta', 'direction_from_angles', 'split_spec']

#: metres per unit symbol (SI: BIPM SI Brochure, 9th ed. 2019, tables 5 and 7; the ångström: ISO 80000-3 and the
#: SI Brochure table 8 footnote, 1 Å = 0.1 nm, written ``A`` where Å cannot be typed)
LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9, "pm": 1e-12,
                "A": 1e-10, "Å": 1e-10}

#: spelled-out names of the units of :data:`LENGTH_UNITS` (British and American spellings, plural), the micron
#: (the name of the micrometre until the 13th CGPM, 1967, still the word of surface metrology) and the ångström;
#: matched without regard to case
LENGTH_UNIT_NAMES = {
    **{f"{p}{stem}{s}": sym for p, sym in (("", "m"), ("centi", "cm"), ("milli", "mm"), ("micro", "µm"),
                                           ("nano", "nm"), ("pico", "pm"))
       for stem in ("metre", "meter") for s in ("", "s")},
    "micron": "µm", "microns": "µm", "angstrom": "A", "angstroms": "A", "ångström": "A", "ångströms": "A"}

#: degrees per angle unit: every angle field is in degrees; a suffix may say so (``30deg``, ``30°``) or give
#: radians (``0.5rad``)
ANGLE_UNITS = {"deg": 1.0, "°": 1.0, "degree": 1.0, "degrees": 1.0, "rad": 180.0 / math.pi}


def unit_factor(suffix: str, units: dict):
    """The factor of unit *suffix* in *units* ({symbol: factor}), or None when it is not one of them.

    An exact symbol wins; otherwise the suffix is compared without regard to case (µ U+00B5 and μ U+03BC are the
    same letter under case folding) where that names one unit of several letters: ``NM`` is nm, ``UM`` µm, ``DEG``
    deg, while a single letter keeps its case (``A`` ångström, ``m`` metre; ``M`` is no unit).
    """
    if suffix in units:
        return units[suffix]
    s = unicodedata.normalize("NFKC", suffix)   # compatibility forms: the ångström sign U+212B is Å U+00C5
    exact = {unicodedata.normalize("NFKC", k): v for k, v in units.items()}
    if s in exact:
        return exact[s]
    fold = {k.casefold(): v for k, v in exact.items() if len(k) > 1}
    return fold.get(s.casefold())


def length_unit(symbol: str):
    """Metres per length unit *symbol*: a symbol of :data:`LENGTH_UNITS` (case folded as in :func:`unit_factor`)
    or a name of :data:`LENGTH_UNIT_NAMES`; None for anything else.

    References
    ----------
    .. [1] BIPM, *The International System of Units (SI)*, 9th ed., 2019, tables 5 and 7 (unit symbols and
       prefixes; symbols are case-sensitive, so only spellings that name a single unit here are folded).
    .. [2] ISO 80000-3:2019, *Quantities and units, Part 3: Space and time* (the ångström, 10⁻¹⁰ m).
    """
    s = str(symbol).strip()
    f = unit_factor(s, LENGTH_UNITS)
    if f is None and s.casefold() in LENGTH_UNIT_NAMES:
        f = LENGTH_UNITS[LENGTH_UNIT_NAMES[s.casefold()]]
    return f


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_QTY = re.compile(rf"^\s*({_NUMBER})\s*([^\d\s.,;:+-]\S*)?\s*$")


def _error(name: str, text: str) -> FieldError:
    """The error about the value of field *name*; a name "FIELD DETAIL" (``"vary sigma_nano"``) names the field
    FIELD and keeps DETAIL after it."""
    field, _, detail = str(name).partition(" ")
    return FieldError("{" + field + "}" + (" " + detail if detail else "") + text, field)


def parse_length(text, *, default_unit: str | None = None, name: str = "length",
                 allow_zero: bool = False, allow_negative: bool = False) -> float:
    """Parse a length such as ``"5nm"`` or ``"1.2um"`` and return it in metres.

    Parameters
    ----------
    text : str or float
        The quantity. A bare number is taken in *default_unit*; without one it is refused.
    default_unit : str, optional
        Unit of bare numbers (one of :data:`LENGTH_UNITS`).
    name : str
        The field this value belongs to, named in errors (:class:`~waveoptics.errors.FieldError`; the CLI writes
        it as its flag).

    Returns
    -------
    float
        Length in metres.

    Examples
    --------
    >>> parse_length("5nm"), parse_length("1.2um")
    (5e-09, 1.2e-06)
    >>> parse_length("5", name="sigma")
    Traceback (most recent call last):
    ...
    waveoptics.errors.FieldError: sigma '5' needs a unit (e.g. 5nm, 1.2um, 0.5mm)
    """
    if isinstance(text, (int, float, np.floating, np.integer)):
        if default_unit is None:
            raise _error(name, f" {text!r} needs a unit (e.g. 5nm, 1.2um, 0.5mm)")
        value, unit = float(text), default_unit
    else:
        m = _QTY.match(str(text))
        if not m:
            raise _error(name, f" {text!r} is not a length; write a number and a unit, "
                             f"e.g. 5nm, 1.2um, 0.5mm (units: {', '.join(LENGTH_UNITS)})")
        value, unit = float(m.group(1)), m.group(2) or default_unit
        if unit is None:
            raise _error(name, f" {text!r} needs a unit (e.g. 5nm, 1.2um, 0.5mm)")
        if length_unit(unit) is None:
            raise _error(name, f" {text!r} has unknown unit {unit!r}; allowed: {', '.join(LENGTH_UNITS)} "
                               "(or micron, nanometre, ...)")
    metres = value * length_unit(unit)
    if not math.isfinite(metres):
        raise _error(name, f" {text!r} is not finite")
    if metres < 0 and not allow_negative:
        raise _error(name, f" {text!r} is negative; it must be >= 0")
    if metres == 0 and not allow_zero:
        raise _error(name, f" {text!r} is zero; it must be > 0")
    return metres


#: most values a number list or range may hold (a guard against ranges that would run for hours, e.g. a step of
#: 1e-5 over 80 degrees)
MAX_LIST_VALUES = 100_000

_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf|nan"


def _symbols(units) -> str:
    """The unit symbols of *units* for an error message (spelled-out names left out)."""
    short = [u for u in units if len(u) <= 3]
    return ", ".join(short) + (", ..." if len(short) < len(units) else "")


def _number(token, name, text, units=None) -> float:
    """One finite number, optionally with a unit suffix from *units* ({suffix: factor}, looked up by
    :func:`unit_factor`); anything else is refused."""
    m = re.fullmatch(rf"\s*({_NUM})\s*(\S*?)\s*", str(token), flags=re.IGNORECASE)
    factor = 1.0 if m and not m.group(2) else (unit_factor(m.group(2), units or {}) if m else None)
    if factor is None:
        raise _error(name, f" {text!r} is not a number list; write START:STOP:STEP or A,B,C"
                           + (f" (units: {_symbols(units)})" if units else ""))
    value = float(m.group(1)) * factor
    if not math.isfinite(value):
        raise _error(name, f" {text!r}: {token.strip()!r} is not a finite number")
    return value


def parse_number_list(text, *, name: str = "value", units=None, max_values: int = MAX_LIST_VALUES) -> np.ndarray:
    """Parse ``"a:b:step"`` (inclusive of *b* when it falls on the grid) or ``"a,b,c"`` or ``"a"``.

    Every value must be finite; *units* ({suffix: factor}) allows a unit suffix on each value; at most *max_values*
    values (a range that would hold more is refused in one line, before any work).
    """
    s = str(text).strip()
    if ":" in s:
        parts = [_number(p, name, text, units) for p in s.split(":")] if s.count(":") == 2 else None
        if parts is None:
            raise _error(name, f" {text!r} is not a number list; write START:STOP:STEP or A,B,C")
        a, b, step = parts
        if step <= 0 or b < a:
            raise _error(name, f" {text!r}: a range START:STOP:STEP needs STEP > 0 and STOP >= START")
        n = math.floor((b - a) / step + 1e-9) + 1
        if n > max_values:
            raise _error(name, f" {text!r} holds {n:.3g} values; at most {max_values} are allowed (use a larger "
                               "STEP)")
        return a + step * np.arange(n)
    tokens = s.split(",")
    if all(p.strip() == "" for p in tokens):
        raise _error(name, f" {text!r} holds no number; write START:STOP:STEP or A,B,C")
    if any(p.strip() == "" for p in tokens):   # '550,,650' or '550,': a value left out is a typo, not a list
        raise _error(name, f" {text!r} has an empty item; write A,B,C with a number between every two commas")
    if len(tokens) > max_values:
        raise _error(name, f" {text!r} holds {len(tokens)} values; at most {max_values} are allowed")
    return np.array([_number(p, name, text, units) for p in tokens], dtype=float)


#: nanometres per unit a wavelength may carry: every length unit (``0.45um``, ``5500A``: the ångström of
#: spectroscopy), by symbol or name (:data:`LENGTH_UNIT_NAMES`)
WAVELENGTH_UNITS = {u: f / 1e-9 for u, f in LENGTH_UNITS.items()} | {
    n: LENGTH_UNITS[u] / 1e-9 for n, u in LENGTH_UNIT_NAMES.items()}


def parse_wavelengths(text, *, name: str = "wavelengths_nm") -> np.ndarray:
    """Parse wavelengths in nm (``"400:700:10"``, ``"450, 550, 650"``, ``"550"``); each value may carry a length
    unit (``"0.45um,550nm"``, ``"0.45 μm"``, ``"5500A"``; :data:`WAVELENGTH_UNITS`).

    Returns
    -------
    numpy.ndarray
        Wavelengths in nanometres, each > 0 and finite.
    """
    vals = parse_number_list(text, name=name, units=WAVELENGTH_UNITS)
    check_wavelengths(vals, name=name)
    check_optical_range(vals, name=name)
    return vals


#: wavelengths (nm) where this simulator's physics holds: below 100 nm (extreme UV, X-rays) the optical constants
#: are those of single atoms (n ≈ 1 − δ, tables of Henke et al. 1993) and nanometre heights are a few atoms, so
#: the continuum Fresnel index and the scalar Kirchhoff theory of a height field end; above 1 mm (microwaves) no
#: material table of the database reaches and the patches of a height field are smaller than one wavelength
OPTICAL_RANGE_NM = (100.0, 1.0e6)


def check_optical_range(wavelength_nm, *, name: str = "wavelength") -> np.ndarray:
    """Refuse wavelengths outside :data:`OPTICAL_RANGE_NM`, naming the first and where the theory ends.

    References
    ----------
    .. [1] B. L. Henke, E. M. Gullikson, J. C. Davis, "X-ray interactions: photoabsorption, scattering,
       transmission and reflection at E = 50-30000 eV", Atomic Data and Nuclear Data Tables 54, 181 (1993).
    .. [2] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon
       1963, ch. 3 (the Kirchhoff approximation needs radii of curvature ≫ λ).
    """
    w = np.atleast_1d(np.asarray(wavelength_nm, dtype=float))
    lo, hi = OPTICAL_RANGE_NM
    for x in w:
        if x < lo:
            raise _error(name, f" {x:g} nm is not allowed: below {lo:g} nm (extreme UV and X-rays) the material "
                               "data and the scalar theory of this simulator end (atomic optical constants, heights "
                               f"of a few atoms); use {lo:g}..{hi:g} nm")
        if x > hi:
            raise _error(name, f" {x:g} nm is not allowed: beyond {hi:g} nm (1 mm, microwaves) the material data "
                               f"end; use {lo:g}..{hi:g} nm")
    return w


def check_wavelengths(wavelength_nm, *, name: str = "wavelength") -> np.ndarray:
    """Validate wavelengths in nm: finite and > 0. Returns them as a float array."""
    w = np.atleast_1d(np.asarray(wavelength_nm, dtype=float))
    if w.size == 0:
        raise _error(name, ": no wavelengths given")
    bad = w[~np.isfinite(w) | (w <= 0)]
    if bad.size:
        raise _error(name, f" {float(bad[0])!r} nm is not allowed; wavelengths must be finite and > 0 nm")
    return w


def parse_direction(text, *, name: str = "incident_deg", need_phi: bool = False,
                    max_theta_deg: float = 90.0) -> tuple[float, float]:
    """Parse ``"THETA[,PHI]"`` in degrees; θ from the normal in [0, *max_theta_deg*] (90: above the surface; 180
    for a BSDF over the whole sphere, θ > 90° below it), φ about the normal (any finite value; outside [−180, 360)
    it is brought into [0, 360)).

    Returns
    -------
    (theta_deg, phi_deg) : tuple of float
    """
    vals = [_angle_value(p) for p in str(text).split(",")]
    if any(v is None for v in vals):
        raise _error(name, f" {text!r} is not THETA[,PHI] in degrees (each may end in deg or °)")
    if len(vals) not in ((2,) if need_phi else (1, 2)):
        raise _error(name, f" {text!r}: give {'THETA,PHI' if need_phi else 'THETA[,PHI]'} in degrees")
    theta = vals[0]
    phi = vals[1] if len(vals) == 2 else 0.0
    check_theta(theta, name=name, max_theta_deg=max_theta_deg)
    if not math.isfinite(phi):
        raise _error(name, f" φ {phi!r} is not finite")
    if not -180.0 <= phi < 360.0:   # one turn of azimuth: 400° is 40°, said once in its canonical form
        phi = math.fmod(phi, 360.0) % 360.0
    return theta, phi


def _angle_value(text):
    """Degrees from a number or a number with a unit of :data:`ANGLE_UNITS` (NaN and Inf pass, for the caller's
    range check to name); None for anything else."""
    if isinstance(text, (int, float, np.floating, np.integer)) and not isinstance(text, bool):
        return float(text)
    m = re.fullmatch(rf"\s*({_NUM})\s*(\S*?)\s*", str(text), flags=re.IGNORECASE)
    factor = (1.0 if not m.group(2) else unit_factor(m.group(2), ANGLE_UNITS)) if m else None
    return None if factor is None else float(m.group(1)) * factor


def parse_angle(text, *, name: str = "angle_deg") -> float:
    """An angle in degrees from ``"30"``, ``"30deg"``, ``"30 °"``, ``"30 degrees"`` or ``"0.5rad"``
    (:data:`ANGLE_UNITS`); numbers pass through. Not range-checked (callers know their range); NaN and Inf are
    refused.

    References
    ----------
    .. [1] BIPM, *The International System of Units (SI)*, 9th ed., 2019, table 8 (the degree, ° = π/180 rad,
       written without a space or with one).
    """
    value = _angle_value(text)
    if value is None:
        raise _error(name, f" {text!r} is not an angle; write degrees, e.g. 30, 30deg or 30°")
    if not math.isfinite(value):
        raise _error(name, f" {text!r} is not finite")
    return value


def check_theta(theta_deg, *, name: str = "theta", max_theta_deg: float = 90.0) -> None:
    """Refuse zenith angles outside [0°, *max_theta_deg*] (90°: directions below the surface are not inputs,
    except for a BSDF over the whole sphere, 180°)."""
    t = np.atleast_1d(np.asarray(theta_deg, dtype=float))
    bad = t[~np.isfinite(t) | (t < 0) | (t > max_theta_deg)]
    if bad.size:
        raise _error(name, f" θ={float(bad[0])!r}° is outside the allowed range [0, {max_theta_deg:g}] degrees")


def direction_from_angles(theta_deg, phi_deg=0.0) -> np.ndarray:
    """Unit vector(s) (x, y, z) for zenith θ and azimuth φ in degrees; z is the macro normal."""
    t = np.radians(np.asarray(theta_deg, dtype=float))
    p = np.radians(np.asarray(phi_deg, dtype=float))
    t, p = np.broadcast_arrays(t, p)
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


def split_spec(text) -> tuple[str, list[tuple[str, str, str]]]:
    """The ``MODEL:key=value,...`` grammar of every model option (``--nano``, a generator, a cost configuration):
    (model name lower-cased, [(key, value, item), ...]) with *key* and *value* stripped and *item* the raw text of
    the entry; an entry without ``=`` has an empty key and value and its own text as *item*, so each caller names
    its own field in the error it raises."""
    model, _, rest = str(text).strip().partition(":")
    items = []
    for item in filter(None, (p.strip() for p in rest.split(","))):
        key, eq, val = item.partition("=")
        items.append((key.strip(), val.strip(), item) if eq else ("", "", item))
    return model.strip().lower(), items
