"""Thin-film stacks as materials: a substrate under any number of films (oxide on a metal, anodizing, an oil film,
an antireflection coating), with the interface of :class:`~waveoptics.materials.Material` (``F``, ``F0``, ``F_sp``,
``F_facet``), evaluated by the transfer-matrix method of :mod:`waveoptics.materials.stack`.

Grammar
-------
``SUBSTRATE|FILM:THICKNESS|FILM:THICKNESS...``: the films are listed **from the substrate outwards** and the light
comes from air onto the last one. ``"Al|Al2O3:120nm"`` is aluminium under 120 nm of alumina;
``"Si|SiO2:100nm|TiO2:50nm"`` is silicon under 100 nm of silica under 50 nm of titania. Each layer is any material
with a complex index that :func:`~waveoptics.materials.get_material` accepts (a preset or alias, ``PRESET@PAGE``,
``shelf/book/page``, ``n+kj``; not ``f0:``); each thickness is a length with its unit (``5nm``, ``1.2um``,
:func:`waveoptics.units.parse_length`), 0 allowed (the bare substrate).

A film may end in ``:roughness=R``: the rms roughness of its top interface relative to the substrate's (R ≥ 0; the
nano-roughness model describes the substrate's interface, and this interface's PSD is R² times it, the same shape:
a film that smooths, R < 1, or roughens, R > 1, its substrate's profile). ``"Al|Al2O3:120nm:roughness=0.5"``;
without it R = 1 (a film replicating its substrate). Only first-order scatter of the rough stack uses it.

Films and the single-interface models
-------------------------------------
A stack has no single interface index: :meth:`Stack.eta` refuses (naming the ``material`` field) rather than
silently using the substrate. The first-order perturbation (Rayleigh-Rice) entry points therefore take a stack to
Elson's first-order scatter of a stack whose interfaces are rough (:func:`waveoptics.scatter.rough_stack_brdf`,
the one PSD on every interface), correlated as :attr:`Stack.roughness_correlation` says (set it with
:func:`with_roughness_correlation`; Elson, Rahn & Bennett 1983). Code that needs one interface's permittivity
(:func:`waveoptics.scatter.permittivity`) refuses a stack in one line. Geometric-optics and Kirchhoff models take
the stack's reflectance of each facet (``F``, ``F_facet``): the films are taken to follow the micro- and
nano-roughness conformally, each facet a flat stack.

References
----------
.. [1] F. Abelès, Ann. Phys. (Paris) 12(5), 596–640, 706–782, 1950.
.. [2] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6.
.. [3] O. S. Heavens, *Optical Properties of Thin Solid Films*, Butterworths 1955, ch. 4.
.. [4] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press 2010, ch. 2.
.. [5] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (rough multilayers with
   correlated and uncorrelated interfaces).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import FieldError, WaveopticsError
from ..units import LENGTH_UNITS, parse_length
from ..vocabulary import ROUGHNESS_CORRELATIONS
from . import fresnel, stack
from .database import SPEC_PARSERS, Material, get_material

__all__ = ['Stack', 'parse_stack', 'GRAMMAR', 'ROUGHNESS_KEY', 'ROUGHNESS_CORRELATIONS', 'roughness_correlation',
           'with_roughness_correlation']

#: the stack grammar, as errors write it
GRAMMAR = ("SUBSTRATE|FILM:THICKNESS[:roughness=R]|... (films from the substrate outwards, e.g. Al|Al2O3:120nm or "
           "Al|Al2O3:120nm:roughness=0.5)")


@dataclass(frozen=True)
class Stack(Material):
    """A substrate under thin films, incidence from air: a :class:`Material` whose reflectance is that of the stack.

    Attributes
    ----------
    substrate : Material
        The semi-infinite substrate.
    films : tuple of (Material, float)
        The films and their thicknesses in nm, **from the substrate outwards**.
    roughness_correlation : str or float
        Cross-correlation of the interfaces' roughness profiles when the stack is rough (first-order scatter,
        :func:`waveoptics.scatter.rough_stack_brdf`): ``"correlated"`` (default: a thin evaporated film replicates
        its substrate's roughness, Elson 1979; Stover ch. 6), ``"uncorrelated"`` or a coefficient in [0, 1]
        (:func:`roughness_correlation`). The flat stack's reflectance does not depend on it.
    interface_roughness : tuple of float
        The rms roughness of each interface relative to the nano-roughness model's, substrate interface first (one
        more than the films); () for 1 on every interface. Interface j's PSD is r_j² times the model's.
    """

    substrate: Material = None
    films: tuple = ()
    roughness_correlation: object = "correlated"
    interface_roughness: tuple = ()

    @property
    def cache_name(self) -> str:
        """The name (with any interface roughness) and the roughness correlation: a key for caches of rough-stack
        quantities."""
        return f"{self.name}~{self.roughness_correlation}"

    @property
    def roughness_scales(self) -> tuple:
        """r_j of every interface, substrate interface first (:attr:`interface_roughness`, 1 where not given)."""
        return tuple(self.interface_roughness) or (1.0,) * (len(self.films) + 1)

    @property
    def has_index(self) -> bool:
        """False: a stack has no single interface index (:meth:`eta` refuses)."""
        return False

    @property
    def thicknesses_nm(self) -> tuple:
        """The film thicknesses (nm), from the substrate outwards."""
        return tuple(d for _, d in self.films)

    def eta(self, wavelength_nm) -> np.ndarray:
        """Refused: a stack has no single refractive index (the substrate's would silently drop the films)."""
        raise FieldError(f"{{material}} {self.name!r} is a thin-film stack and has no single refractive index; this "
                         "computation needs one interface (a bare material: preset, shelf/book/page or n+kj)",
                         "material")

    def indices(self, wavelength_nm):
        """(n_substrate, [n_film, ...]) at *wavelength_nm* (nm), each of its shape (clamped at the data ranges as
        :meth:`Material.eta`)."""
        return self.substrate.eta(wavelength_nm), [m.eta(wavelength_nm) for m, _ in self.films]

    def optical_thickness_nm(self, wavelength_nm) -> np.ndarray:
        """Σ_j Re(n_j) d_j (nm) of the films at *wavelength_nm* (nm): the normal-incidence path that sets the fringes."""
        return sum(np.real(m.eta(wavelength_nm)) * d for m, d in self.films)

    def fringe_spacing_nm(self, wavelength_nm) -> np.ndarray:
        """Spacing Δλ ≈ λ²/(2 Σ n_j d_j cos θ_j) (nm) of the interference fringes of R(λ) near *wavelength_nm*,
        at normal incidence (cos θ_j = 1: the closest fringes of any angle, as n d cos θ_j ≤ n d); inf without
        film.

        References
        ----------
        .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §7.5.1 (fringes of equal inclination: successive
           orders m of 2 n d cos θ = m λ, whence Δλ = λ²/(2 n d cos θ)).
        .. [2] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., 2010, §2.7 (the spectral period of a film).
        """
        w = np.asarray(wavelength_nm, dtype=float)
        opd = self.optical_thickness_nm(w)
        with np.errstate(divide="ignore"):
            return np.where(opd > 0, w * w / (2.0 * np.maximum(opd, 1e-300)), np.inf)

    def out_of_range(self, wavelength_nm) -> np.ndarray:
        """Wavelengths outside the data range of any layer (clamped there)."""
        out = self.substrate.out_of_range(wavelength_nm)
        for m, _ in self.films:
            out = out | m.out_of_range(wavelength_nm)
        return out

    def F_sp(self, cos_theta_i, wavelength_nm):
        """(R_s, R_p) of the stack, broadcasting *cos_theta_i* against *wavelength_nm* (nm).

        References
        ----------
        .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6; :func:`waveoptics.materials.stack.R`.
        """
        ns, nf = self.indices(wavelength_nm)
        w = np.asarray(wavelength_nm, dtype=float)
        d = self.thicknesses_nm
        return (stack.R(cos_theta_i, w, ns, nf, d, "s"), stack.R(cos_theta_i, w, ns, nf, d, "p"))

    def F(self, cos_theta_i, wavelength_nm) -> np.ndarray:
        """Unpolarized reflectance (R_s + R_p)/2 of the stack."""
        Rs, Rp = self.F_sp(cos_theta_i, wavelength_nm)
        return 0.5 * (Rs + Rp)

    def F0(self, wavelength_nm) -> np.ndarray:
        """Normal-incidence reflectance spectrum of the stack."""
        return self.F(1.0, wavelength_nm)

    def F_facet(self, wi, wo, wavelength_nm, polarization: str = "unpolarized"):
        """The facet reflectance for s, p or unpolarized light (:func:`waveoptics.materials.fresnel.F_facet_sp`
        with the stack's R_s, R_p)."""
        return fresnel.F_facet_sp(wi, wo, lambda cos_d: self.F_sp(cos_d, wavelength_nm), polarization)


def _layer(spec: str, token: str, role: str) -> Material:
    """The material of one layer of *spec*, refused in one line naming *token* when it has no complex index."""
    if not token:
        raise FieldError(f"{{material}} {spec!r}: empty {role} between '|'; write {GRAMMAR}", "material")
    if token.lower().startswith("f0:"):
        raise FieldError(f"{{material}} {spec!r}: {role} {token!r} gives only F0; a stack needs complex indices "
                         "(a preset, PRESET@PAGE, shelf/book/page or n+kj)", "material")
    try:
        m = get_material(token)
    except WaveopticsError as e:
        raise FieldError(f"{{material}} {spec!r}: {role} {token!r}: {e}",
                         "material") from None
    return m


def _thickness_nm(spec: str, film: str, text: str) -> float:
    try:
        return parse_length(text, name="material", allow_zero=True) * 1e9
    except WaveopticsError:
        raise FieldError(f"{{material}} {spec!r}: film {film!r} has thickness {text!r}, which is not a length >= 0 "
                         f"with a unit ({', '.join(LENGTH_UNITS)}), e.g. 120nm or 1.2um", "material") from None


#: the suffix of a film giving its top interface's relative roughness (module docstring)
ROUGHNESS_KEY = "roughness="


def _film_roughness(spec: str, tok: str):
    """(the film token without ``:roughness=R``, R or None)."""
    head, sep, value = tok.rpartition(":")
    if not sep or not value.strip().lower().startswith(ROUGHNESS_KEY):
        return tok, None
    text = value.strip()[len(ROUGHNESS_KEY):]
    try:
        r = float(text)
    except ValueError:
        r = float("nan")
    if not (np.isfinite(r) and r >= 0.0):
        film = head.rpartition(":")[0].strip() or head.strip()
        raise FieldError(f"{{material}} {spec!r}: film {film!r} has roughness {text!r}, which is not a "
                         "number >= 0 (the rms roughness of its top interface relative to the substrate's, e.g. "
                         "roughness=0.5)", "material")
    return head.strip(), r


def parse_stack(spec: str) -> Stack:
    """A :class:`Stack` from ``"SUBSTRATE|FILM:THICKNESS[:roughness=R]|..."`` (module docstring), films from the
    substrate outwards.

    Raises
    ------
    FieldError
        Naming the ``material`` field and the bad token: an empty layer, a film without ``:THICKNESS``, a thickness
        that is not a length ≥ 0 with a unit, a roughness that is not a number ≥ 0, a layer the database does not
        know or that gives only F0.
    """
    s = str(spec).strip()
    tokens = [t.strip() for t in s.split("|")]
    if ":" in tokens[0] and not tokens[0].lower().startswith("f0:"):
        raise FieldError(f"{{material}} {s!r}: the substrate {tokens[0]!r} takes no thickness (it is semi-infinite); "
                         f"write {GRAMMAR}", "material")
    substrate = _layer(s, tokens[0], "substrate")
    films, scales = [], [1.0]
    for tok in tokens[1:]:
        tok, r = _film_roughness(s, tok)
        scales.append(1.0 if r is None else r)
        if ":" not in tok:
            _layer(s, tok, "film")   # an empty or unknown token is named as such first
            raise FieldError(f"{{material}} {s!r}: film {tok!r} needs a thickness; write FILM:THICKNESS, e.g. "
                             f"{tok or 'Al2O3'}:120nm", "material")
        name, _, text = tok.rpartition(":")
        m = _layer(s, name.strip(), "film")
        films.append((m, _thickness_nm(s, name.strip(), text.strip())))
    if not films:
        raise FieldError(f"{{material}} {s!r} has no film after '|'; write {GRAMMAR}", "material")
    los = [substrate.wavelength_range_nm[0]] + [m.wavelength_range_nm[0] for m, _ in films]
    his = [substrate.wavelength_range_nm[1]] + [m.wavelength_range_nm[1] for m, _ in films]
    rough = any(r != 1.0 for r in scales)
    name = "|".join([substrate.name] + [f"{m.name}:{d:.10g}nm" + (f":{ROUGHNESS_KEY}{r:.10g}" if rough else "")
                                        for (m, d), r in zip(films, scales[1:])])   # exact enough to key caches
    source = "thin-film stack (transfer matrix) of " + "; ".join(
        [f"substrate {substrate.name}: {substrate.source}"] + [f"{d:g} nm {m.name}: {m.source}" for m, d in films])
    return Stack(name=name, source=source, category=substrate.category,
                 wavelength_range_nm=(max(los), min(his)), substrate=substrate, films=tuple(films),
                 interface_roughness=tuple(scales) if rough else ())


def roughness_correlation(value, field: str = "roughness_correlation"):
    """A roughness correlation as a stack holds it: ``"correlated"``, ``"uncorrelated"`` or a float in [0, 1]
    (text such as ``"0.5"`` is read as a number; 1 and 0 stay numbers: the same as the names).

    Raises
    ------
    FieldError
        Naming *field*, for any other value.

    References
    ----------
    .. [1] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (partly correlated
       interfaces: S_jk = c √(S_j S_k)).
    """
    if isinstance(value, str):
        text = value.strip().lower()
        if text in ROUGHNESS_CORRELATIONS:
            return text
        try:
            value = float(text)
        except ValueError:
            raise FieldError(f"{{{field}}} {value!r} is not allowed; use one of {', '.join(ROUGHNESS_CORRELATIONS)} "
                             "or a coefficient in [0, 1]", field) from None
    if isinstance(value, (bool, np.bool_)):
        raise FieldError(f"{{{field}}} {value!r} is not allowed; use one of {', '.join(ROUGHNESS_CORRELATIONS)} "
                         "or a coefficient in [0, 1]", field)
    try:
        c = float(value)
    except (TypeError, ValueError):
        raise FieldError(f"{{{field}}} {value!r} is not allowed; use one of {', '.join(ROUGHNESS_CORRELATIONS)} "
                         "or a coefficient in [0, 1]", field) from None
    if not 0.0 <= c <= 1.0:   # also refuses nan
        raise FieldError(f"{{{field}}} {value!r} is not allowed; a correlation coefficient lies in [0, 1]", field)
    return c


def with_roughness_correlation(material, correlation):
    """*material* with the interface-roughness *correlation* (:func:`roughness_correlation`) when it is a
    :class:`Stack`; any other material unchanged (one rough interface has nothing to correlate with)."""
    c = roughness_correlation(correlation)
    if isinstance(material, Stack):
        return dataclasses.replace(material, roughness_correlation=c)
    return material


SPEC_PARSERS["stack"] = parse_stack
