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

import numpy as np

from ..errors import WaveopticsError, unknown
from ..units import WAVELENGTH_UNITS, check_wavelengths, parse_number_list
from .cie_tables import d65

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
    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)
    sd = colour.sd_blackbody(T, colour.SpectralShape(360, 830, 1))
    return SPD(f"blackbody {T:g} K", sd.wavelengths, 100.0 * sd.values / sd[560])


def standard_illuminant(name: str) -> SPD:
    """A CIE (or other colour-science) illuminant by name: ``"D65"``, ``"A"``, ``"F2"`` (= ``"FL2"``), ``"E"``."""

    key = _STANDARD_ALIASES.get(name.upper(), name)
    if key.lower() == "d65":   # the default illuminant, without importing colour-science (cie_tables)
        return SPD("D65", *d65())
    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)
    table = {k.lower(): k for k in colour.SDS_ILLUMINANTS}
    if key.lower() not in table:
        raise unknown("illuminant", name, ILLUMINANT_NAMES)
    key = table[key.lower()]
    sd = colour.SDS_ILLUMINANTS[key]
    return SPD(name.upper() if name.upper() in _STANDARD_ALIASES else key, sd.wavelengths, sd.values)


#: most data rows an SPD file may hold (a spectrometer's 0.01 nm steps over 380-780 nm are 40 001)
MAX_SPD_ROWS = 100_000


_DECIMAL_COMMA = re.compile(r"^([-+]?\d+),(\d+(?:[eE][-+]?\d+)?)$")


def _spd_delimiter(lines) -> str | None:
    """The separator of a spectrum file, from its first data line: ',' (CSV), ';' (spreadsheets in locales
    whose decimal mark is the comma), a tab, or None for runs of blanks (the two-column text files spectrometer
    software writes)."""
    for line in lines:
        for d in (",", ";", "\t"):
            if d in line:
                return d
        if line.strip():
            return None
    return ","


def _spd_lines(fh):
    """(line number, text) of the lines that hold data or the header: blank lines and '#' comments (whole lines or
    after the values) left out."""
    for n, line in enumerate(fh, 1):
        text = line.split("#", 1)[0].strip()
        if text:
            yield n, text


def _read_spd_rows(p: Path):
    """(column names, rows of floats) of a spectrum file: a header row (wavelength, then one name per spectrum; a
    file without one gets the names 1, 2, ...), values separated by ',', ';', a tab or blanks; a UTF-8
    byte-order mark, Windows line ends, blank lines, '#' comments and an empty last cell (a trailing separator, as
    spreadsheets export) ignored. One line errors: no data, a ragged or non-numeric row, more than
    :data:`MAX_SPD_ROWS` rows.

    References
    ----------
    .. [1] Y. Shafranovich, "Common Format and MIME Type for Comma-Separated Values (CSV) Files", RFC 4180 (2005)
       (the comma, CRLF line ends, quoted fields; other separators are the common variants of the format).
    """
    import csv

    try:
        fh = open(p, newline="", encoding="utf-8-sig")
    except OSError as exc:
        raise WaveopticsError(f"SPD file {str(p)!r} cannot be read ({exc.strerror})") from None
    names, rows = None, []
    with fh:
        try:
            lines = list(_spd_lines(fh))
            delim = _spd_delimiter(t for _, t in lines)
            for n, text in lines:
                cells = [c.strip() for c in (next(csv.reader([text], delimiter=delim)) if delim else text.split())]
                if len(cells) > 1 and cells[-1] == "":
                    cells = cells[:-1]
                if delim == ";":   # '400;1,25': with ';' between values a comma between digits is a decimal mark
                    cells = [_DECIMAL_COMMA.sub(r"\1.\2", c) for c in cells]
                try:
                    vals = [float(c) for c in cells]
                except ValueError:
                    if names is None and not rows:
                        names = cells[1:]
                        continue
                    raise WaveopticsError(f"SPD file {str(p)!r} line {n}: {text[:60]!r} is not numbers "
                                          "(wavelength,value,...)") from None
                if len(rows) >= MAX_SPD_ROWS:
                    raise WaveopticsError(f"SPD file {str(p)!r} holds more than {MAX_SPD_ROWS} rows; at most "
                                          f"{MAX_SPD_ROWS} are allowed (resample it, e.g. to 1 nm steps)")
                rows.append(vals)
        except (UnicodeDecodeError, csv.Error) as exc:
            raise WaveopticsError(f"SPD file {str(p)!r} is not a CSV text file ({exc})") from None
    if not rows:
        raise WaveopticsError(f"SPD file {str(p)!r} has no data rows; write wavelength,value rows (nm) under a "
                              "header row")
    width = len(rows[0])
    names = names if names is not None else [str(k) for k in range(1, width)]
    if width < 2 or any(len(r) != width for r in rows) or len(names) != width - 1:
        raise WaveopticsError(f"SPD file {str(p)!r} needs the same columns on every row: wavelength (nm), then "
                              f"one value per spectrum ({', '.join(names) or 'none named'})")
    return names, np.asarray(rows, dtype=float)


def spd_from_csv(path, column: str | None = None) -> SPD:
    """An SPD from a CSV file: first column wavelength (nm), then one column per spectrum.

    Several rows are a continuous spectrum (per nm, linear between rows); a single row is one line of that
    wavelength and power (a laser, the way a lab writes one line: ``wavelength,power`` / ``532,1``).

    Parameters
    ----------
    path : str or Path
        CSV file with a header row (colour-science ``read_sds_from_csv_file`` format: wavelength, then names).
    column : str, optional
        Column to use; required when the file has more than one spectrum.
    """

    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"SPD file {str(p)!r} does not exist")
    names, data = _read_spd_rows(p)
    if column is None:
        if len(names) > 1:
            raise WaveopticsError(f"SPD file {str(p)!r} has {len(names)} spectra ({', '.join(names)}); "
                                  f"pick one with {p.name}:COLUMN")
        column = names[0]
    if column not in names:
        raise unknown(f"column of {p.name}", column, list(names))
    wl = data[:, 0]
    values = data[:, 1 + names.index(column)]
    # the first column is in nm: a spectrum entirely below 100 nm is a file in µm (0.38-0.78), whose light would
    # otherwise fall outside the colour-matching functions and still "give colour" from their extrapolation
    if wl.size and np.max(wl) < 100.0:
        raise WaveopticsError(f"SPD file {str(p)!r}: wavelengths {wl.min():g}-{wl.max():g} are not nm (they look "
                              "like µm); write the first column in nm")
    if not np.all(np.isfinite(values)) or not np.all(np.isfinite(wl)):
        raise WaveopticsError(f"SPD file {str(p)!r} column {column!r} has missing or non-numeric values")
    name = f"{p.name}:{column}" if len(names) > 1 else p.name
    return SPD(name, wl, values, lines=wl.size == 1)


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
        text = s.split(":", 1)[1]
        try:   # each line in nm, or with a length unit (532nm, 0.532um: waveoptics.units.WAVELENGTH_UNITS)
            if ":" in text:
                raise WaveopticsError("a range is no list of lines")
            lines = list(parse_number_list(text, name="illuminant", units=WAVELENGTH_UNITS))
        except WaveopticsError:
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
