"""Light sources as spectral power distributions: CIE illuminants, blackbodies, laser lines, RGB laser
projectors and measured CSV spectra (colour-science underneath).

References
----------
.. [1] CIE 015:2018, *Colorimetry*, 4th ed. (standard illuminants).
.. [2] ITU-R BT.2020-2 (2015): monochromatic primaries at 630, 532 and 467 nm, D65 white.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import colour
import numpy as np

from ..errors import WaveopticsError, unknown
from ..units import check_wavelengths

__all__ = ['ILLUMINANT_NAMES', 'SPD', 'laser', 'blackbody', 'standard_illuminant', 'spd_from_csv', 'illuminant']


_STANDARD_ALIASES = {f"F{i}": f"FL{i}" for i in range(1, 13)}
#: illuminant names offered in error messages (any colour-science illuminant name is accepted too)
ILLUMINANT_NAMES = ("A", "D50", "D55", "D65", "D75", "E", *(f"F{i}" for i in range(1, 13)), "rgb-laser",
                    "blackbody:<T>K", "laser:<nm>[,<nm>...]", "<file>.csv")


# ----------------------------------------------------------------------------------------------- sources

@dataclass(frozen=True, eq=False)
class SPD:
    """A spectral power distribution: continuous (per nm) or a set of lines.

    Attributes
    ----------
    name : str
        Display name (``"D65"``, ``"laser 465,532,638 nm"``).
    wavelengths_nm : numpy.ndarray
        Increasing wavelengths, nm.
    values : numpy.ndarray
        Continuous: relative spectral power per nm at ``wavelengths_nm`` (linearly interpolated between them,
        constant beyond). Lines: power of each line (continuous units × nm).
    lines : bool
        True for a line spectrum (lasers): only these wavelengths carry light.
    """

    name: str
    wavelengths_nm: np.ndarray
    values: np.ndarray
    lines: bool = False

    def __post_init__(self):
        w = check_wavelengths(self.wavelengths_nm, name=f"SPD {self.name!r} wavelength")
        v = np.asarray(self.values, dtype=float).reshape(-1)
        if v.shape != w.shape:
            raise WaveopticsError(f"SPD {self.name!r}: {v.size} values for {w.size} wavelengths")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise WaveopticsError(f"SPD {self.name!r}: spectral power must be finite and >= 0")
        order = np.argsort(w, kind="stable")
        w, v = w[order], v[order]
        if np.any(np.diff(w) <= 0):
            raise WaveopticsError(f"SPD {self.name!r}: wavelengths must be distinct")
        if not np.any(v > 0):
            raise WaveopticsError(f"SPD {self.name!r} has no power")
        w.setflags(write=False)
        v.setflags(write=False)
        object.__setattr__(self, "wavelengths_nm", w)
        object.__setattr__(self, "values", v)

    def __call__(self, wavelength_nm) -> np.ndarray:
        """Spectral power per nm at *wavelength_nm* (nm) of a continuous SPD (linear, constant beyond)."""
        if self.lines:
            raise WaveopticsError(f"SPD {self.name!r} is a line spectrum; it has no value per nm")
        return np.interp(np.asarray(wavelength_nm, dtype=float), self.wavelengths_nm, self.values)


def laser(lines_nm, powers=None, *, name: str | None = None) -> SPD:
    """A line spectrum: lasers at *lines_nm* (nm) with *powers* (equal when omitted)."""
    w = check_wavelengths(lines_nm, name="laser line")
    p = np.ones_like(w) if powers is None else np.asarray(powers, dtype=float).reshape(-1)
    label = ",".join(f"{x:g}" for x in w)
    return SPD(name or f"laser {label} nm", w, p, lines=True)


def blackbody(temperature_K: float) -> SPD:
    """Planckian radiator at *temperature_K* (K), 360–830 nm at 1 nm, normalized to 100 at 560 nm.

    References
    ----------
    .. [1] CIE 015:2018, §B.1 (Planck's law with c2 = 1.4388e-2 m·K); colour-science ``sd_blackbody``.
    """

    T = float(temperature_K)
    if not (math.isfinite(T) and 100.0 <= T <= 1e7):
        raise WaveopticsError(f"blackbody temperature {temperature_K!r} K is not allowed; use 100 to 1e7 K")
    sd = colour.sd_blackbody(T, colour.SpectralShape(360, 830, 1))
    return SPD(f"blackbody {T:g} K", sd.wavelengths, 100.0 * sd.values / sd[560])


def standard_illuminant(name: str) -> SPD:
    """A CIE (or other colour-science) illuminant by name: ``"D65"``, ``"A"``, ``"F2"`` (= ``"FL2"``), ``"E"``."""

    key = _STANDARD_ALIASES.get(name.upper(), name)
    table = {k.lower(): k for k in colour.SDS_ILLUMINANTS}
    if key.lower() not in table:
        raise unknown("illuminant", name, ILLUMINANT_NAMES)
    key = table[key.lower()]
    sd = colour.SDS_ILLUMINANTS[key]
    return SPD(name.upper() if name.upper() in _STANDARD_ALIASES else key, sd.wavelengths, sd.values)


def spd_from_csv(path, column: str | None = None) -> SPD:
    """A continuous SPD from a CSV file: first column wavelength (nm), then one column per spectrum.

    Parameters
    ----------
    path : str or Path
        CSV file with a header row (colour-science ``read_sds_from_csv_file`` format).
    column : str, optional
        Column to use; required when the file has more than one spectrum.
    """

    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"SPD file {str(p)!r} does not exist")
    try:
        sds = colour.io.read_sds_from_csv_file(str(p))
    except Exception as exc:  # noqa: BLE001 - colour raises assorted errors for malformed CSV
        raise WaveopticsError(f"SPD file {str(p)!r} is not a CSV of wavelength,value columns ({exc})") from None
    if not sds:
        raise WaveopticsError(f"SPD file {str(p)!r} has no spectrum column")
    if column is None:
        if len(sds) > 1:
            raise WaveopticsError(f"SPD file {str(p)!r} has {len(sds)} spectra ({', '.join(sds)}); "
                                  f"pick one with {p.name}:COLUMN")
        column = next(iter(sds))
    if column not in sds:
        raise unknown(f"column of {p.name}", column, list(sds))
    sd = sds[column]
    values = np.asarray(sd.values, dtype=float)
    wl = np.asarray(sd.wavelengths, dtype=float)
    # the first column is in nm: a spectrum entirely below 100 nm is a file in µm (0.38-0.78), whose light would
    # otherwise fall outside the colour-matching functions and still "give colour" from their extrapolation
    if wl.size and np.max(wl) < 100.0:
        raise WaveopticsError(f"SPD file {str(p)!r}: wavelengths {wl.min():g}-{wl.max():g} are not nm (they look "
                              "like µm); write the first column in nm")
    if not np.all(np.isfinite(values)):
        raise WaveopticsError(f"SPD file {str(p)!r} column {column!r} has missing or non-numeric values")
    return SPD(f"{p.name}:{column}" if len(sds) > 1 else p.name, sd.wavelengths, values)


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def illuminant(spec) -> SPD:
    """Parse a light-source specification into an :class:`SPD`.

    Parameters
    ----------
    spec : str or SPD
        ``"D65"``, ``"D50"``, ``"A"``, ``"F1"``..``"F12"`` (or ``"FL1"``..), ``"E"`` (equal energy), any other
        colour-science illuminant name (``"LED-B1"``, ``"FL3.1"``); ``"blackbody:5500K"``;
        ``"laser:532nm"`` or ``"laser:465,532,638"`` (equal line powers); ``"rgb-laser"`` (BT.2020 lasers
        mixed to a D65 metamer) or ``"rgb-laser:465,532,638"``; a CSV file path (``"lamp.csv"`` or
        ``"lamps.csv:COLUMN"``).

    Returns
    -------
    SPD

    Raises
    ------
    WaveopticsError
        Unknown names (with a did-you-mean suggestion), bad numbers, missing files.
    """
    if isinstance(spec, SPD):
        return spec
    if not isinstance(spec, (str, Path)):
        raise TypeError(f"illuminant must be a name or an SPD, got {type(spec).__name__}")
    s = str(spec).strip()
    low = s.lower()
    if low.startswith("blackbody:"):
        m = re.fullmatch(rf"\s*({_NUM})\s*k?\s*", low.split(":", 1)[1])
        if not m:
            raise WaveopticsError(f"illuminant {s!r}: write blackbody:TEMPERATUREK, e.g. blackbody:5500K")
        return blackbody(float(m.group(1)))
    if low.startswith("laser:") or low.startswith("rgb-laser:"):
        text = s.split(":", 1)[1].replace("nm", "")
        try:
            lines = [float(x) for x in text.split(",") if x.strip()]
        except ValueError:
            raise WaveopticsError(f"illuminant {s!r}: write laser:NM[,NM...], e.g. laser:465,532,638") from None
        if low.startswith("rgb-laser:"):
            return _registered("rgb-laser")(lines)
        return laser(lines)
    if low == "rgb-laser":
        return _registered("rgb-laser")()
    path, _, column = s.partition(".csv:")
    if column or low.endswith(".csv"):
        return spd_from_csv(path + ".csv" if column else s, column or None)
    return standard_illuminant(s)


as_spd = illuminant  # for functions whose parameter is called 'illuminant'

#: Illuminants built by a higher module, by name: the RGB laser projector is defined by metamerism
#: (:mod:`waveoptics.colour.metamers` registers it), which needs the colorimetry built on this module's SPD.
SPD_FACTORIES: dict = {}


def _registered(name: str):
    if name not in SPD_FACTORIES:  # only when waveoptics.colour.metamers was never imported
        raise WaveopticsError(f"illuminant {name!r} is defined in waveoptics.colour.metamers; import it first")
    return SPD_FACTORIES[name]
