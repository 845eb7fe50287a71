"""Which roughness scatters: the propagating band of surface frequencies and the relevant rms roughness
(docs/physics.md §9).

A surface frequency f scatters light of wavelength λ incident at (θ_i, φ_i) into the direction whose direction
cosines are (u, v) = −(sinθ_i cosφ_i, sinθ_i sinφ_i) − λ f (grating equation; the sign follows ω_i pointing
towards the light). The direction propagates only when |(u, v)| ≤ 1, so the frequencies that scatter at all fill
the disc

    |f + (sinθ_i cosφ_i, sinθ_i sinφ_i) / λ| ≤ 1 / λ

of the frequency plane: centred on −sinθ_i/λ (along the incident azimuth), radius 1/λ. Its share of the height
variance is the relevant roughness

    σ_rel² = ∫∫_band S(f_x, f_y) df_x df_y  ≤  σ²,

and the rest, σ² − σ_rel², lies in evanescent orders: it neither scatters nor (in the generalized Harvey-Shack
theory) reduces the specular reflection, exp(−(4π σ_rel cosθ_i / λ)²). A model that uses the full σ in exp(−g)
while its diffracted lobe receives only the band loses the difference (docs/physics.md §9).

For an isotropic PSD the band integral reduces to one radial integral: the circle |f| = r lies inside the disc
for r ≤ 1/λ − s and meets it in an arc of angle 2 arccos((r² + s² − 1/λ²) / (2 r s)) for |1/λ − s| < r < 1/λ + s,
with s = sinθ_i / λ.

References
----------
.. [1] A. Krywonos, J. E. Harvey, N. Choi, "Linear systems formulation of scattering theory for rough surfaces
   with arbitrary incident and scattering angles", JOSA A 28(6), 1121–1138, 2011 (relevant roughness).
.. [2] J. E. Harvey, N. Choi, S. Schröder, A. Duparré, "Total integrated scatter from surfaces with arbitrary
   roughness, correlation widths, and incident angles", Opt. Eng. 51(1) 013402, 2012.
"""
from __future__ import annotations

import dataclasses
import functools
import math
import threading
from dataclasses import dataclass, field

import numpy as np
from scipy import integrate

from ..surfaces.heightfield import HeightField
from ..surfaces.psd import PSDModel
from ..surfaces.statistics import detrended
from .band_energy import BandAlbedos
from .models import get_model
from .series import M_MAX, poisson_weights, roughness_g, series_tables, series_terms

__all__ = ["band_arc", "relevant_variance", "relevant_variance_of_field", "beyond_band_fraction", "SIN_NODES",
           "relevant_variances", "relevant_sigma2", "band_correlation", "BandSeries", "band_series",
           "band_series_built", "series_arrays", "scattered_lobe"]


