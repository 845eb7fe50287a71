"""One simulation request: its fields, their defaults and validation, the nano-roughness grammar and the
wavelength choice.

Every front end builds a :class:`SimulationRequest`: the CLI (``simulate``, ``compare``, ``table``, ``sweep``), the
Python API (:func:`waveoptics.simulate.simulate`), scene files (:func:`waveoptics.distributed.case_from_scene`),
the planner and the Dask tasks. The rules live here once. Errors are :class:`~waveoptics.errors.FieldError`
naming the field (``micro_alpha``, ``nano``, ``incident_deg`` ...); only the CLI writes them as its flags.

Nano roughness is written ``MODEL:key=value,...`` with lengths in units (docs/physics.md §4 for the PSDs):

    abc:sigma=10nm,B=2um,C=2.6
    gaussian:sigma=5nm,corr_length=1um        exponential:sigma=5nm,corr_length=1um
    sinusoid:amplitude=40nm,period=2um[,orientation=DEG]
    scratches:count=20,width=200nm,depth=30nm[,orientation=DEG,spread=DEG]

``corr_length`` is the correlation length (the PSD formulas' T); the old spelling ``T=`` is accepted with a
one-line deprecation warning until waveoptics 0.3. Statistics models (gaussian, exponential, abc) run on the PSD series when the solver allows it; the others (and
statistics with ``solver='fft'|'direct'``) are generated as height fields sized by :func:`nano_surface_size`.

Examples
--------
>>> from waveoptics.request import SimulationRequest, parse_nano
>>> parse_nano("gaussian:sigma=5nm,corr_length=1um")
('gaussian', {'sigma': 5e-09, 'corr_length': 1e-06})
>>> req = SimulationRequest(material="Au", micro_alpha=0.1, wavelengths_nm=(450, 550, 650))
>>> req.wavelengths().tolist()
[450.0, 550.0, 650.0]
>>> SimulationRequest(micro_alpha=-1)
Traceback (most recent call last):
...
waveoptics.errors.FieldError: micro_alpha -1 is not allowed; α must be finite and >= 0
"""
from __future__ import annotations

import dataclasses
import functools
import math
import warnings
from dataclasses import dataclass

import numpy as np

# the numerical sub-packages (colour, surfaces, brdf, materials) are imported where they are used, so that the
# command line can read the fields' defaults (:func:`request_default`) without loading them
from .errors import FieldError, RenamedWarning, WaveopticsError, unknown
from .units import check_optical_range, check_theta, check_wavelengths, parse_length, split_spec
from .vocabulary import (DEFAULT_MATERIAL, DEFAULT_NANO, DEFAULT_NDF, DIFFRACTION, NANO_SOLVERS,
                         PARAMETRIC_NDF_NAMES, POLARIZATIONS, PRECISIONS, ROUGHNESS_CORRELATIONS,
                         SHADOWING_NAMES)

__all__ = ["DEFAULT_NANO", "NO_NANO", "NANO_PARAMS", "NANO_ALIASES", "NANO_RENAMED", "nano_key", "psd_statistics", "RESOLUTION_RANGE",
           "MAX_NANO_SAMPLES", "SimulationRequest", "request_default", "parse_nano", "nano_surface_size",
           "make_nano", "crop"]

#: the documented way to say "no nano roughness" (σ = 0)
NO_NANO = "gaussian:sigma=0nm,corr_length=1um"

#: parameter names accepted by ``MODEL:...`` nano text (lengths take units)
NANO_PARAMS = {
    "gaussian": {"sigma": "length", "corr_length": "length"},
    "exponential": {"sigma": "length", "corr_length": "length"},
    "abc": {"sigma": "length", "B": "length", "C": "number"},
    "sinusoid": {"amplitude": "length", "period": "length", "orientation": "number"},
    "scratches": {"count": "number", "width": "length", "depth": "length", "orientation": "number",
                  "spread": "number"},
}
#: other spellings of a nano parameter → its one name (old → new)
NANO_ALIASES = {"corr": "corr_length", "corr-length": "corr_length", "a": "amplitude", "amp": "amplitude",
                "b": "B", "c": "C", "rms": "sigma"}
#: retired spellings still accepted for one release with a one-line warning (old → new)
NANO_RENAMED = {"T": "corr_length"}
_NANO_OPTIONAL = ("orientation", "spread")
_NANO_ZERO_OK = ("sigma", "depth", "amplitude")

#: allowed direction-grid resolutions (cells per axis)
RESOLUTION_RANGE = (8, 2048)

