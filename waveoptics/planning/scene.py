"""Scene files: what a user wants to see, as a validated TOML document.

A scene names its materials (micro roughness and an optional nano surface), its light sources with their
incident directions, the directions of interest (view directions or a camera looking at a sphere), the outputs
wanted and a colour-accuracy target. :func:`load` parses and validates it; every mistake is reported as one line
that names the key and what is allowed (``scene.toml: materials[1].roughness = -0.1 is not allowed; use a
number >= 0``). :mod:`waveoptics.planning` then decides which physical effects the scene needs.

Schema (``examples/scenes/*.toml`` are worked examples)::

    name = "gold-sphere"                 # optional, default: the file name
    description = "..."                  # optional
    seed = 0                             # optional, seeds generated nano surfaces

    [accuracy]
    delta_e = 1.0                        # CIEDE2000 colour accuracy target (> 0), default 1

    [[materials]]
    name = "gold"                        # unique
    material = "Au"                      # preset, shelf/book/page or f0:...   (or: ior = 1.5 / "0.2+3.1j")
    roughness = 0.1                      # micro NDF alpha >= 0, default 0.05 (alpha_x if roughness_y is given)
    # roughness_y = 0.3                  # alpha_y of an anisotropic NDF (ggx, beckmann, epd, sgd); default isotropic
    ndf = "ggx"                          # ggx | beckmann (default) | blinn-phong | abc | epd | sgd
    # ndf_shape = 1.5                    # abc's C, epd's or sgd's p (default: the NDF's own)
    # micro_surface = "micro.npy"        # or {path, spacing, units, channel}: the NDF is this height field's
    #                                    #   slope law (tabulated; instead of roughness, ndf and ndf_shape)
    multiple_scattering = false          # add the light lost between micro facets (Kulla & Conty 2017)
    shadowing = "smith-correlated"       # see waveoptics.brdf.SHADOWINGS
    diffuse_albedo = 0.5                 # dielectric substrate's diffuse albedo in [0, 1] (metals: none)
    diffraction = "auto"                 # nano-lobe model: auto (the planner picks) | kirchhoff | ghs | rghs | ohs | rohs
    #                                    #   | rayleigh-rice
    roughness_correlation = "correlated" # a thin-film stack's interface roughness under rayleigh-rice: correlated
    #                                    #   (default) | uncorrelated | a coefficient in [0, 1]
    [materials.nano]                     # optional nano surface, exactly one of:
    statistics = "abc:sigma=2nm,B=2um,C=2.6"      #   height statistics (gaussian | exponential | abc)
    # generator = {model = "sinusoid", amplitude = "40nm", period = "1.6um", size = "24um", samples = 256}
    # file = "surface.npz"   (or {path = "...", spacing = "50nm", units = "nm", channel = 0}), relative to the
    #                         scene file; instrument formats (.x3p .sur .datx .sdf .gwy ...) read by SurfaceTopography

    [[lights]]
    name = "sun"
    spd = "D65"                          # D65, A, F2, blackbody:3000K, laser:532, rgb-laser, lamp.csv
    directions_deg = [[30, 0]]           # incident (theta, phi) in degrees, theta < 90

    [view]
    directions_deg = [[0, 0]]            # view directions of interest (theta, phi), degrees
    camera = "sphere"                    # optional: a camera looking at a sphere (every direction is seen)

    [output]
    spectral_brdf = false                # spectral OpenEXR of the BRDF over the hemisphere
    rgb_images = true                    # RGB OpenEXR + PNG of the BRDF (and the sphere with camera = "sphere")
    tables = false                       # CSV of the BRDF at the view directions and the albedo, per wavelength
    resolution = 64                      # optional: direction grid N x N (default: chosen by the planner)
    sphere_size = 256                    # sphere render size in pixels

References
----------
.. [1] TOML v1.0.0, https://toml.io/en/v1.0.0 (read with the standard library's ``tomllib``).
"""
from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field
from pathlib import Path

from .. import brdf, surfaces
from ..colour.illuminants import illuminant
from ..vocabulary import DIFFRACTION, PARAMETRIC_NDF_NAMES
from ..errors import WaveopticsError, did_you_mean
from ..materials.database import get_material
from ..request import NO_NANO, SimulationRequest, parse_nano, request_default
from ..units import parse_angle, parse_length

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib


