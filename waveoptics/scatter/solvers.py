"""The solvers of the Kirchhoff lobe (registry :data:`SOLVERS`) and the public entry points :func:`brdf` and
:func:`scatter`.
"""
from __future__ import annotations

import contextlib
import math
import threading
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import WaveopticsError, unknown
from ..materials import fresnel_function
from ..runtime import check_memory
from ..surfaces.heightfield import HeightField
from ..units import check_wavelengths
from ..vocabulary import FIELD_BACKENDS
from .direct import kirchhoff_U, kirchhoff_U_cl, phase_coefficients
from .fft import FFT_TOL, field_fft
from .grid import HORIZON_SIN, DirectionGrid, incident_dirs, outgoing_dirs, integrate
from .kirchhoff import brdf_from_field, coherent_amplitude, cos_theta_d
from .models import get_model
from .patch import DEFAULT_WINDOW, Samples, samples

__all__ = ['ENERGY_TOL', 'DiffractionWarning', 'diffraction_warnings_held', 'Solver', 'SOLVERS', 'BACKENDS', 'get_solver', 'tile_layout', 'split_patch', 'sampling_warnings', 'brdf', 'ScatterResult', 'memory_estimate', 'check_request_memory', 'scatter']

#: largest albedo of the F = 1 lobe that :func:`scatter` accepts without an "energy not conserved" warning
ENERGY_TOL = 1.05


class DiffractionWarning(UserWarning):
    """A result is computed but an approximation or sampling condition is violated (aliasing, coarse grid...)."""


_HELD = threading.local()   # this thread's sink of held messages (diffraction_warnings_held), or none


@contextlib.contextmanager
def diffraction_warnings_held(sink: list):
    """Within the block, in the calling thread only, the messages :func:`warn_or_collect` would warn are appended
    to *sink* instead (for a computation whose own caller says what its sampling misses). Unlike
    ``warnings.catch_warnings``, which swaps the process-wide filters and is not thread-safe, it leaves other
    threads' warnings alone: two pool threads that entered and left ``catch_warnings`` in turn restored each
    other's "ignore" filter, and every later :class:`DiffractionWarning` of the run was lost (issue 28)."""
    outer = getattr(_HELD, "sink", None)
    _HELD.sink = sink
    try:
        yield sink
    finally:
        _HELD.sink = outer


def warn_or_collect(msg: str, sink: list | None = None) -> None:
    """Warn *msg* as a :class:`DiffractionWarning` (appended to *sink* too, if given); held instead inside
    :func:`diffraction_warnings_held`."""
    if sink is not None:
        sink.append(msg)
    held = getattr(_HELD, "sink", None)
    if held is not None:
        held.append(msg)
        return
    warnings.warn(msg, DiffractionWarning, stacklevel=3)


# ----------------------------------------------------------------------------------------------------------------
# High-level API
# ----------------------------------------------------------------------------------------------------------------

def _grid_field_direct(smp: Samples, wi, grid: DirectionGrid, wl, *, backend="opencl", runtime=None,
                       precision="float32", progress=None, diffraction="kirchhoff", **_) -> tuple[np.ndarray, dict]:
    """U on the grid by the direct sum at every cell centre inside the disc (0 outside), with the vertical phase
    of the *diffraction* model."""
    d_in = grid.directions()[grid.inside]
    coef = phase_coefficients(smp, wi, d_in, wl, frozen_cos_sum=get_model(diffraction).frozen_cos_sum)
    if backend == "numpy":
        Uin = kirchhoff_U(smp, coef)
        if progress is not None:
            progress(len(wl))
    else:
        step = (lambda n, _k=d_in.shape[0]: progress(n / _k)) if progress is not None else None
        Uin = kirchhoff_U_cl(smp, coef, runtime=runtime, precision=precision, progress=step)
    U = np.zeros((len(wl), grid.n_v, grid.n_u), np.complex128)
    U[:, grid.inside] = Uin.reshape(len(wl), -1)
    return U, {"precision": precision if backend == "opencl" else "float64", "backend": backend}


