"""``scatter``'s request and job: the Kirchhoff lobes of a height field, per wavelength, written as files.

:class:`ScatterRequest` holds every choice of a scatter run (the height field with its file metadata, the
material, the light, the wavelengths and the solver's settings). Its fields own the defaults that the
``waveoptics scatter`` command shows, and it validates itself on construction with errors that name the field
(:class:`~waveoptics.errors.FieldError`; only the command line writes them as its flags). :func:`scatter_job` runs
it: the checks that need the data (material, tiles, memory), the solver (:func:`waveoptics.scatter.scatter`, or
:func:`waveoptics.scatter.footprint_scatter` for a footprint of a large field) and the files
(:func:`waveoptics.scatter.write_scatter`: ``lobes.exr``, ``summary.json``, ``lobes.png``).

This module imports nothing numerical at its top: the command line reads the defaults while it builds its parser.

Examples
--------
>>> from waveoptics.scatter_job import ScatterRequest
>>> r = ScatterRequest(surface="g.npz", material="Au", incident_deg=(30, 0), wavelengths_nm="450:650:100")
>>> r.wavelengths_nm, r.incident_deg, r.order
((450.0, 550.0, 650.0), (30.0, 0.0), 'auto')
>>> ScatterRequest(surface="g.npz", material="Au", incident_deg=30, coherence="1um")
Traceback (most recent call last):
...
waveoptics.errors.FieldError: coherence is the coherence area inside a footprint; give one
"""
from __future__ import annotations

import numbers
import os
import warnings
from dataclasses import dataclass, fields

from .errors import FieldError, unknown
from .units import check_optical_range, check_wavelengths, parse_direction, parse_length, parse_wavelengths
from .vocabulary import DETRENDS, DIFFRACTION, FIELD_BACKENDS, FIELD_SOLVERS, POLARIZATIONS, PRECISIONS

__all__ = ["ScatterRequest", "ScatterRun", "scatter_default", "scatter_job", "load_height_field"]

#: the fields of a request that describe the *surface* file (they have no meaning for a height-field object)
FILE_METADATA = ("spacing", "units", "channel")