__all__ = ['KEYS', 'CAMERAS', 'DEFAULT_DELTA_E', 'DEFAULT_LIGHT_DIRECTIONS', 'NanoSpec', 'MaterialSpec', 'LightSpec', 'ViewSpec', 'OutputSpec', 'Scene', 'parse', 'load', 'request_of']

#: allowed keys per table (the schema); values are checked by the parsers below
KEYS = {
    "": ("name", "description", "seed", "accuracy", "materials", "lights", "view", "output"),
    "accuracy": ("delta_e",),
    "materials": ("name", "material", "ior", "roughness", "roughness_y", "ndf", "ndf_shape", "shadowing",
                  "diffuse_albedo", "nano", "diffraction", "micro_surface", "multiple_scattering",
                  "roughness_correlation"),
    "nano": ("statistics", "generator", "file"), "file": ("path", "spacing", "units", "channel"),
    "lights": ("name", "spd", "directions_deg"), "view": ("directions_deg", "camera"),
    "output": ("spectral_brdf", "rgb_images", "tables", "resolution", "sphere_size"),
}
CAMERAS = ("sphere",)
#: defaults of scene keys that are request fields: the :class:`~waveoptics.request.SimulationRequest` field's
DEFAULT_DELTA_E = request_default("delta_e")
DEFAULT_LIGHT_DIRECTIONS = ((30.0, 0.0),)


@dataclass(frozen=True)
class NanoSpec:
    """A nano surface: ``kind`` is "statistics" (``text`` = MODEL:params), "generator" (``params`` for
    :func:`waveoptics.surfaces.generate`, model included) or "file" (``path`` and load options)."""

    kind: str
    text: str | None = None
    params: dict = field(default_factory=dict)
    path: Path | None = None

    def height_field(self, seed: int = 0):
        """The height field of a ``file`` or ``generator`` nano surface (generators get *seed* when they take one)."""
        if self.kind == "file":
            return surfaces.load(self.path, **self.params)
        if self.kind != "generator":
            raise WaveopticsError(f"nano {self.describe()} is statistics, not a height field")
        params = dict(self.params)
        model = params.pop("model")
        if "seed" in inspect.signature(surfaces.GENERATORS[model]).parameters:
            params.setdefault("seed", seed)
        return surfaces.generate(model, **params)

    def describe(self) -> str:
        if self.kind == "statistics":
            return f"statistics {self.text}"
        if self.kind == "generator":
            return "generator " + ", ".join(f"{k}={v}" for k, v in self.params.items())
        return f"file {self.path}"


@dataclass(frozen=True)
class MaterialSpec:
    """One material of the scene (see the module schema)."""

    name: str
    material: str
    roughness: float = request_default("micro_alpha")
    roughness_y: float | None = request_default("alpha_y")   # α_y of an anisotropic NDF; None: isotropic
    ndf: str = request_default("ndf")
    shadowing: str = request_default("shadowing")
    diffuse_albedo: float = request_default("kd")
    nano: NanoSpec | None = None
    ndf_shape: float | None = None   # the NDF's shape parameter (ABC's C, EPD's/SGD's p); None: its default
    diffraction: str = "auto"        # a model of waveoptics.vocabulary.DIFFRACTION, or auto (the planner picks)
    micro_surface: NanoSpec | None = None   # a height-field file whose slope law is the NDF (kind "file")
    multiple_scattering: bool = request_default("multiple_scattering")   # add the Kulla-Conty compensation lobe
    roughness_correlation: str | float = request_default("roughness_correlation")   # of a stack's interfaces

    def micro(self):
        """The micro roughness (:class:`waveoptics.brdf.Micro`): the slope law of *micro_surface* when given, else
        the parametric NDF."""
        if self.micro_surface is not None:
            return brdf.Micro.from_slopes(brdf.slope_table(self.micro_surface.height_field()), self.shadowing)
        return brdf.Micro(self.roughness, self.roughness_y, self.ndf, self.shadowing, self.ndf_shape)


@dataclass(frozen=True)
class LightSpec:
    """A light source: SPD specification and incident directions (θ, φ) in degrees."""

    name: str
    spd: str
    directions_deg: tuple = DEFAULT_LIGHT_DIRECTIONS


@dataclass(frozen=True)
class ViewSpec:
    """Directions of interest: explicit view directions (θ, φ) in degrees and/or a sphere camera."""

    directions_deg: tuple = ()
    camera: str | None = None


