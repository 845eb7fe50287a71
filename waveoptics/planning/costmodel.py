"""The planner's cost model, calibrated by timing on this machine once per process.
"""
from __future__ import annotations

import functools
import math
import os
import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from .. import runtime, scatter, surfaces
from ..brdf import twoscale
from ..errors import WaveopticsError
from ..materials import get_material
from ..scatter.grid import DirectionGrid
from ..scatter.series import roughness_g, series_terms
from ..units import direction_from_angles

__all__ = ['CostModel', 'fft_units', 'fft_solver_units', 'psd_terms', 'band_table_time', 'calibrate', 'calibrate_direct', 'machine_busy', 'calibration', 'direct_calibration']

# ----------------------------------------------------------------------------------------------------------------
# Cost model, calibrated on this machine once per process
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class CostModel:
    """Seconds per unit of work, measured by :func:`calibrate` (``direct_term`` by :func:`calibrate_direct`)."""

    call: float             # per two-scale evaluation on one grid (set-up, micro albedo quadrature)
    cell: float             # per direction cell (micro geometry)
    cell_wl: float          # per cell and wavelength (Fresnel, coherent part)
    diffuse_cell_wl: float  # per cell and wavelength (diffuse term of dielectrics)
    psd_wl: float           # per grid and wavelength (nano lobe set-up)
    psd_cell_wl: float      # per cell and wavelength (nano lobe, micro convolution)
    psd_term: float         # per cell, wavelength and PSD series term
    fft_unit: float         # per chirp-z work unit (see fft_units)
    band_wl: float          # per PSD model and wavelength: the band-limited series' tables and its albedo table
    calibration_s: float

    def evaluation(self, cells, n_wl: int, *, diffuse: bool = False, psd_terms: int | None = None,
                   nano_lobe: bool = False) -> float:
        """Seconds of one two-scale evaluation over grids with *cells* cells each (a list), *n_wl* wavelengths.

        *psd_terms*: the PSD series' number of terms (PSD route); *nano_lobe*: a height-field lobe is convolved
        (its solver's own cost comes on top). The band tables of the PSD route are built once per wavelength for a
        whole run, not per evaluation: :meth:`band_tables`.
        """
        t = 0.0
        for c in cells:
            t += self.call + c * (self.cell + n_wl * (self.cell_wl + (self.diffuse_cell_wl if diffuse else 0.0)))
            if psd_terms is not None:
                t += n_wl * (self.psd_wl + c * (self.psd_cell_wl + psd_terms * self.psd_term))
            elif nano_lobe:
                t += n_wl * (self.psd_wl + c * self.psd_cell_wl)
        return t

    def band_tables(self, n_wl: int) -> float:
        """Seconds to build the band-limited series' tables of one PSD model at *n_wl* wavelengths (once per run;
        every later evaluation at those wavelengths finds them cached)."""
        return n_wl * self.band_wl

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def best_of(fn, repeat=3) -> float:
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def fft_units(n_samples_xy, n_cells_uv) -> float:
    """Work of one 2-D chirp-z transform (rows then columns, Bluestein lengths n + m): Σ n log2 n."""
    nx, ny = n_samples_xy
    nu, nv = n_cells_uv
    lx, ly = nx + nu, ny + nv
    return ny * lx * math.log2(lx) + nu * ly * math.log2(ly)


def fft_solver_units(smp, wi, grids, wavelengths_nm) -> float:
    """Chirp-z work units (:func:`fft_units`) of the fft solver's incoherent lobe U − χ U_flat over *grids* at each
    wavelength: the height field's transforms (one per expansion term, :func:`waveoptics.scatter.fft_plan`) plus
    one for the flat patch."""
    return sum((1 + sum(K + 1 for _, K, _ in scatter.fft_plan(smp, wi, g, float(lam), "auto")))
               * fft_units((smp.nx, smp.ny), (g.n_u, g.n_v)) for g in grids for lam in wavelengths_nm)


def psd_terms(sigma_m: float, wavelength_nm: float) -> int:
    """Series terms :func:`waveoptics.scatter.scattered_lobe` sums at most: those of its largest g = (2kσ)²."""
    return series_terms(roughness_g(sigma_m, 2.0, wavelength_nm))


