"""Export a BRDF to the RGL tabulated-BSDF format (``.bsdf``) read by Mitsuba 3's and pbrt-v4's ``measured`` models.

The format (Dupuy & Jakob 2018; Mitsuba 3 ``src/bsdfs/measured.cpp``, pbrt-v4 ``MeasuredBxDF``) stores a BRDF in
coordinates warped by its own visible-normal distribution, so a coarse grid holds a sharp lobe:

* ``ndf`` (n_φ, n_θ): the NDF D(m) (1/sr) on a grid of the unit square u = (√(2θ_m/π), (φ_m + π)/2π);
* ``sigma`` (n_φ, n_θ): the projected area σ(ω_i) = ∫ D(m) ⟨ω_i·m⟩ dm on the same kind of grid over ω_i;
* ``vndf`` (n_φi, n_θi, n, n): per incidence node, the density of u_m of the visible normals
  D(m) ⟨ω_i·m⟩ / σ(ω_i) times the Jacobian 2π² u_θ sin θ_m of the u parametrization (normalized by the reader);
* ``spectra`` (n_φi, n_θi, n_λ, n, n) and ``luminance`` (n_φi, n_θi, n, n): the BRDF on a regular grid of the
  *primary sample space* of that warp: at a sample point s, m = m(u_m(s)), ω_o = reflect(ω_i, m) and, with the
  ``jacobian`` flag set, the stored value is f(ω_i, ω_o, λ) cos θ_o · 4 σ(ω_i) / D(m) (the reader multiplies by
  D/(4σ)); the luminance (CIE Y weights of the wavelengths) is the sampling density of s;
* ``theta_i``, ``phi_i``, ``wavelengths`` (nm), ``description``, ``jacobian``. Two azimuth nodes mean an isotropic
  BRDF (azimuths of m relative to ω_i's); an anisotropic one has azimuth nodes over [−π, π].

No measurement is simulated: D comes from the model's retro-reflection, D(m) ∝ f_Y(m, m) cos² θ_m as Dupuy &
Jakob estimate it from a goniophotometer (§4), mixed with 0.1 % of the uniform NDF 1/π so that every half-vector
has a positive density (sampling must reach every direction where f > 0); σ is its exact integral. The warps
are Mitsuba 3's own ``MarginalContinuous2D0`` (the class ``measured`` builds from the file), so the sample points
land exactly where the reader looks them up. Accuracy against the model (median relative error of eval, albedo)
is measured in ``tests/test_renderers.py`` and written in docs/renderers.md.

References
----------
.. [1] J. Dupuy, W. Jakob, "An Adaptive Parameterization for Efficient Material Acquisition and Rendering",
   ACM TOG 37(6), 274, 2018 (SIGGRAPH Asia).
.. [2] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014
   (projected area σ and the visible-normal distribution).
.. [3] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 2023, §9.8 (measured BSDFs).
"""
from __future__ import annotations

import contextlib
import io as _io
from dataclasses import dataclass

import numpy as np

from .. import colour
from ..brdf import roughness_scales
from ..errors import FieldError

__all__ = ['RGLGrid', 'export_rgl', 'read_back_eval', 'read_back_albedo', 'sigma_table', 'u2theta', 'u2phi', 'theta2u', 'phi2u', 'UNIFORM_NDF_SHARE']

#: share of the uniform NDF 1/π in the warp's NDF (positivity of the sampling density)
UNIFORM_NDF_SHARE = 1e-3


def u2theta(u):
    """θ = u² π/2 (the format's elevation coordinate)."""
    return np.asarray(u) ** 2 * (np.pi / 2)


def u2phi(u):
    """φ = (2u − 1) π."""
    return (2.0 * np.asarray(u) - 1.0) * np.pi


def theta2u(theta):
    return np.sqrt(np.asarray(theta) * (2.0 / np.pi))