@dataclass(frozen=True)
class OutputSpec:
    """Outputs wanted (see the module schema)."""

    spectral_brdf: bool = False
    rgb_images: bool = True
    tables: bool = False
    resolution: int | None = None
    sphere_size: int = 256


@dataclass(frozen=True)
class Scene:
    """A validated scene."""

    name: str
    materials: tuple
    lights: tuple
    view: ViewSpec = ViewSpec()
    output: OutputSpec = OutputSpec()
    delta_e: float = DEFAULT_DELTA_E
    description: str = ""
    seed: int = request_default("seed")
    path: Path | None = None

    def material(self, name: str) -> MaterialSpec:
        for m in self.materials:
            if m.name == name:
                return m
        raise WaveopticsError(f"scene {self.name!r} has no material {name!r}; it has "
                              f"{', '.join(m.name for m in self.materials)}")


# ----------------------------------------------------------------------------------------------------------------
# Validation helpers: each raises one line naming the key
# ----------------------------------------------------------------------------------------------------------------

class _Ctx:
    """Prefix for error messages: the file and the key path."""

    def __init__(self, where: str):
        self.where = where

    def err(self, key: str, msg: str) -> WaveopticsError:
        return WaveopticsError(f"{self.where}: {key} {msg}")


def _check_keys(ctx: _Ctx, table: dict, kind: str, key: str) -> None:
    allowed = KEYS[kind]
    for k in table:
        if k not in allowed:
            where = f"{key}.{k}" if key else k
            raise ctx.err(where, f"is not a known key{did_you_mean(k, allowed)}; allowed: {', '.join(allowed)}")


def _table(ctx, value, key) -> dict:
    if not isinstance(value, dict):
        raise ctx.err(key, f"= {value!r} is not allowed; it must be a table ([{key}] or {{...}})")
    return value


def _string(ctx, value, key) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ctx.err(key, f"= {value!r} is not allowed; it must be a non-empty string")
    return value.strip()


def _number(ctx, value, key, *, lo=None, hi=None, lo_open=False) -> float:
    rng = (f"> {lo:g}" if lo_open else f">= {lo:g}") if lo is not None else ""
    if hi is not None:
        rng = f"in [{lo:g}, {hi:g}]" if lo is not None else f"<= {hi:g}"
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ctx.err(key, f"= {value!r} is not allowed; use a number {rng}".rstrip())
    v = float(value)
    if lo is not None and (v < lo or (lo_open and v == lo)) or hi is not None and v > hi:
        raise ctx.err(key, f"= {value!r} is not allowed; use a number {rng}")
    return v


def _bool(ctx, value, key) -> bool:
    if not isinstance(value, bool):
        raise ctx.err(key, f"= {value!r} is not allowed; use true or false")
    return value


def _int(ctx, value, key, lo, hi) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise ctx.err(key, f"= {value!r} is not allowed; use an integer in {lo}..{hi}")
    return int(value)


def _choice(ctx, value, key, choices) -> str:
    if value not in choices:
        raise ctx.err(key, f"= {value!r} is not allowed{did_you_mean(value, choices)}; allowed: "
                           f"{', '.join(choices)}")
    return value


def _angle(ctx, value, key, *, lo=None) -> float:
    """An angle in degrees: a TOML number, or a string with the unit (``"30deg"``, ``"30°"``; as on the command
    line, :func:`waveoptics.units.parse_angle`)."""
    if isinstance(value, str):
        try:
            value = parse_angle(value, name="angle")
        except WaveopticsError:
            raise ctx.err(key, f"= {value!r} is not allowed; use a number of degrees (30, or \"30deg\")") from None
    return _number(ctx, value, key, lo=lo)


def _is_angle(v) -> bool:
    return isinstance(v, (int, float, str)) and not isinstance(v, bool)