@dataclass(frozen=True)
class ScatterRequest:
    """One ``scatter`` run: the Kirchhoff BRDF of a height-field patch over the projected hemisphere, per
    wavelength, with its albedo and coherent (specular) and scattered fractions (:func:`scatter_job`).

    Parameters
    ----------
    surface : str, Path or HeightField
        The height field (heights and spacing in m) or its file (:func:`waveoptics.surfaces.load`; a ``.npy`` file
        with a *footprint* is memory-mapped and only the footprint's patch is read).
    material : str
        Material name, constant index ``n+kj``, ``f0:VALUE``, a thin-film stack, or ``one`` for F = 1
        (:func:`waveoptics.materials.fresnel_function`).
    incident_deg : (float, float), float or str
        Direction to the light, (θ, φ) in degrees (θ alone: φ = 0; text ``"THETA[,PHI]"``); stored as (θ, φ).
    spacing : str, optional
        Grid spacing of the *surface* file with unit (``50nm`` or ``50nm,80nm``), where it does not state it.
    units : str, optional
        Unit of the heights of a *surface* file that does not state it (m, mm, um, nm, pm or A).
    channel : int or str, optional
        Data channel of an instrument file, by index or name (default its height channel).
    wavelengths_nm : str or sequence of float, nm
        ``"400:700:10"`` (start:stop:step), ``"450,550,650"`` (units may follow: ``0.55um``) or numbers in nm;
        stored as a tuple of float.
    diffraction : str
        Diffraction model (:data:`waveoptics.vocabulary.DIFFRACTION`; rayleigh-rice is a two-scale lobe only).
    polarization : str
        Of the incident light (:data:`waveoptics.vocabulary.POLARIZATIONS`); each facet reflects its own s/p split.
    solver : str
        ``fft`` (chirp-z transforms with a banded Taylor series in v_z) or ``direct`` (the Kirchhoff sum).
    resolution : int
        Cells per side of the direction-cosine grid over the projected hemisphere.
    max_memory : int or str, optional
        Memory budget in bytes or text (``4GB``); None: half the machine's memory (or $WAVEOPTICS_MAX_MEMORY).
    realizations : int
        Tiles of the patch averaged as realizations (1: the whole patch).
    order : 'auto' or int
        fft solver: 'auto' (exact to 1e-8) or a fixed Taylor order about the specular v_z (0 freezes v_z).
    window : str
        Taper over the patch: a scipy.signal.windows name (boxcar = none) or ``gaussian:SIGMA`` (a length).
    footprint : str, optional
        ``X,Y,SIGMA[,SIGMA_Y,ANGLE]`` (lengths with units): the BRDF of that Gaussian footprint only (its Gaussian
        is the window; :class:`waveoptics.surfaces.Footprint`).
    coherence : str or float, optional
        Width of the light's coherence area inside the *footprint*, a length with unit (or metres); None: the
        whole footprint is coherent.
    detrend : str
        What is removed from each patch's heights first, weighted by the window
        (:data:`waveoptics.vocabulary.DETRENDS`).
    precision : str
        OpenCL precision of the direct solver (:data:`waveoptics.vocabulary.PRECISIONS`).
    backend : str
        Where the direct sum runs: ``opencl`` or its float64 NumPy twin ``numpy``.
    device : str, optional
        OpenCL device of the direct solver (:func:`waveoptics.runtime.get_runtime`; None: the default).

    References
    ----------
    .. [1] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon
       1963, ch. 3 (the Kirchhoff tangent-plane integral the solvers evaluate; docs/physics.md §1).
    """

    surface: object
    material: str
    incident_deg: tuple
    spacing: str | None = None
    units: str | None = None
    channel: object = None
    wavelengths_nm: object = "400:700:10"
    diffraction: str = "kirchhoff"
    polarization: str = "unpolarized"
    solver: str = "fft"
    resolution: int = 256
    max_memory: object = None
    realizations: int = 1
    order: object = "auto"
    window: str = "hann"
    footprint: str | None = None
    coherence: object = None
    detrend: str = "mean"
    precision: str = "float32"
    backend: str = "opencl"
    device: str | None = None

    def __post_init__(self):
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 - frozen dataclass normalization
        w = self.wavelengths_nm
        if isinstance(w, str):
            w = parse_wavelengths(w, name="wavelengths_nm")
        else:
            w = check_optical_range(check_wavelengths(w, name="wavelengths_nm"), name="wavelengths_nm")
        set_("wavelengths_nm", tuple(float(x) for x in w))
        inc = self.incident_deg
        if not isinstance(inc, str):
            inc = ",".join(repr(float(x)) if _is_number(x) else str(x) for x in
                           (inc if isinstance(inc, (tuple, list)) else (inc,)))
        set_("incident_deg", tuple(parse_direction(inc, name="incident_deg")))
        set_("order", _order(self.order))
        self._check_footprint()
        for field, allowed in (("solver", FIELD_SOLVERS), ("backend", FIELD_BACKENDS), ("precision", PRECISIONS),
                               ("detrend", DETRENDS), ("diffraction", DIFFRACTION),
                               ("polarization", POLARIZATIONS)):
            if getattr(self, field) not in allowed:
                raise unknown(field, getattr(self, field), allowed, field=field)
        if self.surface is None:
            raise FieldError("a scatter request needs a height field: {surface} (a file or a HeightField)",
                             "surface")
        if self.material is None:
            raise FieldError("a scatter request needs a {material} ('one' for F = 1)", "material")
        if not isinstance(self.surface, (str, os.PathLike)):
            given = [f for f in FILE_METADATA if getattr(self, f) is not None]
            if given:
                raise FieldError("{" + given[0] + "} describes a {surface} file, not a height field", given[0],
                                 "surface")

    def _check_footprint(self) -> None:
        """A coherence area lies inside a footprint, which is one patch whose Gaussian is the window."""
        if self.footprint is None:
            if self.coherence is not None:
                raise FieldError("{coherence} is the coherence area inside a {footprint}; give one", "coherence",
                                 "footprint")
            return
        if self.realizations != scatter_default("realizations"):
            raise FieldError("{footprint} is one patch; drop {realizations}", "realizations", "footprint")
        if self.window != scatter_default("window"):
            raise FieldError("{footprint} sets the window (its Gaussian); drop {window}", "window", "footprint")
        _ = self.coherence_m   # a bad length is refused here, before any work

    @property
    def coherence_m(self) -> float | None:
        """The coherence width in m (None: the whole footprint is coherent)."""
        if self.coherence is None:
            return None
        return parse_length(self.coherence, name="coherence", default_unit="m" if _is_number(self.coherence) else None)

    @property
    def surface_name(self) -> str:
        """How the outputs name the surface: its path, or ``height field`` for an object."""
        return str(self.surface) if isinstance(self.surface, (str, os.PathLike)) else "height field"


def _is_number(x) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _order(value):
    """'auto' or an integer Taylor order, from an integer or its text (its range is the fft solver's to check)."""
    if isinstance(value, str) and value == "auto":
        return "auto"
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return int(value)
    try:
        if isinstance(value, str):
            return int(value)
    except ValueError:
        pass
    raise FieldError("{order} " + f"{value!r} is not allowed; use 'auto' or an integer >= 0", "order")


def scatter_default(name: str):
    """The default of the :class:`ScatterRequest` field *name* (where a front end shows or compares it).

    Examples
    --------
    >>> scatter_default("resolution"), scatter_default("wavelengths_nm")
    (256, '400:700:10')
    """
    for f in fields(ScatterRequest):
        if f.name == name:
            return f.default
    raise unknown("scatter request field", name, [f.name for f in fields(ScatterRequest)])