def phi2u(phi):
    return (np.asarray(phi) + np.pi) / (2.0 * np.pi)


def _sph(theta, phi):
    st = np.sin(theta)
    return np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], axis=-1)


@dataclass(frozen=True)
class RGLGrid:
    """Resolutions of an export.

    Parameters
    ----------
    n_theta_i : int
        Incidence elevations, evenly spaced from 0 to *theta_i_max_deg*.
    n_phi_i : int
        Incidence azimuths of an anisotropic BRDF over [−180°, 180°] (an isotropic one stores 2).
    resolution : int
        Sample-space grid (n × n) of ``spectra`` and ``luminance``.
    ndf_resolution : int
        Grid of ``ndf``, ``sigma`` and ``vndf`` (n × n).
    theta_i_max_deg : float
        Last incidence node (degrees); the reader extrapolates beyond it.
    """

    n_theta_i: int = 18
    n_phi_i: int = 9
    resolution: int = 32
    ndf_resolution: int = 64
    theta_i_max_deg: float = 89.0

    def __post_init__(self):
        for name, lo in (("n_theta_i", 2), ("n_phi_i", 3), ("resolution", 4), ("ndf_resolution", 8)):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or v < lo or v > 4096:
                raise FieldError(f"{name}={v!r} is not allowed; give an integer in [{lo}, 4096]", name)
        if not 0 < self.theta_i_max_deg < 90:
            raise FieldError(f"theta_i_max_deg={self.theta_i_max_deg!r} is not allowed; it must be in (0, 90)",
                             "theta_i_max_deg")


def _mitsuba():
    """Mitsuba 3 with the variant already set (any: the warps run in scalar and JIT variants), else scalar_rgb;
    a missing installation is one line naming the extra (:func:`waveoptics.renderers.mitsuba.load_mitsuba`)."""
    from .mitsuba import load_mitsuba

    try:
        import mitsuba as mi
    except ImportError:
        return load_mitsuba("scalar_rgb")
    return mi if mi.variant() is not None else load_mitsuba("scalar_rgb")


def _points(mi, xy):
    xy = np.asarray(xy, dtype=np.float32)
    return mi.Point2f(np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1]))


def _map(mi, fn, xy, outputs=1):
    """Apply a Mitsuba warp method to points xy (n, 2): vectorized in JIT variants, a loop in scalar ones."""
    if mi.variant().startswith("scalar"):
        res = [fn(mi.Point2f(float(a), float(b))) for a, b in np.asarray(xy, dtype=float)]
        if outputs == 1:
            return np.array([float(r) for r in res])
        return (np.array([[float(r[0][0]), float(r[0][1])] for r in res]), np.array([float(r[1]) for r in res]))
    res = fn(_points(mi, xy))
    if outputs == 1:
        return np.array(res, dtype=float)
    return np.array(res[0], dtype=float).T, np.array(res[1], dtype=float)


def _luminance_weights(wavelengths):
    return colour.tristimulus_weights(wavelengths)[:, 1]


def _ndf_table(model, grid_n, wY, isotropic):
    """D(m) on the (φ_m, θ_m) vertex grid (n, n), from the model's retro-reflection, normalized so that
    ∫ D cos θ_m dm = 1, with the uniform share added."""
    u = np.linspace(0.0, 1.0, grid_n)
    th, ph = u2theta(u)[None, :], u2phi(u)[:, None]
    if isotropic:
        ph = np.zeros_like(ph)
    m = _sph(np.broadcast_to(th, (grid_n, grid_n)), np.broadcast_to(ph, (grid_n, grid_n))).reshape(-1, 3)
    ok = m[:, 2] > 1e-6
    m_ok = np.where(ok[:, None], m, [0.0, 0.0, 1.0])
    f = model.eval_spectrum(m_ok, m_ok) @ wY
    D = np.where(ok, np.maximum(f, 0.0) * m[:, 2] ** 2, 0.0).reshape(grid_n, grid_n)
    # normalization by the trapezoid rule over u: dm = 2π² u_θ sin θ du_θ du_φ
    jac = 2 * np.pi ** 2 * u[None, :] * np.sin(u2theta(u))[None, :]
    cos_m = np.cos(u2theta(u))[None, :]
    norm = np.trapezoid(np.trapezoid(D * cos_m * jac, u, axis=1), u)
    if not norm > 0:
        raise FieldError("the BRDF reflects no light at retro-reflection; it cannot be tabulated", "brdf")
    return (1.0 - UNIFORM_NDF_SHARE) * D / norm + UNIFORM_NDF_SHARE / np.pi