def _directions(ctx, value, key, *, theta_max: float) -> tuple:
    """[[θ, φ], ...], [θ, φ] or θ (degrees, numbers or strings with deg/°) -> tuple of (θ, φ) with
    0 <= θ < theta_max (or <=)."""
    if _is_angle(value):
        value = [[value, 0.0]]
    if isinstance(value, list) and len(value) == 2 and all(_is_angle(v) for v in value):
        value = [value]
    if not isinstance(value, list) or not value:
        raise ctx.err(key, f"= {value!r} is not allowed; write [[theta, phi], ...] in degrees")
    out = []
    for i, d in enumerate(value):
        k = f"{key}[{i}]"
        if not (isinstance(d, list) and len(d) in (1, 2)):
            raise ctx.err(k, f"= {d!r} is not allowed; write [theta, phi] in degrees")
        th = _angle(ctx, d[0], k + " theta", lo=0.0)
        ph = _angle(ctx, d[1], k + " phi") if len(d) == 2 else 0.0
        if th >= theta_max:
            raise ctx.err(k, f"theta = {th:g} deg is not allowed; use 0 <= theta < {theta_max:g}")
        out.append((th, ph))
    return tuple(out)


# ----------------------------------------------------------------------------------------------------------------
# Sections
# ----------------------------------------------------------------------------------------------------------------

def _nano(ctx, value, key, base: Path) -> NanoSpec:

    t = _table(ctx, value, key)
    _check_keys(ctx, t, "nano", key)
    given = [k for k in KEYS["nano"] if k in t]
    if len(given) != 1:
        raise ctx.err(key, f"has {', '.join(given) or 'none'} of statistics, generator, file; give exactly one")
    kind = given[0]
    k = f"{key}.{kind}"
    v = t[kind]
    if kind == "statistics":
        if isinstance(v, dict):
            if "model" not in v:
                raise ctx.err(k, "lacks model; allowed: " + ", ".join(surfaces.PSD_MODELS))
            v = f"{v['model']}:" + ",".join(f"{p}={q}" for p, q in v.items() if p != "model")
        text = _string(ctx, v, k)
        try:
            model, _ = parse_nano(text)
        except WaveopticsError as exc:
            raise ctx.err(k, f"= {text!r}: {exc}") from None
        if model not in surfaces.PSD_MODELS:
            raise ctx.err(k, f"model {model!r} is not a statistics model; allowed: {', '.join(surfaces.PSD_MODELS)} "
                             f"(use generator for {model})")
        return NanoSpec("statistics", text=text)
    if kind == "generator":
        g = dict(_table(ctx, v, k))
        model = _choice(ctx, g.pop("model", None), k + ".model", tuple(surfaces.GENERATORS))
        sig = inspect.signature(surfaces.GENERATORS[model])
        for p in g:
            if p not in sig.parameters:
                raise ctx.err(f"{k}.{p}", f"is not a parameter of generator {model!r}{did_you_mean(p, sig.parameters)}"
                                          f"; allowed: {', '.join(sig.parameters)}")
        for p in ("size", "samples"):
            if p not in g:
                raise ctx.err(k, f"lacks {p} (the patch size with a unit, e.g. \"24um\", and samples per side; "
                                 "spacing <= lambda/4 covers the whole hemisphere)")
        missing = [p for p, s in sig.parameters.items() if s.default is inspect.Parameter.empty and p not in g]
        if missing:
            raise ctx.err(k, f"lacks {missing[0]} (generator {model!r} needs {', '.join(missing)})")
        return NanoSpec("generator", params={"model": model, **g})
    p, opts = _file(ctx, v, k, base)
    return NanoSpec("file", path=p, params=opts)


def _file(ctx, v, k, base: Path) -> tuple:
    """(path, load options) of a height-field file given as a path or a {path, spacing, units, channel} table."""
    f = {"path": v} if isinstance(v, str) else dict(_table(ctx, v, k))
    _check_keys(ctx, f, "file", k)
    p = Path(_string(ctx, f.get("path"), k + ".path")).expanduser()
    if not p.is_absolute():
        p = base / p
    if not p.is_file():
        raise ctx.err(k, f"= {str(p)!r} does not exist (paths are relative to the scene file)")
    opts = {q: f[q] for q in ("spacing", "units", "channel") if q in f}
    if "spacing" in opts:   # the command line's rule: a length always carries its unit (5 would mean 5 m)
        values = opts["spacing"] if isinstance(opts["spacing"], list) else [opts["spacing"]]
        for v in values:
            if not isinstance(v, str):
                raise ctx.err(k + ".spacing", f"= {v!r} needs a unit, e.g. \"50nm\" (as --spacing on the command "
                                              "line)")
            try:
                parse_length(v, name="spacing")
            except ValueError as exc:
                raise ctx.err(k + ".spacing", f"= {v!r}: {str(exc).split(': ', 1)[-1]}") from None
    return p, opts