def _grid_field_fft(smp: Samples, wi, grid: DirectionGrid, wl, *, order="auto", tol=FFT_TOL, progress=None,
                    diffraction="kirchhoff", workers=None, **_) -> tuple[np.ndarray, dict]:
    """U on the grid by chirp-z transforms (:func:`field_fft`), the wavelengths in parallel threads (NumPy and
    scipy.fft release the GIL; *workers* as :func:`waveoptics.runtime.cpu_workers`)."""
    from concurrent.futures import ThreadPoolExecutor

    from ..runtime import cpu_workers

    U = np.empty((len(wl), grid.n_v, grid.n_u), np.complex128)
    frozen = get_model(diffraction).frozen_cos_sum
    n_threads = min(cpu_workers(workers), len(wl))

    def one(i):
        U[i], inf = field_fft(smp, wi, grid, wl[i], order, tol, frozen)
        if progress is not None:
            progress(1)
        return {"wavelength_nm": float(wl[i]), **inf}

    if n_threads <= 1:
        plans = [one(i) for i in range(len(wl))]
    else:
        with ThreadPoolExecutor(max_workers=n_threads) as pool:
            plans = list(pool.map(one, range(len(wl))))
    return U, {"fft": plans, "threads": n_threads}


def _lobe_at_direct(smp: Samples, wi, wo, wl, F, *, backend="opencl", runtime=None, precision="float32",
                    progress=None, diffraction="kirchhoff", **_) -> np.ndarray:
    """f at the given directions by the direct sum there."""
    for m in sampling_warnings(smp, wi, wl, wo=wo):
        warn_or_collect(m)
    coef = phase_coefficients(smp, wi, wo, wl, frozen_cos_sum=get_model(diffraction).frozen_cos_sum)
    U = kirchhoff_U(smp, coef) if backend == "numpy" else kirchhoff_U_cl(smp, coef, runtime=runtime,
                                                                          precision=precision, progress=progress)
    return brdf_from_field(U.reshape(len(wl), -1), wi, wo, wl, smp.area, F, diffraction)


def lobe_at_fft(smp: Samples, wi, wo, wl, F, *, order="auto", resolution=None, progress=None,
                 diffraction="kirchhoff", **_) -> np.ndarray:
    """f at the given directions, interpolated bilinearly in (u, v) from the lobe on a hemisphere grid fine enough
    to resolve the specular spike at the shortest wavelength (or *resolution*)."""
    res = resolution or min(2048, max(64, int(math.ceil(2 * max(smp.extent) / (wl.min() * 1e-9)))))
    grid = DirectionGrid.hemisphere(res)
    dirs = grid.directions()
    for m in sampling_warnings(smp, wi, wl, grid=grid):
        warn_or_collect(m)
    out = np.zeros((len(wl), wo.shape[0]))
    for i, lam in enumerate(wl):
        U, _ = field_fft(smp, wi, grid, lam, order, frozen_cos_sum=get_model(diffraction).frozen_cos_sum)
        f = brdf_from_field(U[None], wi, dirs, [lam], smp.area, F, diffraction)[0]
        # bilinear between the four nearest cell centres, held at the edge cells (a convex combination: never
        # below the smallest of them); linear extrapolation beyond the outermost centres made f < 0 near the horizon
        out[i] = np.where(wo[:, 2] > 0, grid.interpolate(f, wo[:, 0], wo[:, 1]), 0.0)
        if progress is not None:
            progress(1)
    return out


@dataclass(frozen=True)
class Solver:
    """A solver of the Kirchhoff field of a prepared patch (:class:`Samples`).

    Attributes
    ----------
    name, description : str
    grid_field : callable (smp, wi, grid, wavelengths_nm, **options) -> (U (n_λ, n_v, n_u) complex, info dict)
        The field U (m²) at the grid's cell centres (0 outside the disc).
    lobe_at : callable (smp, wi, wo, wavelengths_nm, F, **options) -> f (n_λ, n) in 1/sr
        The BRDF at arbitrary outgoing directions.
    """

    name: str
    description: str
    grid_field: Callable
    lobe_at: Callable