#: incidences per block of :func:`_sigma`'s matrix product (a block of 256 × 192² doubles is 75 MB)
_SIGMA_BLOCK = 256


def _sigma(D_warp_eval, mi, wi_dirs, n_quad=192):
    """σ(ω_i) = ∫ D(m) ⟨ω_i·m⟩ dm by the midpoint rule in u over the tabulated (interpolated) NDF."""
    uq = (np.arange(n_quad) + 0.5) / n_quad
    U, V = np.meshgrid(uq, uq)                          # U: θ coordinate, V: φ coordinate
    pts = np.stack([U.ravel(), V.ravel()], axis=-1)
    D = _map(mi, D_warp_eval, pts)
    m = _sph(u2theta(pts[:, 0]), u2phi(pts[:, 1]))
    w = D * 2 * np.pi ** 2 * pts[:, 0] * np.sin(u2theta(pts[:, 0])) / n_quad ** 2
    # in blocks of incidences: the whole (n_i, n_quad²) matrix of ⟨ω_i·m⟩ would take GBs (each row is the same sum);
    # the clamp in place (a second 75 MB block per step doubled the time)
    mt = np.ascontiguousarray(m.T)
    out = []
    for i in range(0, wi_dirs.shape[0], _SIGMA_BLOCK):
        cos = wi_dirs[i:i + _SIGMA_BLOCK] @ mt
        out.append(np.maximum(cos, 0.0, out=cos) @ w)
    return np.concatenate(out)


def sigma_table(D_warp_eval, mi, nn: int, isotropic: bool) -> np.ndarray:
    """σ(ω_i) of :func:`_sigma` on the (φ_i, θ_i) vertex grid (nn, nn) of the format (rows φ_i, columns θ_i).

    An isotropic NDF (every φ row of its table the same) has σ independent of φ_i: the row at φ_i = −π is
    computed and repeated (nn times fewer directions; the other rows of the full grid differ from it only by the
    midpoint rule's φ discretization, measured ≤ 1.2e-4 relative at θ_i = 90° for Beckmann α = 0.1, where both
    are 4.0e-4 from the same rule with 8x the nodes per axis; tests/test_table_shortcuts.py).

    References
    ----------
    .. [1] J. Dupuy, W. Jakob, "An adaptive parameterization for efficient material acquisition and rendering",
       ACM TOG 37(6), 2018 (the projected area σ of the format).
    .. [2] E. Heitz, "Understanding the masking-shadowing function in microfacet-based BRDFs", JCGT 3(2), 2014,
       eq. (2) (σ(ω) = ∫ D(m) ⟨ω·m⟩ dm = cos θ (1 + Λ(ω))).
    """
    u = np.linspace(0.0, 1.0, nn)
    th_s, ph_s = np.meshgrid(u2theta(u), u2phi(u))
    if isotropic:
        row = _sigma(D_warp_eval, mi, _sph(th_s[:1], ph_s[:1]).reshape(-1, 3))
        return np.repeat(row[None, :], nn, axis=0)
    return _sigma(D_warp_eval, mi, _sph(th_s, ph_s).reshape(-1, 3)).reshape(nn, nn)