def _material(ctx, t, key, base) -> MaterialSpec:

    _check_keys(ctx, t, "materials", key)
    name = _string(ctx, t.get("name"), key + ".name")
    if ("material" in t) == ("ior" in t):
        raise ctx.err(key, "needs exactly one of material (a name like \"Au\", shelf/book/page, f0:...) and "
                           "ior (a number like 1.5 or \"0.2+3.1j\")")
    if "material" in t:
        spec = _string(ctx, t["material"], key + ".material")
    else:
        ior = t["ior"]
        if isinstance(ior, bool) or not isinstance(ior, (int, float, str)):
            raise ctx.err(key + ".ior", f"= {ior!r} is not allowed; write a number like 1.5 or \"0.2+3.1j\"")
        spec = str(ior).strip()
    try:
        get_material(spec)
    except WaveopticsError as exc:
        raise ctx.err(key + (".material" if "material" in t else ".ior"), f"= {spec!r}: {exc}") from None
    micro_surface = None
    if "micro_surface" in t:   # the NDF is the field's slope law: no parametric NDF keys beside it
        clash = [q for q in ("roughness", "roughness_y", "ndf", "ndf_shape") if q in t]
        if clash:
            raise ctx.err(key + ".micro_surface", f"sets the NDF from the field's slopes; drop {', '.join(clash)}")
        path, opts = _file(ctx, t["micro_surface"], key + ".micro_surface", base)
        micro_surface = NanoSpec("file", path=path, params=opts)
    return MaterialSpec(
        name=name, material=spec, micro_surface=micro_surface,
        multiple_scattering=_bool(ctx, t.get("multiple_scattering", request_default("multiple_scattering")), key + ".multiple_scattering"),
        roughness=_number(ctx, t.get("roughness", request_default("micro_alpha")), key + ".roughness", lo=0.0, hi=2.0),
        ndf=_choice(ctx, t.get("ndf", request_default("ndf")), key + ".ndf", PARAMETRIC_NDF_NAMES),
        ndf_shape=_ndf_shape(ctx, t, key), roughness_y=_roughness_y(ctx, t, key),
        shadowing=_choice(ctx, t.get("shadowing", request_default("shadowing")), key + ".shadowing",
                          tuple(brdf.SHADOWINGS)),
        diffuse_albedo=_number(ctx, t.get("diffuse_albedo", request_default("kd")), key + ".diffuse_albedo", lo=0.0, hi=1.0),
        nano=_nano(ctx, t["nano"], key + ".nano", base) if "nano" in t else None,
        diffraction=_choice(ctx, t.get("diffraction", "auto"), key + ".diffraction", ("auto",) + DIFFRACTION),
        roughness_correlation=_correlation(ctx, t, key, spec))


def _correlation(ctx, t, key, material: str):
    """The roughness correlation of a stack's interfaces (:func:`waveoptics.materials.roughness_correlation`): a
    value other than the default is refused where no model can use it, a material with one interface or a named
    diffraction model other than rayleigh-rice (with ``diffraction = "auto"`` the planner says whether it is used)."""
    from ..materials.thinfilm import roughness_correlation

    value = t.get("roughness_correlation", request_default("roughness_correlation"))
    try:
        c = roughness_correlation(value)
    except WaveopticsError:
        raise ctx.err(key + ".roughness_correlation", f"= {value!r} is not allowed; use correlated, uncorrelated "
                      "or a number in [0, 1]") from None
    model = t.get("diffraction", "auto")
    if c != request_default("roughness_correlation"):
        if "|" not in str(material):
            raise ctx.err(key + ".roughness_correlation", f"= {value!r} applies to a thin-film stack (e.g. "
                          f"'Al|Al2O3:120nm'); material {material!r} has one interface")
        if model not in ("auto", "rayleigh-rice"):
            raise ctx.err(key + ".roughness_correlation", f"= {value!r} applies under diffraction = "
                          f"'rayleigh-rice' (first-order scatter from every interface); the {model} lobe scatters "
                          "from the top surface only and does not use it")
    return c