#: seconds each band series took to build in this process, by (model, λ in nm)
_BAND_BUILD_S: dict = {}


def band_table_time(model, wavelength_nm: float, material=None, theta_deg: float = 30.0) -> float:
    """Seconds to build the band-limited series of *model* at *wavelength_nm* (nm) with the albedo table its
    coherent fraction needs, on this machine. Its cost depends on the model (the radial grid follows its length
    scale, the terms its σ) by 2× and more between the PSDs of the example scenes, which the calibration's one
    model (:attr:`CostModel.band_wl`) cannot follow; the shortest wavelength is the dearest.

    The series is built once, through its cache (:func:`waveoptics.scatter.band.band_series`), and the time of
    that build is kept: the run that follows the plan in this process finds the series built instead of building
    it a second time. Only when the series was already cached by other work is a build timed past the cache."""
    from ..scatter.band import band_series, band_series_cached

    key = (model, float(wavelength_nm))
    if key not in _BAND_BUILD_S:
        hits = band_series_cached.cache_info().hits
        t = time.perf_counter()
        band_series(model, wavelength_nm).scattered_albedo(theta_deg, material=material)
        if band_series_cached.cache_info().hits > hits:     # cached by earlier work: time a build of its own
            def build():
                band_series_cached.__wrapped__(model, float(wavelength_nm), None, 512).scattered_albedo(
                    theta_deg, material=material)
            return best_of(build, 1)
        _BAND_BUILD_S[key] = time.perf_counter() - t
    return _BAND_BUILD_S[key]


@functools.lru_cache(maxsize=1)
def calibrate() -> CostModel:
    """Time small runs of each code path (two-scale micro, diffuse, PSD lobe; a chirp-z transform) on this machine.

    Each cost is a non-negative least-squares fit (scipy ``nnls``) of timed runs on grids of 16² to 64² cells with
    1 to 6 wavelengths and 11 or 41 PSD series terms to the linear model of :meth:`CostModel.evaluation`; best of
    a few repeats each, so that a busy machine inflates the fit as little as possible.
    """


    t0 = time.perf_counter()
    wi = direction_from_angles(30.0, 0.0)
    metal, diel = get_material("f0:0.9"), get_material("1.5")
    micro = twoscale.Micro(0.2, ndf="ggx")
    grids = {n: DirectionGrid.hemisphere(n) for n in (16, 32, 64)}
    wls = {k: np.linspace(420.0, 680.0, k) for k in (1, 3, 6)}

    def t(n, k, mat=metal, nano=None, repeat=3):
        f = lambda: twoscale.evaluate(wi, wls[k], mat, micro, nano, grids[n], kd=0.5)  # noqa: E731
        return best_of(f, repeat)

    runs = [(16, 1), (64, 1), (64, 6), (32, 3)]
    mf = {r: t(*r) for r in runs}
    A = np.array([[1.0, n * n, n * n * k] for n, k in runs])
    (call, cell, cell_wl), _ = nnls(A, np.array([mf[r] for r in runs]))
    diffuse = max(t(64, 6, diel) - mf[(64, 6)], 0.0) / (6 * 64 * 64)
    # PSD lobe on top of the micro model: series tables built first (not timed)
    nanos = {sg: twoscale.Nano(model=surfaces.PSDModel("gaussian", sigma=sg, T=1e-6)) for sg in (0.2e-9, 100e-9)}
    for nano in nanos.values():
        t(16, 3, nano=nano, repeat=1)
    runs = [(16, 0.2e-9), (64, 0.2e-9), (64, 100e-9), (32, 100e-9)]
    rows, y = [], []
    for n, sg in runs:
        k = psd_terms(sg, 420.0)
        rows.append([3.0, 3.0 * n * n, 3.0 * n * n * k])
        y.append(max(t(n, 3, nano=nanos[sg], repeat=2) - t(n, 3, repeat=2), 0.0))
    (psd_wl, psd_cell_wl, psd_term), _ = nnls(np.array(rows), np.array(y))
    # fft: one chirp-z transform of a 128² patch onto a 32² grid
    hf = surfaces.generate("flat", size=128 * 100e-9, samples=128)
    smp = scatter.samples(hf)
    t_fft = best_of(lambda: scatter.field_fft(smp, wi, grids[32], 550.0, order=0), 2)
    fft_unit = t_fft / fft_units((smp.nx, smp.ny), (32, 32))
    # the band-limited series of a PSD model is built once per wavelength (scatter.band_series, cached): time two
    # builds past the cache (a recalibration in the same process would otherwise time cache hits), with the albedo
    # table the coherent fraction needs
    from ..scatter.band import band_series_cached

    band_model = surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6)
    t_band = time.perf_counter()
    for lam in (431.7, 563.3):
        band_series_cached.__wrapped__(band_model, lam, None, 512).scattered_albedo(30.0, material=metal)
    band_wl = (time.perf_counter() - t_band) / 2
    return CostModel(float(call), float(cell), float(cell_wl), diffuse, float(psd_wl), float(psd_cell_wl),
                     float(psd_term), fft_unit, float(band_wl), time.perf_counter() - t0)