def export_rgl(model, path, *, grid: RGLGrid = RGLGrid(), description: str = "waveoptics BRDF",
               isotropic: bool | None = None, overwrite: bool = True) -> dict:
    """Write *model* to the RGL ``.bsdf`` file *path* (see the module doc) and return its fields.

    Parameters
    ----------
    model : waveoptics.brdf.SpectralNodes
        The BRDF at its wavelength nodes (``eval_spectrum``); :func:`waveoptics.renderers.renderer_brdf` gives
        one.
    path : str or Path
        Output file (written whole: a temporary file renamed into place).
    grid : RGLGrid
        Resolutions.
    description : str
        Text stored in the file.
    isotropic : bool or None
        Store the isotropic form; None decides from the model (its micro ``alpha_y`` and a height field's
        anisotropy).
    overwrite : bool
        Replace an existing *path* (else :class:`waveoptics.errors.OutputExistsError`).
    """
    from ..io import files
    mi = _mitsuba()
    lam = np.asarray(model.wavelengths_nm, dtype=float)
    wY = _luminance_weights(lam)
    if isotropic is None:
        base = model.base
        isotropic = roughness_scales.isotropic(base.micro, getattr(base, "nano", None))
    n, nn = grid.resolution, grid.ndf_resolution

    ndf = _ndf_table(model, nn, wY, isotropic).astype(np.float32)
    ndf_warp = mi.MarginalContinuous2D0(ndf, normalize=False, enable_sampling=False)

    # projected area on its own (φ_i, θ_i) vertex grid
    u = np.linspace(0.0, 1.0, nn)
    sigma = sigma_table(ndf_warp.eval, mi, nn, isotropic).astype(np.float32)
    sigma_warp = mi.MarginalContinuous2D0(sigma, normalize=False, enable_sampling=False)

    theta_i = np.radians(np.linspace(0.0, grid.theta_i_max_deg, grid.n_theta_i))
    phi_i = np.array([-np.pi, np.pi]) if isotropic else np.linspace(-np.pi, np.pi, grid.n_phi_i)
    n_phi_compute = 1 if isotropic else phi_i.size

    # vertex grid of u_m for the VNDF and of s for the spectra
    um = np.stack(np.meshgrid(u, u), axis=-1).reshape(-1, 2)             # (x=θ, y=φ) per vertex, row = y
    m_grid = _sph(u2theta(um[:, 0]), u2phi(um[:, 1]))
    D_grid = ndf.reshape(-1).astype(float)
    jac_grid = 2 * np.pi ** 2 * um[:, 0] * np.sin(u2theta(um[:, 0]))
    s = np.linspace(0.0, 1.0, n)
    s_pts = np.stack(np.meshgrid(s, s), axis=-1).reshape(-1, 2)

    vndf = np.zeros((n_phi_compute, theta_i.size, nn, nn), dtype=np.float32)
    spectra = np.zeros((n_phi_compute, theta_i.size, lam.size, n, n), dtype=np.float32)
    for a in range(n_phi_compute):
        for b, t in enumerate(theta_i):
            p = 0.0 if isotropic else phi_i[a]
            wi = _sph(np.array(t), np.array(p))
            # an isotropic table has ω_i at azimuth 0, so m's azimuth is already relative to ω_i's
            vndf[a, b] = (D_grid * np.maximum(m_grid @ wi, 0.0) * jac_grid).reshape(nn, nn)
            warp = mi.MarginalContinuous2D0(np.ascontiguousarray(vndf[a, b]))
            u_m, _ = _map(mi, warp.sample, s_pts, outputs=2)
            th_m, ph_m = u2theta(u_m[:, 0]), u2phi(u_m[:, 1]) + (p if isotropic else 0.0)
            m = _sph(th_m, ph_m)
            cos_d = m @ wi
            wo = 2.0 * cos_d[:, None] * m - wi
            ok = (wo[:, 2] > 0) & (cos_d > 0)
            wo_ok = np.where(ok[:, None], wo, [0.0, 0.0, 1.0])
            f = model.eval_spectrum(np.broadcast_to(wi, wo.shape), wo_ok)          # (n², n_λ)
            D_at = _map(mi, ndf_warp.eval, u_m)
            sig = _map(mi, sigma_warp.eval, np.array([[theta2u(t), phi2u(p)]]))[0]
            val = np.where(ok[:, None], f * (wo_ok[:, 2] * 4.0 * sig / np.maximum(D_at, 1e-30))[:, None], 0.0)
            spectra[a, b] = val.T.reshape(lam.size, n, n)
    if isotropic:
        vndf = np.repeat(vndf, 2, axis=0)
        spectra = np.repeat(spectra, 2, axis=0)
    luminance = np.einsum("abkyx,k->abyx", spectra, wY).astype(np.float32)
    if not np.all(np.isfinite(spectra)) or np.any(luminance.reshape(luminance.shape[:2] + (-1,)).sum(-1) <= 0):
        raise FieldError("the BRDF could not be tabulated (a non-finite value or an incidence without reflected "
                         "light)", "brdf")

    fields = dict(description=description, jacobian=np.array([1], dtype=np.uint8),
                  theta_i=theta_i.astype(np.float32), phi_i=phi_i.astype(np.float32),
                  wavelengths=lam.astype(np.float32), ndf=ndf, sigma=sigma, vndf=vndf,
                  luminance=luminance, spectra=spectra.astype(np.float32))
    from mitsuba.python import tensor_io

    with files.atomic_path(path, overwrite=overwrite) as tmp, contextlib.redirect_stdout(_io.StringIO()):
        tensor_io.write(str(tmp), **fields)
    return fields