def _roughness_y(ctx, t, key):
    """materials.roughness_y: α_y in [0, 2], only for an NDF with an anisotropic form (Heitz 2014 §5)."""
    ndf = t.get("ndf", request_default("ndf"))
    if "roughness_y" in t and not getattr(brdf.NDFS.get(ndf), "anisotropic", False):
        raise ctx.err(key + ".roughness_y", f"needs an anisotropic NDF (ggx, beckmann, epd, sgd), not {ndf!r}")
    return _number(ctx, t["roughness_y"], key + ".roughness_y", lo=0.0, hi=2.0) if "roughness_y" in t else None


def _ndf_shape(ctx, t, key):
    """materials.ndf_shape: a number in the NDF's range, only for an NDF that has a shape parameter."""
    if "ndf_shape" not in t:
        return None
    spec = brdf.NDFS.get(t.get("ndf", request_default("ndf")))
    if spec is None or spec.shape is None:
        raise ctx.err(key + ".ndf_shape", f"applies to NDFs with a shape parameter "
                                          f"({', '.join(k for k, v in brdf.NDFS.items() if v.shape)}), not "
                                          f"{t.get('ndf', request_default('ndf'))!r}")
    lo, hi = brdf.ndf.SHAPE_RANGE[spec.name]
    return _number(ctx, t["ndf_shape"], key + ".ndf_shape", lo=lo, hi=None if math.isinf(hi) else hi, lo_open=True)


def _light(ctx, t, key) -> LightSpec:
    _check_keys(ctx, t, "lights", key)
    name = _string(ctx, t.get("name"), key + ".name")
    spd = _string(ctx, t.get("spd", "D65"), key + ".spd")
    try:
        illuminant(spd)
    except WaveopticsError as exc:
        raise ctx.err(key + ".spd", f"= {spd!r}: {exc}") from None
    dirs = _directions(ctx, t.get("directions_deg", [list(d) for d in DEFAULT_LIGHT_DIRECTIONS]),
                       key + ".directions_deg", theta_max=90.0)
    return LightSpec(name=name, spd=spd, directions_deg=dirs)


def _array_of_tables(ctx, value, key) -> list:
    if not isinstance(value, list) or not value or not all(isinstance(x, dict) for x in value):
        raise ctx.err(key, f"is missing or empty; write at least one [[{key}]] table")
    return value


def _unique(ctx, items, key) -> None:
    seen = set()
    for i, it in enumerate(items):
        if it.name in seen:
            raise ctx.err(f"{key}[{i}].name", f"= {it.name!r} is used twice; names must be unique")
        seen.add(it.name)


def parse(data: dict, *, where: str = "scene", base: Path | None = None, name: str = "scene") -> Scene:
    """Validate a scene given as a dict (the parsed TOML); *where* prefixes error messages.

    Raises
    ------
    WaveopticsError
        One line naming the key and what is allowed.
    """
    ctx = _Ctx(where)
    base = Path(".") if base is None else Path(base)
    _check_keys(ctx, data, "", "")
    acc = _table(ctx, data.get("accuracy", {}), "accuracy")
    _check_keys(ctx, acc, "accuracy", "accuracy")
    delta_e = _number(ctx, acc.get("delta_e", DEFAULT_DELTA_E), "accuracy.delta_e", lo=0.0, lo_open=True)
    if delta_e >= 100:
        raise ctx.err("accuracy.delta_e", f"= {delta_e:g} is not allowed; use a CIEDE2000 target in (0, 100)")
    mats = tuple(_material(ctx, t, f"materials[{i}]", base)
                 for i, t in enumerate(_array_of_tables(ctx, data.get("materials"), "materials")))
    _unique(ctx, mats, "materials")
    lights = tuple(_light(ctx, t, f"lights[{i}]")
                   for i, t in enumerate(_array_of_tables(ctx, data.get("lights"), "lights")))
    _unique(ctx, lights, "lights")
    v = _table(ctx, data.get("view", {}), "view")
    _check_keys(ctx, v, "view", "view")
    view = ViewSpec(
        directions_deg=_directions(ctx, v["directions_deg"], "view.directions_deg", theta_max=90.0)
        if "directions_deg" in v else (),
        camera=_choice(ctx, v["camera"], "view.camera", CAMERAS) if "camera" in v else None)
    o = _table(ctx, data.get("output", {}), "output")
    _check_keys(ctx, o, "output", "output")
    output = OutputSpec(
        spectral_brdf=_bool(ctx, o.get("spectral_brdf", False), "output.spectral_brdf"),
        rgb_images=_bool(ctx, o.get("rgb_images", True), "output.rgb_images"),
        tables=_bool(ctx, o.get("tables", False), "output.tables"),
        resolution=_int(ctx, o["resolution"], "output.resolution", 8, 2048) if "resolution" in o else None,
        sphere_size=_int(ctx, o.get("sphere_size", 256), "output.sphere_size", 16, 4096))
    if not (output.spectral_brdf or output.rgb_images or output.tables):
        raise ctx.err("output", "asks for nothing; set at least one of spectral_brdf, rgb_images, tables to true")
    if output.tables and not view.directions_deg:
        raise ctx.err("output.tables", "needs view.directions_deg (the directions to tabulate)")
    return Scene(name=_string(ctx, data.get("name", name), "name"), materials=mats, lights=lights, view=view,
                 output=output, delta_e=delta_e,
                 description=str(data.get("description", "")),
                 seed=_int(ctx, data.get("seed", request_default("seed")), "seed", 0, 2**63 - 1))