#: nano height fields larger than this per side are cropped to a central tile for the solvers (the statistics of
#: a stationary surface are the same on the tile; the cost is not)
MAX_NANO_SAMPLES = 512


def parse_nano(text: str) -> tuple[str, dict]:
    """Parse ``MODEL:key=value,...`` nano-roughness text into (model, parameters in SI units).

    Parameters
    ----------
    text : str
        E.g. ``"abc:sigma=10nm,B=5um,C=3"``; lengths need units (``5nm``, ``1.2um``), angles are degrees.

    Returns
    -------
    (str, dict)
        The model name and its parameters (lengths in m).
    """
    model, items = split_spec(text)
    if model not in NANO_PARAMS:
        raise unknown("nano model", model, NANO_PARAMS, field="nano")
    params = {}
    for key, val, item in items:
        key = nano_key(key)
        if not key or key not in NANO_PARAMS[model]:
            raise FieldError(f"{{nano}} {text!r}: parameter {item!r} is not allowed for {model}; "
                             f"use {', '.join(k + '=...' for k in NANO_PARAMS[model])}", "nano")
        if key in params:
            raise FieldError(f"{{nano}} {text!r}: parameter {key!r} is given twice", "nano")
        if NANO_PARAMS[model][key] == "length":
            params[key] = parse_length(val, name=f"nano {key}", allow_zero=key in _NANO_ZERO_OK)
        else:
            try:
                params[key] = float(val)
            except ValueError:
                raise FieldError(f"{{nano}} {key}={val!r} is not a number", "nano") from None
            if not math.isfinite(params[key]):
                raise FieldError(f"{{nano}} {key}={val!r} is not finite", "nano")
    missing = [k for k in NANO_PARAMS[model] if k not in params and k not in _NANO_OPTIONAL]
    if missing:
        raise FieldError(f"{{nano}} {text!r} lacks {', '.join(missing)} (units: 5nm, 1.2um)", "nano")
    return model, params


def psd_statistics(text: str, user: str):
    """The height statistics (:class:`~waveoptics.surfaces.PSDModel`) of nano-roughness text ``MODEL:params``
    (:func:`parse_nano`) for a first-order model *user* (named in the refusal), or None for σ = 0. A generator
    that is not a PSD family (a grating, a height-field file) is refused naming ``nano``."""
    from . import surfaces

    model, p = parse_nano(text)
    if model not in surfaces.PSD_MODELS:
        raise FieldError(f"{{nano}} {text!r}: {user} needs height statistics ({', '.join(surfaces.PSD_MODELS)}), "
                         f"not {model!r}", "nano")
    if p["sigma"] <= 0:
        return None
    return surfaces.PSDModel(model, sigma=p["sigma"], T=p.get("corr_length"), B=p.get("B"), C=p.get("C"))


def nano_key(key: str) -> str:
    """The one name of the nano parameter spelled *key* (:data:`NANO_ALIASES`); a retired spelling
    (:data:`NANO_RENAMED`: ``T`` → ``corr_length``) is accepted with a one-line :class:`RenamedWarning`."""
    if key in NANO_RENAMED:
        new = NANO_RENAMED[key]
        warnings.warn(f"nano parameter {key}= is deprecated and will be removed in waveoptics 0.3; use {new}=",
                      RenamedWarning, stacklevel=3)
        return new
    return NANO_ALIASES.get(key, key)


def nano_surface_size(wavelengths_nm, length_scale_m, *, max_samples=MAX_NANO_SAMPLES) -> tuple[float, int]:
    """Patch size (m) and samples per side for a generated nano height field.

    The spacing is ≤ λ_min/4 (no aliasing over the whole hemisphere, docs/physics.md §1) and the patch spans ≥ 16
    correlation lengths (statistics) and ≥ 24 λ_max (the specular spike is about λ/L wide), within
    *max_samples*.
    """
    lmin = float(np.min(wavelengths_nm)) * 1e-9
    lmax = float(np.max(wavelengths_nm)) * 1e-9
    dx = lmin / 4
    L = max(16 * length_scale_m, 24 * lmax)
    n = int(min(max_samples, 2 ** math.ceil(math.log2(max(L / dx, 64)))))
    return n * dx, n