@dataclass
class ScatterRun:
    """What :func:`scatter_job` made: the :class:`~waveoptics.scatter.ScatterResult`, the files it wrote
    ({name: path}), the header written into them, the surface's description and the warnings of the run."""

    result: object
    paths: dict
    header: dict
    surface_info: dict
    warnings: list

    def summary(self) -> dict:
        """The run as plain data: ``summary.json``'s content plus the paths of the outputs."""
        return {**self.result.summary(), **self.header, "surface_info": self.surface_info,
                "outputs": {k: str(v) for k, v in self.paths.items()}}


def load_height_field(request: ScatterRequest):
    """(footprint or None, surface) of *request*: with a footprint a ``.npy`` file is memory-mapped
    (:func:`waveoptics.surfaces.open_large`), otherwise the file is read whole (:func:`waveoptics.surfaces.load`)."""
    from . import surfaces

    fp = None if request.footprint is None else surfaces.Footprint.parse(request.footprint)
    src = request.surface
    if not isinstance(src, (str, os.PathLike)):
        return fp, src
    if fp is not None and str(src).lower().endswith(".npy") and request.channel is None:
        spacing = None
        if request.spacing is not None:
            parts = [parse_length(x, name="spacing") for x in str(request.spacing).split(",")]
            spacing = (parts[0], parts[-1])
        return fp, surfaces.open_large(src, spacing=spacing, units=request.units)
    return fp, surfaces.load(src, spacing=request.spacing, units=request.units, channel=request.channel,
                             layout=None, nan_is_mask=False)


def _field_info(field, res) -> dict:
    """What the output says about a footprint's surface: the file, its grid and the footprint."""
    return {"source": str(getattr(field, "path", field.meta.get("source") if hasattr(field, "meta") else "")),
            "samples": list(field.shape[::-1]), "spacing_m": [field.dx, field.dy],
            "memory_mapped": not hasattr(field, "heights"), "footprint": res.info.get("footprint")}


def scatter_job(request: ScatterRequest, output, *, overwrite: bool = False, progress=None,
                estimate=None) -> ScatterRun:
    """Run *request* and write its files into the directory *output* (``lobes.exr``, ``summary.json``,
    ``lobes.png``; :func:`waveoptics.scatter.write_scatter`); an existing set is replaced only with *overwrite*.

    Every check that needs the data (the material, the split into tiles, the memory budget) runs before the
    output directory is made, so that a refused request creates nothing.

    Parameters
    ----------
    request : ScatterRequest
    output : str or Path
        The output directory.
    overwrite : bool
        Replace the files of an earlier run.
    progress : callable, optional
        ``progress(total=N, desc=TEXT)`` returning a progress bar with ``update(k)`` and ``close()`` (tqdm's),
        made when the work starts; N = wavelengths × realizations.
    estimate : callable, optional
        Called with the height field of a whole-patch request after the checks and before the output directory
        is made (the command line's time estimate, which may refuse the request).

    Returns
    -------
    ScatterRun
        The result, the files, and the warnings issued while solving (:class:`waveoptics.scatter.
        DiffractionWarning` among them).
    """
    from . import scatter
    from .io.files import prepare_outdir
    from .materials.database import fresnel_function
    from .runtime import get_runtime

    r = request
    wl = r.wavelengths_nm
    fp, field = load_height_field(r)
    hf = field if fp is None else None
    fresnel_function(r.material)      # refuse a bad material before computing
    if fp is None:
        scatter.tile_layout(hf.shape, r.realizations)   # before the time estimate: an error is its only line
    scatter.check_request_memory(r.resolution, len(wl), field.shape if fp is None else (0, 0), r.max_memory)
    if fp is None and estimate is not None:
        estimate(hf)
    prepare_outdir(output, overwrite=overwrite, expected=scatter.SCATTER_FILES)
    rt = get_runtime(r.device) if r.solver == "direct" and r.backend == "opencl" else None
    bar = None if progress is None else progress(total=len(wl) * max(1, r.realizations), desc="scatter")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", scatter.DiffractionWarning)
        common = dict(solver=r.solver, resolution=r.resolution, order=r.order, detrend=r.detrend,
                      precision=r.precision, backend=r.backend, diffraction=r.diffraction,
                      polarization=r.polarization, runtime=rt, max_memory=r.max_memory)
        if fp is None:
            res = scatter.scatter(hf, r.incident_deg, wl, r.material, realizations=r.realizations,
                                  window_name=r.window, progress=None if bar is None else bar.update, **common)
        else:
            res = scatter.footprint_scatter(field, fp, r.incident_deg, wl, r.material, coherence_m=r.coherence_m,
                                            **common)
    surface_info = hf.provenance() if hf is not None else _field_info(field, res)
    if bar is not None:
        bar.close()
    header = {"surface": r.surface_name, "material": str(r.material)}
    if rt is not None:
        header["device"] = rt.name
    paths = scatter.write_scatter(res, output, overwrite=overwrite, header=header, surface_info=surface_info)
    return ScatterRun(res, paths, header, surface_info, [str(w.message) for w in caught])