#: solver name -> :class:`Solver` (the ``method=`` registry; every caller dispatches through it)
SOLVERS = {
    "direct": Solver("direct", "direct Kirchhoff sum on the OpenCL device or its NumPy twin (exact tangent-plane "
                               "model; O(samples x directions))", _grid_field_direct, _lobe_at_direct),
    "fft": Solver("fft", "chirp-z transforms on the direction-cosine grid, banded Taylor series in v_z "
                         "(order='auto') or frozen v_z (order=0)", _grid_field_fft, lobe_at_fft),
}
BACKENDS = FIELD_BACKENDS


def _F_at(F, wi, wo, wavelengths_nm):
    """The Fresnel factor for directions wo (..., 3): per direction for polarized light, else from cos θ_d."""
    if hasattr(F, "at"):
        return F.at(wi, wo, wavelengths_nm)
    return F(cos_theta_d(wi, wo), wavelengths_nm)


def get_solver(solver: str, backend: str = "opencl") -> Solver:
    """The :class:`Solver` named *solver* (and a check of the direct solver's *backend*)."""
    if solver not in SOLVERS:
        raise unknown("solver", solver, SOLVERS, field="solver")
    if backend not in BACKENDS:
        raise unknown("backend", backend, BACKENDS, field="backend")
    return SOLVERS[solver]


def _realizations(surface, realizations, seed=0) -> list[HeightField]:
    """The list of height fields to average over (see :func:`scatter`)."""
    n = 1 if realizations is None else realizations
    try:
        ok = not isinstance(n, bool) and float(n) == int(n) and int(n) >= 1
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise WaveopticsError(f"realizations={realizations!r} is not allowed; it must be an integer >= 1")
    n = int(n)
    if isinstance(surface, HeightField):
        return split_patch(surface, n) if n > 1 else [surface]
    if callable(surface):
        return [surface(seed + r) for r in range(n)]
    try:
        hfs = list(surface)
    except TypeError:
        raise WaveopticsError(f"surface must be a HeightField, a list of them or a callable seed -> HeightField, "
                              f"got {type(surface).__name__}") from None
    if not hfs or not all(isinstance(h, HeightField) for h in hfs):
        raise WaveopticsError("surface list must hold at least one HeightField and nothing else")
    if realizations is not None and int(realizations) != len(hfs):
        raise WaveopticsError(f"realizations={realizations} differs from the {len(hfs)} height fields given")
    return hfs