def band_arc(r, sin_theta_i, wavelength_nm):
    """Angle (radians, 0 … 2π) of the circle |f| = r (1/m) that lies inside the propagating band."""
    R = 1.0 / (np.asarray(wavelength_nm, dtype=float) * 1e-9)
    s = np.asarray(sin_theta_i, dtype=float) * R
    r = np.asarray(r, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos_half = (r * r + s * s - R * R) / (2 * r * s)
    arc = 2 * np.arccos(np.clip(np.nan_to_num(cos_half, nan=-1.0), -1.0, 1.0))
    # guard: s = 0 (normal incidence) or r = 0 make the ratio undefined: inside ⇔ r + s ≤ R there
    return np.where(r + s <= R, 2 * np.pi, np.where(r >= R + s, 0.0, arc))


def relevant_variance(model: PSDModel, wavelength_nm: float, sin_theta_i: float) -> float:
    """σ_rel² (m²): the height variance of *model* inside the propagating band at (λ, sinθ_i).

    The radial integral ∫ S(r) arc(r) r dr is split at the band's edges (r = 1/λ − s and 1/λ + s), where its
    integrand has kinks, and integrated adaptively (scipy.integrate.quad, relative tolerance 1e-10).
    """
    R = 1.0 / (float(wavelength_nm) * 1e-9)
    s = float(sin_theta_i) * R
    edges = sorted({0.0, max(R - s, 0.0), R + s})

    def integrand(r):
        return float(model.S(r)) * float(band_arc(r, sin_theta_i, wavelength_nm)) * r

    total = 0.0
    scale = 1.0 / model.length_scale
    for a, b in zip(edges[:-1], edges[1:]):
        if b <= a:
            continue
        # the PSD falls off on the scale 1/T (or 1/B): tell quad where its knee is
        pts = [x for x in (0.1 * scale, scale, 10 * scale) if a < x < b]
        val, _ = integrate.quad(integrand, a, b, points=pts or None, limit=400, epsrel=1e-10, epsabs=0.0)
        total += val
    return total


def relevant_variance_of_field(hf: HeightField, wavelength_nm: float, sin_theta_i: float,
                               phi_i_deg: float = 0.0) -> float:
    """σ_rel² (m²) of a height field: the periodogram of its detrended heights summed over the band.

    By Parseval the sum over all frequencies is the field's variance; a periodic field (no window) gives the
    exact split, a masked or non-periodic one the split of its samples as they are.
    """
    h = detrended(hf)
    ny, nx = hf.shape
    valid = hf.valid
    n = int(valid.sum())
    P = np.abs(np.fft.fft2(np.where(valid, h, 0.0))) ** 2 / (n * nx * ny)
    fy = np.fft.fftfreq(ny, hf.dy)[:, None]
    fx = np.fft.fftfreq(nx, hf.dx)[None, :]
    R = 1.0 / (float(wavelength_nm) * 1e-9)
    c = float(sin_theta_i) * R
    phi = math.radians(phi_i_deg)
    inside = np.hypot(fx + c * math.cos(phi), fy + c * math.sin(phi)) <= R
    inside[0, 0] = False  # the mean is not roughness
    return float(np.sum(P[inside]))


def beyond_band_fraction(sigma2_total: float, sigma2_band: float) -> float:
    """(σ² − σ_rel²) / σ²: the share of the height variance that does not scatter (0 for a flat surface)."""
    if sigma2_total <= 0:
        return 0.0
    # guard: quadrature round-off can put σ_rel² a hair (1e-10 relative) above σ²
    return max(0.0, 1.0 - sigma2_band / sigma2_total)


# --- the band-limited Kirchhoff series ---------------------------------------------------------------------------

#: sinθ nodes at which σ_rel² and the in-band share of the multiple-order terms are tabulated (linear in between)
SIN_NODES = 65

#: radial quadrature points of the band integrals (geometric from far below the PSD's knee to twice the band radius)
RADIAL_POINTS = 6000


def _radial_grid(model: PSDModel, R: float) -> np.ndarray:
    lo = min(1e-3 / model.length_scale, 1e-4 * R)
    return np.concatenate([[0.0], np.geomspace(lo, 2.0 * R, RADIAL_POINTS)])


def _trapz(y, x, axis=-1):
    return integrate.trapezoid(y, x, axis=axis)


def relevant_variances(model: PSDModel, wavelength_nm: float, sin_theta) -> np.ndarray:
    """σ_rel² (m²) at every sinθ_i of *sin_theta* at once: the radial band integral ∫ S(r) arc(r) r dr on one fine
    geometric grid (trapezoid rule; against :func:`relevant_variance`'s adaptive quadrature: < 1e-5 relative)."""
    R = 1.0 / (float(wavelength_nm) * 1e-9)
    r = _radial_grid(model, R)
    # S ∝ σ²: integrate the unit-σ PSD and scale (guard: σ² underflows to 0 below 1e-154 m, the shape does not)
    w = np.asarray(dataclasses.replace(model, sigma=1.0).S(r), dtype=float) * r
    s = np.atleast_1d(np.asarray(sin_theta, dtype=float))
    return _trapz(w[None, :] * band_arc(r[None, :], s[:, None], wavelength_nm), r) * model.sigma ** 2


@functools.lru_cache(maxsize=256)
def sigma2_nodes(model: PSDModel, wavelength_nm: float) -> np.ndarray:
    return relevant_variances(model, wavelength_nm, np.linspace(0.0, 1.0, SIN_NODES))


def relevant_sigma2(model: PSDModel, wavelength_nm: float, sin_theta) -> np.ndarray:
    """σ_rel² (m²) at any sinθ_i: :func:`relevant_variances` at :data:`SIN_NODES` nodes (cached per model and λ),
    interpolated linearly (the band's share changes smoothly with θ_i)."""
    nodes = np.linspace(0.0, 1.0, SIN_NODES)
    return np.interp(np.clip(np.asarray(sin_theta, dtype=float), 0.0, 1.0), nodes,
                     sigma2_nodes(model, float(wavelength_nm)))


def band_correlation(model: PSDModel, wavelength_nm: float, r) -> np.ndarray:
    """c_b(r): the normalized autocorrelation of the surface band-limited to |f| ≤ 1/λ, the propagating band at
    normal incidence (1 at r = 0), by the Hankel transform 2π ∫₀^{1/λ} S(f) J0(2π f r) f df / σ_b².

    The f integral is Gauss-Legendre quadrature on panels of :data:`BAND_GL_NODES` nodes, each panel at most
    four periods of J0(2π f r_max) wide and half the PSD's knee 1/ℓ: against a midpoint rule of ≥ 32 000 points,
    within 2e-7 (1e-9 for most PSDs) where the midpoint rule of 16 points per period it replaces was within
    1e-6-2e-5, with 3-6x fewer Bessel evaluations.

    References
    ----------
    .. [1] R. N. Bracewell, *The Fourier Transform and its Applications*, 3rd ed., 2000, ch. 12 (the Hankel
       transform of a circularly symmetric function).
    .. [2] W. H. Press et al., *Numerical Recipes*, 3rd ed., 2007, §4.6 (Gauss-Legendre quadrature).
    """
    from scipy import special

    R = 1.0 / (float(wavelength_nm) * 1e-9)
    r = np.asarray(r, dtype=float)
    f, w = _gauss_legendre_panels(R, min(4.0 / max(float(r.max()), 1e-30), 0.5 / model.length_scale, R / 4.0))
    w = w * np.asarray(dataclasses.replace(model, sigma=1.0).S(f), dtype=float) * 2 * np.pi * f   # shape only
    out = np.empty_like(r)
    for a in range(0, r.size, 512):
        out[a:a + 512] = special.j0(2 * np.pi * np.outer(r[a:a + 512], f)) @ w
    return out / w.sum()


#: Gauss-Legendre nodes per panel of :func:`band_correlation`'s frequency integral
BAND_GL_NODES = 16


def _gauss_legendre_panels(upper: float, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of Gauss-Legendre quadrature on [0, *upper*] split into equal panels no wider than
    *width*, :data:`BAND_GL_NODES` nodes each."""
    x, wx = np.polynomial.legendre.leggauss(BAND_GL_NODES)
    edges = np.linspace(0.0, upper, int(math.ceil(upper / width)) + 1)
    a, b = edges[:-1, None], edges[1:, None]
    return (0.5 * (b - a) * x + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * wx).ravel()


@dataclass(frozen=True, eq=False)
class BandSeries(BandAlbedos):
    """The Kirchhoff series of a surface band-limited to the propagating frequencies, at one wavelength
    (docs/physics.md §9): the coherent reduction and the diffracted lobe see the same roughness, σ_rel.

    For the direction pair (ω_i, ω_o), with g = (k σ_rel c)², c the diffraction model's cos_sum and σ_rel² the
    variance inside the band (the mean of its values at θ_i and θ_o, which keeps the lobe reciprocal; both are the
    same at the mirror direction),

        Σ = g e^{−g} S(q/2π) / σ_rel²  +  K(g, θ_i, θ_o) Σ_{m≥2} p_m(g) H_m^b(q),

    * the first-order term is the PSD itself: every propagating direction lies inside the band, so it holds
      exactly p_1(g) of the light over the band (Rayleigh-Rice to first order);
    * H_m^b (m ≥ 2) are the Hankel transforms of c_b^m, c_b the correlation of the surface band-limited at
      normal incidence (|f| ≤ 1/λ, :func:`band_correlation`). Their convolutions reach beyond the band: the
      Kirchhoff series sends that share of the multiple-order light into evanescent waves, which carry no energy.
      K = Σ p_m / Σ p_m B_m (B_m the share of H_m^b inside the true, off-centre band of θ_i) returns it to the
      propagating directions in proportion to the series' own shape, as the generalized Harvey-Shack theory
      renormalizes its scatter (Krywonos, Harvey & Choi 2011). Its size is reported
      (:meth:`redistributed_share`).

    The isotropic band of normal incidence approximates the off-centre band of oblique incidence only in the shape
    of the m ≥ 2 terms (their energy is fixed by K). The tables are checked against the same band-limited surface
    built with Cartesian FFTs (tests/test_band.py: H_2^b within 2 %, B_2 within 5e-3).

    References
    ----------
    .. [1] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness, renormalized
       scatter).
    .. [2] P. Beckmann, A. Spizzichino, 1963, ch. 5 (the series).
    """

    model: PSDModel
    wavelength_nm: float
    sin_nodes: np.ndarray
    sigma2: np.ndarray          # σ_rel² at sin_nodes, m²
    m_max: int | None = None    # series terms (None: those the largest g = (2kσ)² needs)
    n_q: int = 512              # q nodes of the tables
    _albedos: dict = field(default_factory=dict, repr=False)   # diffraction model name -> E¹ at ALBEDO_THETAS_DEG
    _lock: object = field(default_factory=threading.Lock, init=False, repr=False, compare=False)

    # The tables of the series, computed on first use (:func:`series_arrays`, ~0.2 s CPU a wavelength): the
    # albedo tables (``_albedos``) of a series may be known without them (read from a cache by the caller).
    @property
    def _arrays(self) -> dict:
        # computed once, under this series' own lock: functools.cached_property (before Python 3.12) holds one lock
        # shared by every instance, so threads building the series of different wavelengths waited for each other
        got = self.__dict__.get("_series_arrays")
        if got is None:
            with self._lock:
                got = self.__dict__.get("_series_arrays")
                if got is None:
                    got = series_arrays(self.model, self.wavelength_nm, self.sin_nodes, self.sigma2, self.m_max,
                                        self.n_q)
                    self.__dict__["_series_arrays"] = got   # a frozen dataclass: kept beside its fields
        return got

    @property
    def q(self) -> np.ndarray:
        """Frequency nodes |q| (rad/m) of the tables."""
        return self._arrays["q"]

    @property
    def H(self) -> np.ndarray:
        """H_m^b for m = 2..m_max (m_max − 1, n_q), m²."""
        return self._arrays["H"]

    @property
    def inband(self) -> np.ndarray:
        """B_m at sin_nodes (m_max − 1, n_nodes)."""
        return self._arrays["inband"]

    @property
    def x(self) -> np.ndarray:
        """√g nodes of the look-up tables."""
        return self._arrays["x"]

    @property
    def rest(self) -> np.ndarray:
        """Σ_{m≥2} p_m(g) H_m^b(q) at (x, q), m²."""
        return self._arrays["rest"]

    @property
    def K(self) -> np.ndarray:
        """K(g, θ_i) at (x, sin_nodes)."""
        return self._arrays["K"]

    @property
    def k(self) -> float:
        return 2 * np.pi / (self.wavelength_nm * 1e-9)

    def sigma2_rel(self, sin_theta) -> np.ndarray:
        """σ_rel² (m²) at sinθ (interpolated between :data:`SIN_NODES` nodes)."""
        return np.interp(np.clip(np.asarray(sin_theta, dtype=float), 0.0, 1.0), self.sin_nodes, self.sigma2)

    def _K(self, g, sin_i):
        """K(g, θ_i) of the class doc, exactly (per point: Σ_m over the tabulated terms)."""
        g = np.asarray(g, dtype=float)
        m_use = min(self.H.shape[0] + 1, _series_terms(float(np.max(g)) if g.size else 0.0))
        if m_use < 2:
            return np.ones_like(g)
        p = _poisson(g, m_use)[1:]                                        # m = 2..m_use
        B = np.stack([np.interp(np.clip(sin_i, 0, 1), self.sin_nodes, self.inband[j]) for j in range(m_use - 1)])
        num, den = p.sum(axis=0), (p * B).sum(axis=0)
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)

    def terms(self, q, cos_sum, sigma2, sin_i, sin_o, exact: bool = False):
        """Σ (m²) of the class doc at frequency |q| (rad/m) for the model's *cos_sum* and the variance *sigma2*
        (m²) seen by the pair (arrays broadcast).

        The multiple-order part and K are looked up bilinearly in tables over (√g, q) and (√g, sinθ) built with the
        series (a look-up costs the same for any number of terms); *exact* sums the terms instead (measured: the
        two agree within 2e-3 of the lobe wherever it exceeds 1e-4 of its peak, tests/test_band.py).
        """
        q = np.asarray(q, dtype=float)
        c2 = self.k ** 2 * np.asarray(cos_sum, dtype=float) ** 2
        g = c2 * np.asarray(sigma2, dtype=float)
        # the first-order term g e^{-g} S / σ_rel² = (k c)² e^{-g} S, written without the division (σ → 0)
        first = c2 * np.exp(-g) * self.model.S(q / (2 * np.pi))
        if self.H.shape[0] == 0:
            return first
        if not exact:
            x = np.sqrt(np.maximum(g, 0.0))
            rest = _bilinear(self.rest, self.x, x, self.q, q, outside=0.0)
            K = 0.5 * (_bilinear(self.K, self.x, x, self.sin_nodes, sin_i)
                       + _bilinear(self.K, self.x, x, self.sin_nodes, sin_o))
            return first + K * rest
        m_use = min(self.H.shape[0] + 1, _series_terms(float(np.max(g)) if g.size else 0.0))
        if m_use < 2:
            return first
        p = _poisson(g, m_use)[1:]
        Hm = np.stack([np.interp(q, self.q, self.H[j], right=0.0) for j in range(m_use - 1)])
        rest = np.sum(p * Hm, axis=0)
        K = 0.5 * (self._K(g, sin_i) + self._K(g, sin_o))
        return first + K * rest

    def __call__(self, wi, wo, cos_sum, q=None):
        """Σ (m²) for direction pairs (..., 3) with the diffraction model's *cos_sum* (array)."""
        wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
        if q is None:
            s = wi + wo
            q = self.k * np.hypot(s[..., 0], s[..., 1])
        sin_i = np.hypot(wi[..., 0], wi[..., 1])
        sin_o = np.hypot(wo[..., 0], wo[..., 1])
        sigma2 = 0.5 * (self.sigma2_rel(sin_i) + self.sigma2_rel(sin_o))
        return self.terms(q, cos_sum, sigma2, sin_i, sin_o)

    def redistributed_share(self, sin_theta_i, cos_sum) -> float:
        """Share of the scattered light (1 − e^{−g}) that the multiple-order terms would send beyond the band and
        K returns to it, at the mirror direction of θ_i (g = (k σ_rel c)² with that *cos_sum*)."""
        s = float(sin_theta_i)
        g = float(self.k ** 2 * self.sigma2_rel(s) * float(cos_sum) ** 2)
        m_use = min(self.H.shape[0] + 1, _series_terms(g))
        if g <= 0 or m_use < 2:
            return 0.0
        p = _poisson(np.asarray(g), m_use)[1:]
        B = np.array([np.interp(s, self.sin_nodes, self.inband[j]) for j in range(m_use - 1)])
        return float(np.sum(p * (1.0 - B)) / -math.expm1(-g))


def _bilinear(table, xs, x, ys, y, outside=None):
    """table[ix, iy] at (x, y) by bilinear interpolation on uniform node arrays *xs*, *ys* (x clamped to its range;
    y beyond the last node gives *outside* when given, else the edge value). The four corners are read from the
    flattened table by one linear index each (a gather ~4x faster than a two-index one on large point sets)."""
    y_raw = np.asarray(y, dtype=float)
    fx = np.clip((np.asarray(x, dtype=float) - xs[0]) * (1.0 / (xs[1] - xs[0])), 0.0, xs.size - 1)
    ix = np.minimum(fx.astype(np.intp), xs.size - 2)
    tx = fx - ix
    fy = np.clip((y_raw - ys[0]) * (1.0 / (ys[1] - ys[0])), 0.0, ys.size - 1)
    iy = np.minimum(fy.astype(np.intp), ys.size - 2)
    ty = fy - iy
    ny = table.shape[1]
    flat = np.ascontiguousarray(table).ravel()
    k = ix * ny + iy
    low = flat.take(k)
    low += ty * (flat.take(k + 1) - low)
    high = flat.take(k + ny)
    high += ty * (flat.take(k + ny + 1) - high)
    v = low + tx * (high - low)
    return v if outside is None else np.where(y_raw <= ys[-1], v, outside)


def _series_terms(g, m_max=None):
    return series_terms(g, M_MAX if m_max is None else m_max)


def _poisson(g, m_use):
    return poisson_weights(g, m_use)


def band_series(model: PSDModel, wavelength_nm: float, m_max: int | None = None, n_q: int = 512) -> BandSeries:
    """:class:`BandSeries` of *model* at *wavelength_nm* (nm), built once per (model, λ, m_max, n_q) and cached
    (:func:`band_series_cached`)."""
    return band_series_cached(model, float(wavelength_nm), None if m_max is None else int(m_max), int(n_q))


def band_series_built(model: PSDModel, wavelengths_nm, workers: int | None = None) -> list:
    """:func:`band_series` of *model* at each of *wavelengths_nm* (nm), each with its tables (:func:`series_arrays`,
    ~0.2 s CPU a wavelength) built: the wavelengths in parallel threads (:func:`waveoptics.runtime.parallel_map`,
    *workers*), where their first use one after the other would build them in turn. The tables are those a serial
    build gives, bit for bit (each depends on its own wavelength only)."""
    from ..runtime import parallel_map

    def built(lam):
        bs = band_series(model, lam)
        bs.q   # noqa: B018 - builds the tables
        return bs

    return parallel_map(built, [float(x) for x in np.atleast_1d(wavelengths_nm)], workers)


#: band series kept in memory (~5 MB each, the look-up tables): more than the wavelength nodes one model is built
#: at (a renderer's 25 at the default 20 nm step, 48 at 10 nm), since callers loop over all of them per incidence and
#: an LRU cache smaller than such a loop is evicted on every call: at 24 entries and 25 nodes every look-up missed
#: and rebuilt its series (the render's default model, 2 of its 20 incidences: not done after 20 min on a busy
#: 2-core machine; 24 s CPU with every series kept, the whole model 52 s CPU)
BAND_CACHE_SIZE = 50


@functools.lru_cache(maxsize=BAND_CACHE_SIZE)
def band_series_cached(model: PSDModel, wavelength_nm: float, m_max: int | None, n_q: int) -> BandSeries:
    """:class:`BandSeries` of *model* at *wavelength_nm* (nm), built once and cached; its tables
    (:func:`series_arrays`) are computed on first use."""
    lam = float(wavelength_nm)
    return BandSeries(model=model, wavelength_nm=lam, sin_nodes=np.linspace(0.0, 1.0, SIN_NODES),
                      sigma2=sigma2_nodes(model, lam), m_max=m_max, n_q=int(n_q))


def series_arrays(model: PSDModel, wavelength_nm: float, nodes, sigma2, m_max: int | None, n_q: int) -> dict:
    """The tables of :class:`BandSeries` (``q``, ``H``, ``inband``, ``x``, ``rest``, ``K``) of *model* at
    *wavelength_nm* (nm), with σ_rel² *sigma2* at the sinθ_i *nodes*.

    The tables hold H_m^b for m = 2..m_max (by default the terms the largest g = (2kσ)² needs), on q ≤ 2k (every
    reflected direction) from the trapezoid Hankel transform of c_b^m on r ≤ max(12 ℓ, 60 λ) (ℓ the PSD's length
    scale), and B_m at :data:`SIN_NODES` values of sinθ_i by the arc-weighted radial integral of H_m^b.
    """
    from scipy import special

    lam = float(wavelength_nm)
    k = 2 * np.pi / (lam * 1e-9)
    g_max = (2 * k * model.sigma) ** 2
    m_use = _series_terms(g_max) if m_max is None else int(m_max)
    L = model.length_scale
    r_max = max(12.0 * L, 60.0 * lam * 1e-9)
    n_r = int(min(max(r_max / (lam * 1e-9 / 16.0), r_max / (L / 40.0), 400), 12000))
    r = np.linspace(0.0, r_max, n_r)
    dr = r[1] - r[0]
    wr = np.full(n_r, dr)
    wr[0] = wr[-1] = 0.5 * dr
    c = band_correlation(model, lam, r)
    q = np.linspace(0.0, 2.0 * k * 1.001, int(n_q))
    J = special.j0(np.outer(q, r)) * (2 * np.pi * r * wr)
    end_fix = 2 * np.pi * dr ** 2 / 12      # Euler-Maclaurin correction of the r = 0 end (as series_tables)
    # c_b^m for m = 2..m_use as the columns of one matrix: every H_m in one pass over J (a product per term read
    # the (n_q, n_r) matrix m_use − 1 times)
    powers = np.empty((n_r, max(m_use - 1, 0)))
    cm = c.copy()
    for j in range(m_use - 1):
        cm = cm * c
        powers[:, j] = cm
    # guard: H_m ≥ 0 (Bochner); negatives are quadrature noise
    H = np.ascontiguousarray(np.maximum((J @ powers).T + end_fix, 0.0))
    # B_m: the share of H_m^b in the off-centre band of each θ_i (f = q / 2π)
    f = q / (2 * np.pi)
    arc = band_arc(f[None, :], nodes[:, None], lam)                       # (nodes, n_q)
    # H_m^b holds unit mass over the whole plane (c_b^m(0) = 1); the table stops at 2k, so the in-band mass is
    # the share itself
    # guard: quadrature round-off may put a share a hair outside [0, 1]
    inband = np.clip(_trapz(H[:, None, :] * (arc * f)[None, :, :], f), 0.0, 1.0)   # (m − 1, nodes)
    # look-up tables over √g (g up to the largest the band allows; √g is proportional to cos_sum)
    x = np.linspace(0.0, 2.0 * k * math.sqrt(max(float(sigma2.max()), 0.0)) * 1.0001 + 1e-12, 1025)
    if H.shape[0]:
        p = _poisson(x ** 2, H.shape[0] + 1)[1:]                           # (m − 1, n_x), m = 2..
        rest = p.T @ H                                                      # (n_x, n_q)
        num = p.sum(axis=0)[:, None]
        den = p.T @ inband                                                  # (n_x, nodes)
        Ktab = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
    else:
        rest, Ktab = np.zeros((x.size, q.size)), np.ones((x.size, nodes.size))
    return dict(q=q, H=H, inband=inband, x=x, rest=rest, K=Ktab)


def scattered_lobe(wi, wo, wavelength_nm, model: PSDModel, F=1.0, *, m_max: int = M_MAX, return_captured=False,
                   diffraction="kirchhoff", band_limited: bool = True):
    """BRDF (1/sr) of the diffusely scattered part for the PSD *model* (the series of the module doc, with the
    factor K and the vertical phase of the *diffraction* model, :mod:`waveoptics.scatter.models`).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit vectors towards the light and the viewer (macro normal = z).
    wavelength_nm : array_like
        Vacuum wavelength(s) in nm, broadcast against the direction arrays' leading shape.
    model : PSDModel
        Height statistics.
    F : array_like
        Fresnel reflectance at the half-vector angle (broadcast), 1 by default.
    m_max : int
        Number of series terms.
    return_captured : bool
        Also return Σ_{m≤m_max} p_m(g) / (1 − e^{−g}), the fraction of the scattered energy the truncated
        series holds (1 when converged).
    diffraction : str or DiffractionModel
        ``kirchhoff`` (default), ``ghs``, ``rghs``, ``ohs`` or ``rohs``.
    band_limited : bool
        True (default): the series of the roughness inside the propagating band, σ_rel
        (:class:`waveoptics.scatter.band.BandSeries`, docs/physics.md §9); the two-scale model's coherent
        fraction (:meth:`waveoptics.brdf.Nano.coherent_fraction`) is the complement of the light this lobe
        scatters, so the two add up to the reflected light.
        False: the classical series with the full σ (Beckmann & Spizzichino), whose coherent reduction also
        removes the variance in evanescent frequencies, which cannot scatter.

    Returns
    -------
    ndarray
        f_s, zero where either direction is below the surface.
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    lam = np.asarray(wavelength_nm, dtype=float)
    k = 2 * np.pi / (lam * 1e-9)
    s = wi + wo
    q = k * np.hypot(s[..., 0], s[..., 1])
    dm = get_model(diffraction)
    g = roughness_g(model.sigma, dm.cos_sum(wi, wo), lam)
    if model.sigma == 0:
        out = np.zeros(np.broadcast(q, g).shape)
        return (out, np.ones_like(out)) if return_captured else out
    if band_limited:
        c = dm.cos_sum(wi, wo)
        lam_b, q_b, c_b = np.broadcast_arrays(lam, q, c)
        wi_b = np.broadcast_to(wi, q_b.shape + (3,))
        wo_b = np.broadcast_to(wo, q_b.shape + (3,))
        total = np.empty(q_b.shape)
        g_b = np.empty(q_b.shape)
        for l_val in np.unique(lam_b):
            sel = lam_b == l_val
            bs = band_series(model, float(l_val), None if m_max == M_MAX else m_max)
            total[sel] = bs(wi_b[sel], wo_b[sel], c_b[sel], q=q_b[sel])
            sin_i = np.hypot(wi_b[sel][..., 0], wi_b[sel][..., 1])
            sin_o = np.hypot(wo_b[sel][..., 0], wo_b[sel][..., 1])
            g_b[sel] = bs.k ** 2 * 0.5 * (bs.sigma2_rel(sin_i) + bs.sigma2_rel(sin_o)) * c_b[sel] ** 2
        val = np.asarray(F) * dm.K(wi, wo, lam) * total
        if return_captured:
            m_use = series_terms(float(np.max(g_b)) if g_b.size else 0.0, m_max)
            with np.errstate(invalid="ignore", divide="ignore"):
                captured = np.where(g_b > 0, poisson_weights(g_b, m_use).sum(axis=0) / -np.expm1(-g_b), 1.0)
            return val, captured
        return val
    # round the table range up to a power of two so that one table serves a whole spectrum (cache hit)
    q_max = 2.0 ** math.ceil(math.log2(float(np.max(q)) * 1.001 + 1.0))
    tab = series_tables(model, q_max, m_max)
    q_b, g_b = np.broadcast_arrays(q, g)
    m_use = series_terms(float(np.max(g_b)) if g_b.size else 0.0, m_max)
    p = poisson_weights(g_b, m_use)
    Hm = tab.Hm(q_b)[:m_use]
    total = np.sum(p * Hm, axis=0)
    val = np.asarray(F) * dm.K(wi, wo, lam) * total
    if return_captured:
        with np.errstate(invalid="ignore", divide="ignore"):
            captured = np.where(g_b > 0, p.sum(axis=0) / -np.expm1(-g_b), 1.0)
        return val, captured
    return val