def calibration(*, recalibrate: bool = False) -> CostModel:
    """The cost model of this machine: timed once by :func:`calibrate` and kept in the per-user cache
    (:mod:`waveoptics.cache`, keyed by the machine); *recalibrate* times it again and replaces the cached one."""
    from .. import cache

    if not recalibrate:
        hit = cache.get("calibration", "cost_model")
        if isinstance(hit, dict) and set(hit) == set(CostModel.__dataclass_fields__):
            return CostModel(**hit)
    elif hasattr(calibrate, "cache_clear"):
        calibrate.cache_clear()   # the in-process memo too
    cm = calibrate()
    if not machine_busy():   # a busy machine's timings serve this process only: the next one re-times them
        cache.put("calibration", "cost_model", cm.as_dict())
    return cm


def machine_busy() -> bool:
    """Whether more work than the machine has CPUs for runs now (1-minute load average above the CPU count): a
    cost model timed then overstates every later estimate (measured: 4× on the haze scene, 100× per cell and
    wavelength, from a calibration kept while the test suite ran)."""
    try:
        load = os.getloadavg()[0]
    except (AttributeError, OSError):   # no load average on this platform: trust the timings
        return False
    return load > (os.cpu_count() or 1)


def direct_calibration(device: str | None = None, precision: str = "float32", *,
                       recalibrate: bool = False) -> tuple[float | None, str]:
    """:func:`calibrate_direct` kept in the per-user cache per device and precision (an unavailable device is
    not cached: it may be installed later)."""
    from .. import cache

    key = f"direct|{device or os.environ.get('WAVEOPTICS_DEVICE', '')}|{precision}"
    if not recalibrate:
        hit = cache.get("calibration", key)
        if isinstance(hit, (int, float)) and hit > 0:
            return float(hit), ""
    elif hasattr(calibrate_direct, "cache_clear"):
        calibrate_direct.cache_clear()
    term, why = calibrate_direct(device, precision)
    if term is not None:
        cache.put("calibration", key, term)
    return term, why


@functools.lru_cache(maxsize=4)
def calibrate_direct(device: str | None = None, precision: str = "float32") -> tuple[float | None, str]:
    """(seconds per sample·direction·wavelength of the OpenCL direct sum, "") or (None, why it is unavailable)."""

    if not runtime.opencl_available():
        return None, "no OpenCL platform"
    try:
        return _time_direct(runtime.get_runtime(device), precision), ""
    except WaveopticsError as exc:  # no device of that name, or the kernel does not build here
        return None, str(exc).splitlines()[0]


def _time_direct(rt, precision):

    if precision == "float64" and not rt.fp64:
        precision = "float32"
    hf = surfaces.generate("sinusoid", amplitude=40e-9, period=1.6e-6, size=128 * 100e-9, samples=128)
    smp = scatter.samples(hf)
    g = DirectionGrid.hemisphere(24)
    wo = g.directions()[g.inside]
    coef = scatter.phase_coefficients(smp, direction_from_angles(30.0, 0.0), wo, [550.0])
    scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision=precision)      # build + warm-up
    t = best_of(lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision=precision), 2)
    return t / (coef.size * smp.size)