def load(path) -> Scene:
    """Read and validate a scene TOML file (see the module schema)."""
    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"scene file {str(p)!r} does not exist")
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8-sig"))   # a byte-order mark (Windows editors) is no key
    except tomllib.TOMLDecodeError as exc:
        raise WaveopticsError(f"{p}: not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise WaveopticsError(f"{p}: not a UTF-8 text file") from None
    sc = parse(data, where=str(p), base=p.parent, name=p.stem)
    return Scene(**{**sc.__dict__, "path": p})


def request_of(sc: Scene, material: str | None = None, light: str | None = None, **overrides) -> SimulationRequest:
    """The :class:`~waveoptics.request.SimulationRequest` of one (material, light) pair of a scene: the request
    that the planner, tables and sweeps start from (scene keys left out keep the fields' defaults).

    Parameters
    ----------
    sc : Scene
        A validated scene.
    material, light : str, optional
        Names of the scene material and light; default the first of each. The light gives the illuminant and
        the incident direction (its first one); the scene's ``accuracy.delta_e``, ``output.resolution`` and
        ``seed`` are used too.
    **overrides
        Request fields that replace the scene's values (e.g. ``resolution=32``); None values are ignored.

    Returns
    -------
    SimulationRequest
        A nano ``file`` or ``generator`` is named by *surface* (a path or a description): its height field is
        read or generated by the caller; statistics stay text (*nano*). A *micro_surface* is its path.
    """
    mat = sc.material(material) if material is not None else sc.materials[0]
    if light is None:
        li = sc.lights[0]
    else:
        found = [x for x in sc.lights if x.name == light]
        if not found:
            raise WaveopticsError(f"scene {sc.name!r} has no light {light!r}; it has "
                                  f"{', '.join(x.name for x in sc.lights)}")
        li = found[0]
    kw = dict(material=mat.material, micro_alpha=mat.roughness, alpha_y=mat.roughness_y, ndf=mat.ndf,
              ndf_shape=mat.ndf_shape, shadowing=mat.shadowing, kd=mat.diffuse_albedo, illuminant=li.spd,
              incident_deg=tuple(li.directions_deg[0]), delta_e=sc.delta_e, seed=sc.seed, nano=NO_NANO,
              surface=None, multiple_scattering=mat.multiple_scattering,
              roughness_correlation=mat.roughness_correlation)
    if mat.diffraction != "auto":
        kw["diffraction"] = mat.diffraction
    if mat.micro_surface is not None:   # the NDF is the field's slope law: the parametric keys keep their defaults
        kw.update(micro_surface=str(mat.micro_surface.path), micro_alpha=request_default("micro_alpha"),
                  ndf=request_default("ndf"), ndf_shape=None)
    if sc.output.resolution is not None:
        kw["resolution"] = sc.output.resolution
    if mat.nano is not None and mat.nano.kind == "statistics":
        kw["nano"] = mat.nano.text
    elif mat.nano is not None and mat.nano.kind == "file":
        kw.update(nano=None, surface=str(mat.nano.path))
    elif mat.nano is not None:
        kw.update(nano=None, surface=f"{sc.path or sc.name}: material {mat.name!r} nano {mat.nano.describe()}")
    kw.update({k: v for k, v in overrides.items() if v is not None})
    return SimulationRequest(**kw)