def tile_layout(shape, n) -> tuple[int, int]:
    """(a, b): the split of a patch of *shape* (ny, nx) into *n* equal tiles, a along y and b along x, each at
    least 2x2 samples and as square as possible; a one-line error when *n* is not an integer >= 1 or no split
    exists. Checked before any work (the CLI asks it before its time estimate)."""
    try:
        ok = not isinstance(n, bool) and float(n) == int(n) and int(n) >= 1
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise WaveopticsError(f"realizations={n!r} is not allowed; it must be an integer >= 1")
    n = int(n)
    ny, nx = shape
    most = (ny // 2) * (nx // 2)
    if n > most:   # before the search over divisors, which would take n steps
        raise WaveopticsError(f"cannot split a {nx}x{ny} patch into {n} tiles of at least 2x2 samples; use "
                              f"realizations 1..{max(most, 1)}")
    best = None
    for a in range(1, n + 1):
        if n % a:
            continue
        b = n // a                                   # a tiles along y, b along x
        if ny // a < 2 or nx // b < 2:
            continue
        score = abs(math.log((nx / b) / (ny / a)))
        if best is None or score < best[0]:
            best = (score, a, b)
    if best is None:
        raise WaveopticsError(f"cannot split a {nx}x{ny} patch into {n} tiles of at least 2x2 samples")
    return best[1], best[2]


def split_patch(hf: HeightField, n: int) -> list[HeightField]:
    """Split *hf* into *n* equal, non-overlapping tiles (as square a layout as possible, :func:`tile_layout`) for
    ensemble averages.

    Tiles of one large measured or generated patch stand in for independent realizations when the patch spans
    many correlation lengths; each tile is smaller, so the angular resolution λ/L is coarser.
    """
    ny, nx = hf.shape
    a, b = tile_layout(hf.shape, n)
    ty, tx = ny // a, nx // b
    out = []
    for i in range(a):
        for j in range(b):
            sl = (slice(i * ty, (i + 1) * ty), slice(j * tx, (j + 1) * tx))
            mask = None if hf.mask is None else hf.mask[sl]
            out.append(HeightField(hf.heights[sl], hf.dx, hf.dy, mask, dict(hf.meta, tile=(i, j))))
    return out


def sampling_warnings(smp: Samples, wi, wavelengths_nm, grid: DirectionGrid | None = None,
                      wo=None) -> list[str]:
    """Messages for violated sampling conditions (docs/physics.md §1).

    * Aliasing: the sum is periodic in s_x dx / λ with period 1, so directions with |u_i + u_o| > λ/(2 dx)
      (or the same along y) receive light that belongs elsewhere. The whole disc is safe when dx, dy ≤ λ/4.
    * Lobe sampling (grids only): the specular spike of a patch of length L has width ~λ/L in u; the grid
      sums it exactly (Poisson summation of |Û|², whose transform — the window's autocorrelation — has
      support |x| < L) only when du ≤ λ/Lx and dv ≤ λ/Ly.
    """
    msgs = []
    lam = np.asarray(wavelengths_nm, dtype=float) * 1e-9
    if grid is not None:
        sx = np.abs(wi[0] + grid.u[grid.inside.any(axis=0)]).max()
        sy = np.abs(wi[1] + grid.v[grid.inside.any(axis=1)]).max()
    else:
        wo = np.asarray(wo)
        sx = float(np.max(np.abs(wo[:, 0] + wi[0])))
        sy = float(np.max(np.abs(wo[:, 1] + wi[1])))
    lmin = float(lam.min())
    if sx * smp.dx / lmin > 0.5 + 1e-12 or sy * smp.dy / lmin > 0.5 + 1e-12:
        msgs.append(f"aliasing: sample spacing {smp.dx * 1e9:.4g} x {smp.dy * 1e9:.4g} nm is too coarse for "
                    f"{lmin * 1e9:.4g} nm at these directions (needs |u_i + u_o| <= lambda/(2 dx) = "
                    f"{lmin / (2 * smp.dx):.3g}); use dx <= lambda/4 = {lmin / 4 * 1e9:.4g} nm for the whole "
                    "hemisphere")
    if grid is not None:
        Lx, Ly = smp.extent
        if grid.du > lmin / Lx * (1 + 1e-9) or grid.dv > lmin / Ly * (1 + 1e-9):
            need = int(math.ceil((grid.u_range[1] - grid.u_range[0]) * Lx / lmin))
            msgs.append(f"coarse direction grid: du = {grid.du:.3g} > lambda/L = {lmin / Lx:.3g}; the specular "
                        f"spike is under-sampled and its albedo quadrature is inexact (use resolution >= {need})")
    return msgs


def brdf(surface, wi, wo, wavelengths_nm, material=None, *, solver: str = "direct", backend: str = "opencl",
         precision: str = "float32", window_name=DEFAULT_WINDOW, detrend: str = "mean", order="auto",
         resolution: int | None = None, realizations=None, seed: int = 0, runtime=None,
         progress=None, diffraction: str = "kirchhoff", polarization: str = "unpolarized") -> np.ndarray:
    """Kirchhoff BRDF for arbitrary outgoing directions, averaged over realizations.

    Parameters
    ----------
    surface : HeightField, list of HeightField, or callable seed -> HeightField
        The patch (or the ensemble; see :func:`scatter`).
    wi : (theta_deg, phi_deg) or ndarray (3,)
        Direction towards the light.
    wo : ndarray (n, 3)
        Unit vectors towards the viewer.
    wavelengths_nm : array_like, nm
    material : see :func:`fresnel_function`
    solver : {'direct', 'fft'}
        ``fft`` evaluates on a hemisphere grid (*resolution*, default: fine enough to resolve the specular spike
        at the shortest wavelength) and interpolates bilinearly in (u, v).
    backend : {'opencl', 'numpy'}
        For ``direct``: the kernel or its float64 NumPy twin.
    window_name, detrend : see :func:`window` and :func:`samples`.
    diffraction : str
        Diffraction model, a name in :data:`DIFFRACTION_MODELS` (default ``kirchhoff``).
    polarization : {'unpolarized', 's', 'p'}
        Of the incident light, relative to the macro plane of incidence; each facet reflects its own s/p split
        (:func:`waveoptics.materials.fresnel.F_facet_polarized`). s and p need a material with a complex index.

    Returns
    -------
    ndarray (n_wl, n), sr⁻¹
    """
    sol = get_solver(solver, backend)
    get_model(diffraction)
    wi = incident_dirs(wi)
    wo = outgoing_dirs(wo)
    wl = check_wavelengths(wavelengths_nm)
    F = fresnel_function(material, polarization)
    hfs = _realizations(surface, realizations, seed)
    acc = np.zeros((wl.size, wo.shape[0]))
    for hf in hfs:
        acc += sol.lobe_at(samples(hf, window_name, detrend), wi, wo, wl, F, backend=backend, runtime=runtime,
                           precision=precision, order=order, resolution=resolution, progress=progress,
                           diffraction=diffraction)
    return np.clip(acc / len(hfs), 0.0, None)


@dataclass
class ScatterResult:
    """Per-wavelength Kirchhoff lobes over a direction-cosine grid and their integrals.

    Attributes
    ----------
    wavelengths_nm : ndarray (n_wl,), nm
    grid : DirectionGrid
    brdf : ndarray (n_wl, n_v, n_u), sr⁻¹
        Ensemble-mean BRDF; 0 outside the unit disc.
    albedo : ndarray (n_wl,)
        Directional albedo ∫ f cos θ_o dω_o over the whole disc.
    albedo_inner : ndarray (n_wl,)
        The same over sin θ_o ≤ :data:`HORIZON_SIN` (the rest is the near-horizon share, where 1/cos θ_o
        amplifies any error and the tangent-plane model itself is least reliable).
    coherent_specular_fraction : ndarray (n_wl,)
        |⟨χ̂⟩|², the fraction of the specular reflectance that stays coherent (exp(−g) for Gaussian heights).
    scattered_fraction : ndarray (n_wl,)
        The diffusely scattered reflectance (TIS = F (1 − exp(−g))): the integral of the incoherent lobe
        |U − χ̂ U_flat|² of each patch plus the spread of the patches' coherent amplitudes (:func:`coherent_split`);
        equal to albedo − |⟨χ̂⟩|² · flat_albedo up to the quadrature of the mirror spike, and never negative.
    flat_albedo : ndarray (n_wl,)
        Albedo of the same window without heights on the same grid (≈ F(θ_i); the quadrature reference).
    fresnel_specular : ndarray (n_wl,)
        F(θ_i).
    """

    wavelengths_nm: np.ndarray
    grid: DirectionGrid
    brdf: np.ndarray
    albedo: np.ndarray
    albedo_inner: np.ndarray
    coherent_specular_fraction: np.ndarray
    scattered_fraction: np.ndarray
    flat_albedo: np.ndarray
    fresnel_specular: np.ndarray
    incident: np.ndarray
    solver: str
    realizations: int
    timings_s: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    info: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """Plain data for ``summary.json`` (lists, one entry per wavelength)."""
        th = math.degrees(math.acos(min(1.0, float(self.incident[2]))))
        ph = math.degrees(math.atan2(self.incident[1], self.incident[0]))
        return {
            "wavelengths_nm": self.wavelengths_nm, "albedo": self.albedo,
            "coherent_specular_fraction": self.coherent_specular_fraction,
            "scattered_fraction": self.scattered_fraction, "albedo_inner": self.albedo_inner,
            "horizon_sin": HORIZON_SIN, "flat_albedo": self.flat_albedo, "fresnel_specular": self.fresnel_specular,
            "incident_deg": [th, ph], "solver": self.solver, "realizations": self.realizations,
            "grid": {"n_u": self.grid.n_u, "n_v": self.grid.n_v, "u_range": self.grid.u_range,
                     "v_range": self.grid.v_range},
            "timings_s": self.timings_s, "warnings": self.warnings, "info": self.info,
            "units": {"albedo": "1 (reflected / incident power)", "coherent_specular_fraction": "1",
                      "scattered_fraction": "1", "albedo_inner": "1", "flat_albedo": "1",
                      "fresnel_specular": "1", "horizon_sin": "1 (sine of the horizon cut)",
                      "grid": "direction cosines u = sin θ cos φ, v = sin θ sin φ", "lobes.exr": "1/sr"},
        }


#: bytes per direction-grid cell per wavelength (lobe arrays, fields U and U0, masks; measured with GNU time on the
#: fft route: 156-185 B at 1000² and 2000² cells, 1 and 4 wavelengths) and per cell whatever the wavelengths
_BYTES_PER_CELL_WAVELENGTH = 200.0
_BYTES_PER_CELL = 60.0


def memory_estimate(n_u: int, n_v: int, n_wavelengths: int, sample_shape=(0, 0)) -> float:
    """Bytes a :func:`scatter` request holds at its peak: the (n_λ, n_v, n_u) lobes with their fields and masks,
    plus the zoom-FFT intermediates (n_y × n_u and n_v × n_u complex) of one wavelength.

    Calibrated with GNU ``time`` (maximum resident set) on this project's fft route; the estimate is an upper bound
    within about 30 % for grids of 10⁶ cells and more, where memory matters."""
    cells = float(n_u) * float(n_v)
    ny, nx = (float(v) for v in sample_shape)
    zoom = 16.0 * 3 * (ny * n_u + float(n_v) * n_u) + 16.0 * 4 * nx * ny
    return cells * (_BYTES_PER_CELL + _BYTES_PER_CELL_WAVELENGTH * n_wavelengths) + zoom


def check_request_memory(resolution, n_wavelengths: int, sample_shape=(0, 0), max_memory=None) -> None:
    """Refuse, before any work, a :func:`scatter` request (*resolution* cells per side, or (n_u, n_v)) whose
    :func:`memory_estimate` exceeds the budget, in one line naming what to reduce
    (:func:`waveoptics.runtime.check_memory`)."""
    n_u, n_v = (resolution, resolution) if np.ndim(resolution) == 0 else resolution
    check_memory(memory_estimate(n_u, n_v, n_wavelengths, sample_shape), "this scattering request",
                 "lower {resolution} or the number of {wavelengths_nm}", max_memory,
                 fields=("resolution", "wavelengths_nm"))


def coherent_split(smp: Samples, U, wi, grid: DirectionGrid, wavelengths_nm, F, model):
    """(χ̂, flat albedo, scattered albedo), each (n_wl,), of one patch whose field on *grid* is *U* (n_wl, n_v, n_u).

    χ̂ is the patch's coherent amplitude (:func:`coherent_amplitude`); the flat albedo integrates the lobe of the
    same window without heights, U_flat; the scattered albedo integrates the lobe of the incoherent field
    U − χ̂ U_flat directly. The difference albedo − |χ̂|² · flat equals it only where the cross term
    2 Re(χ̂* U_flat* (U − χ̂ U_flat)) integrates to zero, which holds for the continuous Parseval sum over the patch
    (the w² weights of χ̂) but not for the quadrature of the mirror spike on the direction grid with the factor K
    varying across it: at 40° incidence the difference is off by about −1.5e-6 of the incident power (negative
    for a 0.05 nm rms patch at 550 nm), while the lobe's own integral agrees with the patch's Parseval sum
    Σ w² |exp(i v_z h) − χ̂|² / Σ w² to 3e-4.

    References
    ----------
    .. [1] J. E. Harvey, N. Choi, S. Schröder, A. Duparré, "Total integrated scatter from surfaces with arbitrary
       roughness, correlation widths, and incident angles", Opt. Eng. 51, 013402 (2012): the coherent (specular)
       and the diffusely scattered parts of the reflected field and TIS = R (1 − exp(−g)).
    .. [2] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon
       1963, ch. 5: ⟨|U|²⟩ = |⟨U⟩|² + ⟨|U − ⟨U⟩|²⟩.
    """
    wl = np.atleast_1d(np.asarray(wavelengths_nm, dtype=float))
    dirs = grid.directions()
    flat0 = Samples(smp.ix, smp.iy, np.zeros_like(smp.h), smp.w, smp.dx, smp.dy, smp.nx, smp.ny, smp.area)
    chi, flat, scat = np.zeros(wl.size, np.complex128), np.zeros(wl.size), np.zeros(wl.size)
    for i, lam in enumerate(wl):
        chi[i] = coherent_amplitude(smp, wi, lam, model)
        U0, _ = field_fft(flat0, wi, grid, lam, 0)
        flat[i] = integrate(brdf_from_field(U0[None], wi, dirs, [lam], smp.area, F, model)[0], grid)
        fs = brdf_from_field((U[i] - chi[i] * U0)[None], wi, dirs, [lam], smp.area, F, model)[0]
        scat[i] = integrate(fs, grid)
    return chi, flat, scat


def scatter(surface, wi, wavelengths_nm, material=None, *, solver: str = "fft", resolution: int = 256,
            grid: DirectionGrid | None = None, realizations=None, seed: int = 0, backend: str = "opencl",
            precision: str = "float32", window_name=DEFAULT_WINDOW, detrend: str = "mean", order="auto",
            tol: float = FFT_TOL, runtime=None, progress=None, diffraction: str = "kirchhoff",
            polarization: str = "unpolarized", max_memory=None) -> ScatterResult:
    """Kirchhoff lobes over the projected hemisphere, per wavelength, with albedo and coherent/scattered split.

    Parameters
    ----------
    surface : HeightField, list of HeightField, or callable seed -> HeightField
        One patch, an explicit ensemble, or a generator called with seeds ``seed .. seed + realizations − 1``.
        A single HeightField with ``realizations = n > 1`` is split into n tiles (:func:`split_patch`).
    wi : (theta_deg, phi_deg) or ndarray (3,)
        Direction towards the light.
    wavelengths_nm : array_like, nm
    material : see :func:`fresnel_function` (None: F = 1)
    solver : {'fft', 'direct'}
    resolution : int
        Cells per side of the hemisphere grid (ignored when *grid* is given).
    grid : DirectionGrid, optional
        A custom (sub-)grid of the direction-cosine plane.
    realizations : int, optional
    backend, precision : for the ``direct`` solver (OpenCL float32/float64, or the NumPy twin).
    window_name, detrend : see :func:`window` and :func:`samples`.
    order, tol : for the ``fft`` solver (see :func:`fft_plan`).
    diffraction : str
        Diffraction model, a name in :data:`DIFFRACTION_MODELS` (default ``kirchhoff``): its factor K and vertical
        phase shape the lobe and its coherent part (:mod:`waveoptics.scatter.models`).
    polarization : {'unpolarized', 's', 'p'}
        Of the incident light (see :func:`brdf`); the flat-patch reference then reflects R_s(θ_i) or R_p(θ_i).
    progress : callable, optional
        Called with the number of finished work units (wavelengths × realizations); total is
        ``len(wavelengths) * realizations``.
    max_memory : int or str, optional
        Memory budget (bytes or ``"4GB"``); a request whose :func:`memory_estimate` exceeds it is refused before any
        work (default :func:`waveoptics.runtime.memory_limit`).

    Returns
    -------
    ScatterResult
    """
    t0 = time.perf_counter()
    sol = get_solver(solver, backend)
    model = get_model(diffraction)
    wi = incident_dirs(wi)
    wl = check_wavelengths(wavelengths_nm)
    F = fresnel_function(material, polarization)
    check_request_memory((grid.n_u, grid.n_v) if grid is not None else resolution, wl.size,
                         surface.shape if isinstance(surface, HeightField) else (0, 0), max_memory)
    grid = grid if grid is not None else DirectionGrid.hemisphere(resolution)
    if not grid.inside.any():
        raise WaveopticsError(f"direction grid u_range={grid.u_range}, v_range={grid.v_range} has no cell centre "
                              "inside the unit disc (above the horizon)")
    hfs = _realizations(surface, realizations, seed)
    dirs = grid.directions()
    inside = grid.inside
    horizon = grid.sin_theta <= HORIZON_SIN
    n_wl, R = wl.size, len(hfs)
    f_sum = np.zeros((n_wl, grid.n_v, grid.n_u))
    alb = np.zeros(n_wl)
    alb_in = np.zeros(n_wl)
    flat_r, scat_r = np.zeros((R, n_wl)), np.zeros((R, n_wl))
    chi_r = np.zeros((R, n_wl), np.complex128)
    msgs: list[str] = []
    info = {"window": "explicit weights" if isinstance(window_name, np.ndarray) else str(window_name), "diffraction": model.name, "polarization": polarization}
    t_solve = t_flat = 0.0
    for r, hf in enumerate(hfs):
        smp = samples(hf, window_name, detrend)
        for m in sampling_warnings(smp, wi, wl, grid=grid):
            if m not in msgs:
                warn_or_collect(m, msgs)
        t1 = time.perf_counter()
        U, inf = sol.grid_field(smp, wi, grid, wl, backend=backend, runtime=runtime, precision=precision,
                                order=order, tol=tol, progress=progress, diffraction=model)
        if r == 0:
            info.update(inf)
        t_solve += time.perf_counter() - t1
        f = brdf_from_field(U, wi, dirs, wl, smp.area, F, model)
        f = np.where(inside, np.clip(f, 0.0, None), 0.0)
        f_sum += f
        alb += integrate(f, grid)
        alb_in += integrate(f, grid, region=horizon)
        t1 = time.perf_counter()
        chi_r[r], flat_r[r], scat_r[r] = coherent_split(smp, U, wi, grid, wl, F, model)
        t_flat += time.perf_counter() - t1
    f_mean, alb, alb_in = f_sum / R, alb / R, alb_in / R
    chi, flat = chi_r.mean(axis=0), flat_r.mean(axis=0)
    coh = np.abs(chi) ** 2
    # the scattered reflectance is the integral of the incoherent lobe itself, never a difference albedo − coherent:
    # each patch's lobe of U − χ̂ U_flat, plus the spread of the patches' coherent amplitudes about their mean
    # (light that is specular in each patch but does not add coherently over the ensemble)
    scat = scat_r.mean(axis=0) + np.mean(np.abs(chi_r - chi) ** 2 * flat_r, axis=0)
    spec_share = alb - alb_in
    bad = (spec_share > 0.05 * np.maximum(alb, 1e-300)) & (alb > 0)
    if np.any(bad):
        i = int(np.argmax(np.where(bad, spec_share / np.maximum(alb, 1e-300), 0)))
        warn_or_collect(f"{100 * spec_share[i] / alb[i]:.0f}% of the albedo at {wl[i]:g} nm lies near the horizon "
              f"(sin theta_o > {HORIZON_SIN}), where 1/cos theta_o amplifies errors and the tangent-plane model "
              "(no shadowing) is least reliable" + (" and the frozen-v_z fft approximation fails; use "
                                                    "order='auto' or solver='direct'"
                                                    if solver == "fft" and order != "auto" else ""), msgs)
    mirror = np.array([-wi[0], -wi[1], wi[2]])
    Fspec = np.asarray(_F_at(F, wi, np.broadcast_to(mirror, (n_wl, 3)), wl), dtype=float)
    # energy check: the lobe with F = 1 must not reflect more than the light that arrives (the flat patch's
    # albedo on this grid is 1 to quadrature accuracy); near grazing incidence the tangent-plane obliquity
    # factor grows as 1/cos θ_i and the model, which has no shadowing, breaks this (albedo 260 at 90°)
    Fg = np.asarray(_F_at(F, wi, dirs[None], wl[:, None, None]), dtype=float)
    alb1 = integrate(np.where(Fg > 0, f_mean / np.where(Fg > 0, Fg, 1.0), 0.0), grid)
    if np.any(alb1 > ENERGY_TOL):
        i = int(np.argmax(alb1))
        warn_or_collect(f"energy not conserved: the Kirchhoff albedo with F = 1 is {alb1[i]:.3g} > 1 at {wl[i]:g} nm for "
              f"theta_i = {math.degrees(math.acos(min(1.0, wi[2]))):.4g} deg; the tangent-plane model fails this "
              "close to grazing incidence (obliquity ~ 1/cos theta_i, no shadowing) and these lobes are not "
              "physical", msgs)
    timings = {"solve": t_solve, "flat_and_coherent": t_flat, "total": time.perf_counter() - t0}
    return ScatterResult(wl, grid, f_mean, alb, alb_in, coh, scat, flat, Fspec, wi, solver, R, timings, msgs, info)


# ----------------------------------------------------------------------------------------------------------------
# Output
# ----------------------------------------------------------------------------------------------------------------