def crop(hf, n: int):
    """The central tile of at most n × n samples of *hf* (a :class:`~waveoptics.surfaces.HeightField`; unchanged if
    already that small)."""
    from .surfaces import HeightField

    ny, nx = hf.shape
    if ny <= n and nx <= n:
        return hf
    y0, x0 = max(0, (ny - n) // 2), max(0, (nx - n) // 2)
    sl = (slice(y0, y0 + min(n, ny)), slice(x0, x0 + min(n, nx)))
    meta = {k: v for k, v in hf.meta.items() if k != "periodic"}  # a tile of a periodic field is not periodic
    meta["cropped_from"] = [ny, nx]
    return HeightField(hf.heights[sl], hf.dx, hf.dy, None if hf.mask is None else hf.mask[sl], meta)


def _generator_args(model: str, p: dict, seed: int) -> dict:
    """Keyword arguments of :func:`waveoptics.surfaces.generate` for parsed nano text."""
    args = {"gaussian": dict(sigma=p.get("sigma"), corr_length=p.get("corr_length")),
            "exponential": dict(sigma=p.get("sigma"), corr_length=p.get("corr_length")),
            "abc": dict(sigma=p.get("sigma"), B=p.get("B"), C=p.get("C")),
            "sinusoid": dict(amplitude=p.get("amplitude"), period=p.get("period"),
                             orientation_deg=p.get("orientation", 0.0)),
            "scratches": dict(count=p.get("count", 10), width=p.get("width"), depth=p.get("depth"),
                              orientation_deg=p.get("orientation", 0.0), spread_deg=p.get("spread", 0.0))}[model]
    if model != "sinusoid":  # the only deterministic generator
        args["seed"] = seed
    return args


def make_nano(spec, wavelengths_nm, *, solver="auto", seed=0, surface=None):
    """A :class:`~waveoptics.brdf.twoscale.Nano` from nano text or a height field; None for σ = 0.

    Parameters
    ----------
    spec : str
        ``MODEL:params`` (ignored when *surface* is given).
    wavelengths_nm : array_like, nm
        The request's wavelengths (they size a generated height field).
    solver : {'auto', 'psd', 'fft', 'direct'}
    seed : int
        Seed of a generated height field.
    surface : HeightField, str or Path, optional
        A nano height field (object or file).
    """
    from . import surfaces
    from .brdf import twoscale

    if surface is not None:
        hf = surface if isinstance(surface, surfaces.HeightField) else surfaces.load(surface)
        if solver == "psd":
            raise FieldError("{solver} 'psd' needs nano statistics (MODEL:...), not a height field", "solver")
        return twoscale.Nano(surface=hf)
    model, p = parse_nano(spec)
    if p.get("sigma", p.get("amplitude", p.get("depth", 1.0))) == 0:
        return None
    if model in surfaces.PSD_MODELS and solver in ("auto", "psd"):
        return twoscale.Nano(model=surfaces.PSDModel(model, sigma=p["sigma"], T=p.get("corr_length"), B=p.get("B"),
                                                     C=p.get("C")))
    if solver == "psd":
        raise FieldError(f"{{solver}} 'psd' has no formula for {model!r}; use fft or direct", "solver")
    scale = p.get("corr_length") or p.get("period") or (p.get("B", 0) / (2 * np.pi)) or p.get("width") or 1e-6
    size, n = nano_surface_size(wavelengths_nm, scale)
    return twoscale.Nano(surface=surfaces.generate(model, size=size, samples=n, **_generator_args(model, p, seed)))


@functools.lru_cache(maxsize=8)
def _micro_of_file(path: str, shadowing: str):
    """The tabulated micro roughness of a height-field file (read once per process and path)."""
    from . import surfaces
    from .brdf import slope_table, twoscale

    try:
        hf = surfaces.load(path)
    except WaveopticsError as exc:
        raise FieldError("{micro_surface} " + str(exc).replace("{", "{{").replace("}", "}}"),
                         "micro_surface") from None
    return twoscale.Micro.from_slopes(slope_table(hf), shadowing)


def _finite_number(value, field: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise FieldError(f"{{{field}}} {value!r} is not a number", field) from None
    if not math.isfinite(x):
        raise FieldError(f"{{{field}}} {value!r} is not finite", field)
    return x


def _alpha_y(value, ndf: str) -> float:
    """α_y checked like α (finite, in [0, :data:`~waveoptics.brdf.ndf.ALPHA_MAX`]) and refused for an NDF without an
    anisotropic form (its ``anisotropic`` flag in :data:`waveoptics.brdf.NDFS`: the stretched NDFs of Heitz 2014
    §5)."""
    from .brdf.ndf import ALPHA_MAX, NDFS

    a = _finite_number(value, "alpha_y")
    if not 0 <= a <= ALPHA_MAX:
        raise FieldError(f"{{alpha_y}} {value!r} is not allowed; α_y must be finite and in [0, {ALPHA_MAX:g}]",
                         "alpha_y")
    if ndf in NDFS and not NDFS[ndf].anisotropic:
        raise FieldError(f"{{alpha_y}} {value!r} is not allowed for {{ndf}} {ndf!r}, which is isotropic; "
                         "anisotropic NDFs: " + ", ".join(k for k, v in NDFS.items()
                                                          if v.anisotropic and k in PARAMETRIC_NDF_NAMES),
                         "alpha_y", "ndf")
    return a


@dataclass(frozen=True)
class SimulationRequest:
    """One two-scale simulation: surface, material, light and sampling, validated on construction.

    Attributes
    ----------
    material : str
        Material name, ``shelf/book/page``, ``n+kj`` or ``f0:...`` (:func:`waveoptics.materials.get_material`).
    nano : str or None
        Nano roughness ``MODEL:params`` (ignored when *surface* is given; σ = 0 means none).
    surface : str or None
        Path (or description) of a nano height field; the object itself is passed separately to the solvers.
    micro_alpha : float
        Micro NDF roughness α (≥ 0, unitless); α_x of an anisotropic NDF when *alpha_y* is given.
    alpha_y : float or None
        Micro NDF roughness α_y (≥ 0, unitless) of an anisotropic NDF (ggx, beckmann, epd, sgd: the NDF's
        ``anisotropic`` flag in :data:`waveoptics.brdf.NDFS`); None: isotropic (α_y = α). Refused with
        *micro_surface* and *split*, which measure both α from slopes.
    ndf, shadowing : str
        Micro NDF and masking-shadowing term (:data:`waveoptics.brdf.NDFS`, :data:`waveoptics.brdf.SHADOWINGS`).
    incident_deg : (float, float)
        Light direction (θ, φ) in degrees, 0 ≤ θ < 90.
    illuminant : str
        Light source (:func:`waveoptics.colour.illuminant`).
    wavelengths_nm : tuple of float or None
        Wavelengths in nm; None: chosen from the illuminant for *delta_e*.
    delta_e : float
        Colour accuracy (ΔE2000) that picks the wavelength step, in (0, 100).
    resolution : int
        Direction-grid cells per axis, in :data:`RESOLUTION_RANGE`.
    solver : str
        Nano-lobe solver, one of :data:`waveoptics.vocabulary.NANO_SOLVERS`.
    kd : float
        Diffuse albedo of a dielectric substrate, in [0, 1] (metals have none).
    precision : str
        OpenCL precision of the height-field solvers, one of :data:`PRECISIONS`.
    seed : int
        Seed of generated nano surfaces.
    split : bool
        *surface* holds both scales: split it at a cut-off period of 10 λmax.
    diffraction : str
        Diffraction model of the nano lobe, one of :data:`waveoptics.vocabulary.DIFFRACTION` (default kirchhoff).
    polarization : str
        Of the incident light, one of :data:`waveoptics.vocabulary.POLARIZATIONS` (default unpolarized).
    ndf_shape : float, optional
        Shape parameter of the micro NDF where it has one: ABC's tail exponent C, EPD's and SGD's exponent p
        (default: the NDF's own, :data:`waveoptics.brdf.NDFS`).
    micro_surface : str or None
        Path of a micro-scale height field whose slope law is the NDF (``tabulated``, Heitz 2014;
        :meth:`waveoptics.brdf.Micro.from_slopes`); *micro_alpha*, *ndf* and *ndf_shape* are then not used.
    multiple_scattering : bool
        Add Kulla & Conty's (2017) compensation for light that bounces between micro facets, to both models
        (off by default).
    roughness_correlation : str or float
        Of the interface roughness of a thin-film stack *material* under ``diffraction='rayleigh-rice'``:
        ``"correlated"`` (default: a thin evaporated film replicates its substrate's roughness, Elson 1979;
        Stover ch. 6), ``"uncorrelated"`` or a coefficient in [0, 1]
        (:func:`waveoptics.materials.roughness_correlation`; Elson, Rahn & Bennett 1983). Another value than the
        default is refused for a bare material and under the Kirchhoff-family models, which do not use it.
    """

    material: str = DEFAULT_MATERIAL
    nano: str | None = DEFAULT_NANO
    surface: str | None = None
    micro_alpha: float = 0.05
    alpha_y: float | None = None
    ndf: str = DEFAULT_NDF
    shadowing: str = "smith-correlated"
    incident_deg: tuple = (30.0, 0.0)
    illuminant: str = "D65"
    wavelengths_nm: tuple | None = None
    delta_e: float = 1.0
    resolution: int = 128
    solver: str = "auto"
    kd: float = 0.5
    precision: str = "float32"
    seed: int = 0
    split: bool = False
    diffraction: str = "kirchhoff"
    polarization: str = "unpolarized"
    ndf_shape: float | None = None
    micro_surface: str | None = None
    multiple_scattering: bool = False
    roughness_correlation: str | float = ROUGHNESS_CORRELATIONS[0]

    def __post_init__(self):
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 - frozen dataclass normalization
        if self.wavelengths_nm is not None:
            w = check_optical_range(check_wavelengths(self.wavelengths_nm, name="wavelengths_nm"),
                                    name="wavelengths_nm")
            set_("wavelengths_nm", tuple(float(x) for x in w))
        if isinstance(self.seed, (bool, np.bool_)) or not isinstance(self.seed, (int, np.integer)) \
                or not 0 <= int(self.seed) < 2**63:
            raise FieldError(f"{{seed}} {self.seed!r} is not allowed; a random seed is an integer in 0..2**63-1 "
                             "(numpy's generators take no negative seed)", "seed")
        inc = tuple(self.incident_deg) if np.ndim(self.incident_deg) else (self.incident_deg, 0.0)
        if len(inc) != 2:
            raise FieldError(f"{{incident_deg}} {self.incident_deg!r} is not (θ, φ) in degrees", "incident_deg")
        theta, phi = (_finite_number(x, "incident_deg") for x in inc)
        check_theta(theta, name="incident_deg")
        if theta >= 90:
            raise FieldError(f"{{incident_deg}} θ={theta:g}° is not allowed; the light must be above the horizon "
                             "(< 90)", "incident_deg")
        set_("incident_deg", (theta, phi))
        alpha = _finite_number(self.micro_alpha, "micro_alpha")
        if alpha < 0:
            raise FieldError(f"{{micro_alpha}} {self.micro_alpha!r} is not allowed; α must be finite and >= 0",
                             "micro_alpha")
        set_("micro_alpha", alpha)
        if self.alpha_y is not None:
            set_("alpha_y", _alpha_y(self.alpha_y, self.ndf))
        if int(self.resolution) != self.resolution or not (RESOLUTION_RANGE[0] <= self.resolution
                                                            <= RESOLUTION_RANGE[1]):
            raise FieldError(f"{{resolution}} {self.resolution!r} is not allowed; use "
                             f"{RESOLUTION_RANGE[0]}..{RESOLUTION_RANGE[1]}", "resolution")
        set_("resolution", int(self.resolution))
        kd = _finite_number(self.kd, "kd")
        if not 0 <= kd <= 1:
            raise FieldError(f"{{kd}} {self.kd!r} is not allowed; the diffuse albedo must be in [0, 1]", "kd")
        acc = _finite_number(self.delta_e, "delta_e")
        if not 0 < acc < 100:
            raise FieldError(f"{{delta_e}} {self.delta_e!r} is not allowed; use a ΔE2000 in (0, 100)",
                             "delta_e")
        for field, allowed in (("solver", NANO_SOLVERS), ("precision", PRECISIONS), ("ndf", PARAMETRIC_NDF_NAMES),
                               ("shadowing", SHADOWING_NAMES), ("diffraction", DIFFRACTION),
                               ("polarization", POLARIZATIONS)):
            if getattr(self, field) not in allowed:
                raise unknown(field, getattr(self, field), allowed, field=field)
        if self.ndf_shape is not None:
            from .brdf import twoscale

            shape = _finite_number(self.ndf_shape, "ndf_shape")
            try:
                twoscale.Micro(alpha=min(alpha, 2.0), ndf=self.ndf, ndf_shape=shape)
            except WaveopticsError as exc:
                raise FieldError("{ndf_shape} " + str(exc).split(" ", 1)[1], "ndf_shape") from None
            set_("ndf_shape", shape)
        if not isinstance(self.multiple_scattering, (bool, np.bool_)):
            raise FieldError(f"{{multiple_scattering}} {self.multiple_scattering!r} is not allowed; use true or false",
                             "multiple_scattering")
        set_("multiple_scattering", bool(self.multiple_scattering))
        if self.roughness_correlation not in ROUGHNESS_CORRELATIONS:   # a coefficient (or a typo): parse it
            from .materials.thinfilm import roughness_correlation

            set_("roughness_correlation", roughness_correlation(self.roughness_correlation))
        if self.roughness_correlation != ROUGHNESS_CORRELATIONS[0] and "|" not in str(self.material):
            # an option the model does not use is refused, not ignored (a bare material has one interface)
            raise FieldError(f"{{roughness_correlation}} {self.roughness_correlation!r} applies to a thin-film stack "
                             f"(e.g. 'Al|Al2O3:120nm'); {{material}} {self.material!r} has one interface",
                             "roughness_correlation", "material")
        if self.roughness_correlation != ROUGHNESS_CORRELATIONS[0] and self.diffraction != "rayleigh-rice":
            # refused, not ignored: only first-order perturbation scatters from every interface (Elson 1979)
            raise FieldError(f"{{roughness_correlation}} {self.roughness_correlation!r} applies under {{diffraction}} "
                             f"'rayleigh-rice' (first-order scatter from every interface of the stack); the "
                             f"{self.diffraction} lobe scatters from the top surface only and does not use it",
                             "roughness_correlation", "diffraction")
        if self.micro_surface is not None:
            if self.ndf_shape is not None:
                raise FieldError("{micro_surface} sets the NDF from the field's slopes; drop {ndf_shape}",
                                 "micro_surface", "ndf_shape")
            if self.split:
                raise FieldError("{split} measures the micro roughness from {surface}; drop {micro_surface}",
                                 "split", "micro_surface")
            set_("micro_surface", str(self.micro_surface))
        for field in ("micro_surface", "split"):   # both measure α_x and α_y from slopes
            if getattr(self, field) not in (None, False) and self.alpha_y is not None:
                raise FieldError(f"{{alpha_y}} is not used with {{{field}}}, which measures α_x and α_y from the "
                                 "height field's slopes; drop {alpha_y}", "alpha_y", field)
        if self.surface is None and self.nano is None:
            raise FieldError("a request needs nano roughness: {nano} MODEL:params or a height-field {surface}",
                             "nano", "surface")
        if self.split and self.surface is None:
            raise FieldError("{split} needs a height-field {surface} holding both scales", "split", "surface")
        if self.surface is None:
            parse_nano(self.nano)

    def validate(self) -> "SimulationRequest":
        """Resolve the names that need data (material, illuminant), so that a typo is one clear error before any
        work starts (in the client, not on a worker)."""
        from . import colour
        from .materials import get_material

        get_material(self.material)
        colour.illuminant(self.illuminant)
        return self

    def wavelengths(self) -> np.ndarray:
        """Wavelengths in nm: the given ones, or the grid the illuminant needs for *delta_e*."""
        from . import colour

        if self.wavelengths_nm is not None:
            return np.asarray(self.wavelengths_nm, dtype=float)
        return colour.simulation_wavelengths(colour.illuminant(self.illuminant), self.delta_e)

    def resolved(self) -> "SimulationRequest":
        """This request with its wavelength list fixed (chosen once, not again in every task)."""
        if self.wavelengths_nm is not None:
            return self
        return dataclasses.replace(self, wavelengths_nm=tuple(float(x) for x in self.wavelengths()))

    def micro(self):
        """The micro-scale roughness of this request (a :class:`~waveoptics.brdf.Micro`; the slope law of
        *micro_surface* when it is given)."""
        from .brdf import twoscale

        if self.micro_surface is not None:
            return _micro_of_file(self.micro_surface, self.shadowing)
        return twoscale.Micro(alpha=self.micro_alpha, alpha_y=self.alpha_y, ndf=self.ndf, shadowing=self.shadowing,
                              ndf_shape=self.ndf_shape)

    def params(self) -> dict:
        """Fields as plain data (JSON-able), with the resolved wavelength list."""
        d = dataclasses.asdict(self)
        d["wavelengths_nm"] = [float(x) for x in self.wavelengths()]
        d["incident_deg"] = list(self.incident_deg)
        if self.surface is not None:
            d["nano"] = None
        return d


def request_default(field: str):
    """The default of the :class:`SimulationRequest` field *field*: front ends (the command line's option defaults
    and help, scene files) read it here instead of restating it.

    Examples
    --------
    >>> request_default("ndf"), request_default("micro_alpha")
    ('beckmann', 0.05)
    """
    for f in dataclasses.fields(SimulationRequest):
        if f.name == field:
            return f.default
    raise unknown("request field", field, [f.name for f in dataclasses.fields(SimulationRequest)])