def _jit_spectral(mi):
    if mi.variant().startswith("scalar") or not mi.is_spectral:
        raise FieldError(f"reading a .bsdf back needs a JIT spectral Mitsuba variant, not {mi.variant()!r}",
                         "variant")


def read_back_eval(mi, path, wi, wo, wavelength_nm: float) -> np.ndarray:
    """f (n,) in 1/sr of the file *path* as Mitsuba 3's own ``measured`` model evaluates it, at direction pairs
    wi, wo (n, 3) and one wavelength (nm); *mi* is Mitsuba with a JIT spectral variant set. For checking an
    export against its model."""
    import drjit as dr

    _jit_spectral(mi)
    wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
    n = wi.shape[0]
    b = mi.load_dict({"type": "measured", "filename": str(path)})
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T.astype(np.float32)))
    si.wavelengths = mi.Spectrum(*[mi.Float(np.full(n, wavelength_nm, dtype=np.float32))] * 4)
    v = b.eval(mi.BSDFContext(), si, mi.Vector3f(np.ascontiguousarray(wo.T.astype(np.float32))))
    return np.array(v, dtype=float).reshape(-1, n)[0] / wo[:, 2]


def read_back_albedo(mi, path, wi, wavelength_nm: float, *, samples: int = 200_000, seed: int = 0) -> float:
    """Directional albedo of the file *path* for one incidence wi (3,): the mean sample weight of Mitsuba 3's own
    ``measured`` sampler over *samples* seeded uniform numbers (its standard error is about 0.1 % at 200 000)."""
    import drjit as dr

    _jit_spectral(mi)
    b = mi.load_dict({"type": "measured", "filename": str(path)})
    si = dr.zeros(mi.SurfaceInteraction3f, samples)
    si.wi = mi.Vector3f(*[float(x) for x in wi])
    si.wavelengths = mi.Spectrum(*[mi.Float(np.full(samples, wavelength_nm, dtype=np.float32))] * 4)
    u = np.random.default_rng(seed).random((3, samples)).astype(np.float32)
    _, weight = b.sample(mi.BSDFContext(), si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    return float(np.mean(np.array(weight, dtype=float).reshape(-1, samples)[0]))
