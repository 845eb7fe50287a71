"""The polarized diffracted part of the Dr.Jit two-scale BSDF (``waveoptics_native`` in
``llvm_ad_spectral_polarized``; :mod:`waveoptics.renderers.drjit_polar`).

References written here, not taken from the library:

* the Mueller matrix of a Jones matrix, A (J ⊗ J*) A⁻¹ (Chipman, Lam & Young 2018, §6.9), against Mitsuba's own
  ``specular_reflection`` of the Fresnel amplitudes (Born & Wolf §1.5.2, §14.2) for a metal;
* the plugin's diffracted Mueller matrix, normalized, against one built here from Germer's (1997, eqs. 17–20)
  q_ss, q_sp, q_ps, q_pp, the s/p frames (s = ẑ × ω, p = k × s), A (J ⊗ J*) A⁻¹ and the rotation onto Mitsuba's
  Stokes bases (Duff et al. 2017's orthonormal basis, Mitsuba's rotator), for glass and aluminium, both transport
  modes (measured 1.4e-6), and in the scalar variant;
* at normal incidence the first-order field keeps the incident polarization in the laboratory frame (rotational
  symmetry), so the diffracted Mueller matrix is Mitsuba's ``specular_reflection(1, η)`` with one s axis for both
  beams (another program, and independent of the s/p conventions above);
* the diffracted Mueller matrix does not depolarize (degree of polarization 1, tr MᵀM = 4 M₀₀²);
* a glass sphere (n = 1.5) under a constant sky: the light a linear polarizer lets through at its darkest
  orientation, (S₀ − √(S₁² + S₂²))/2, vanishes at Brewster's angle, 56.3°.
"""
from __future__ import annotations

import functools
import importlib.util

import numpy as np
import pytest
from mitsuba_helpers import mueller_matrices

pytestmark = pytest.mark.skipif(importlib.util.find_spec("mitsuba") is None,
                                reason="Mitsuba 3 (extra 'render') is not installed")

VARIANT = "llvm_ad_spectral_polarized"
NODES = (450.0, 650.0)
#: float32 plugin against the float64 reference, on Mueller elements normalized by M₀₀ (measured 1.4e-6)
ATOL = 1e-5


def _lobes(thetas, grid):
    """Isotropic lobe tables (1, n_θ, n_λ, n_v, n_u), 1/sr: a Gaussian of width 0.15 in direction cosines about
    each node's mirror point. Their shape is not under test here, only the polarization the plugin gives them."""
    U, V = np.meshgrid(grid.u, grid.v)
    out = np.zeros((1, len(thetas), len(NODES), grid.n_v, grid.n_u))
    for k, th in enumerate(np.radians(thetas)):
        lobe = np.exp(-((U + np.sin(th)) ** 2 + V ** 2) / (2 * 0.15 ** 2))
        out[0, k] = np.where(grid.inside, 20.0 * lobe, 0.0)
    return out


@functools.lru_cache(maxsize=None)
def _model(material):
    """Beckmann α = 0.002: the coherent part is nil (below 1e-100 of the lobe) where the half vector is more than
    2° off the normal, so there the plugin's Mueller matrix is the diffracted part alone."""
    from waveoptics import brdf
    from waveoptics.request import make_nano
    from waveoptics.scatter.grid import DirectionGrid

    grid = DirectionGrid.hemisphere(24)
    thetas = (0.0, 30.0, 60.0, 80.0)
    base = brdf.TabulatedTwoScaleBRDF(material=material, micro=brdf.Micro(alpha=0.002, ndf="beckmann"), kd=0.0,
                                      nano=make_nano("abc:sigma=15nm,B=2um,C=2.6", NODES), wavelengths_nm=NODES,
                                      thetas_deg=thetas, table_grid=grid, table_lobes=_lobes(thetas, grid),
                                      table_phis_deg=(0.0,))
    return brdf.SpectralNodes(base, NODES)


def _plugin(material):
    from waveoptics.renderers.mitsuba_native import register_native

    name = "wo_polar_" + "".join(ch for ch in material if ch.isalnum())
    mi = register_native(VARIANT, model=_model(material), name=name)
    return mi, mi.load_dict({"type": name})


#: pairs per evaluation: every LLVM evaluation here has this width (Dr.Jit compiles one kernel per width)
N_PAIRS = 200


@functools.lru_cache(maxsize=None)
def _evaluated(material, radiance=True):
    """(ω_i, ω_o, the plugin's Mueller matrices (4 λ, n, 4, 4)) at :func:`_pairs` (N_PAIRS, seed 7), wavelengths at
    the nodes (450, 650, 450, 650 nm)."""
    mi, plugin = _plugin(material)
    wi, wo = _pairs(N_PAIRS, seed=7)
    lam = np.tile(np.array(NODES * 2), (wi.shape[0], 1))
    mode = mi.TransportMode.Radiance if radiance else mi.TransportMode.Importance
    M = mueller_matrices(mi, plugin, wi, wo, lam, mode)
    return wi, wo, np.moveaxis(M, (0, 1), (-2, -1))


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# -- references written from the papers --------------------------------------------------------------------------
#: Stokes (S0, S1, S2, S3) = A (E_x E_x*, E_x E_y*, E_y E_x*, E_y E_y*): S2 = 2 Re E_x E_y*, S3 = 2 Im E_x E_y*
A = np.array([[1, 0, 0, 1], [1, 0, 0, -1], [0, 1, 1, 0], [0, -1j, 1j, 0]])


def mueller_of(J):
    """A (J ⊗ J*) A⁻¹ (Chipman, Lam & Young §6.9) of Jones matrices J (..., 2, 2)."""
    kron = np.einsum("...ac,...bd->...abcd", J, J.conj()).reshape(J.shape[:-2] + (4, 4))
    return np.real(A @ kron @ np.linalg.inv(A))


def germer_jones(wi, wo, eps):
    """J = [[q_ss, q_ps], [q_sp, q_pp]] (rows: scattered s, p; columns: incident s, p), Germer 1997 eqs. 17–20, and
    the s axes s = ẑ × ω / |ẑ × ω| of the two frames (p = k × s with k the direction of travel)."""
    z = np.array([0.0, 0.0, 1.0])
    ci, co = wi[..., 2], wo[..., 2]
    s_i, s_o = np.cross(z, wi), np.cross(z, wo)
    sin_i, sin_o = np.linalg.norm(s_i, axis=-1), np.linalg.norm(s_o, axis=-1)
    s_i = np.where(sin_i[..., None] > 0, s_i / np.where(sin_i > 0, sin_i, 1)[..., None], [0.0, 1.0, 0.0])
    s_o = s_o / sin_o[..., None]
    e_i = np.cross(s_i, z)                     # ω_i's azimuth; the specular side is −e_i
    e_o = np.cross(s_o, z)
    cphi = -np.sum(e_i * e_o, axis=-1)
    sphi = -np.cross(e_i, e_o)[..., 2]
    ri, ro = np.sqrt(eps - sin_i ** 2 + 0j), np.sqrt(eps - sin_o ** 2 + 0j)
    q_ss = (eps - 1) * cphi / ((ci + ri) * (co + ro))
    q_sp = -(eps - 1) * ro * sphi / ((ci + ri) * (eps * co + ro))
    q_ps = -(eps - 1) * ri * sphi / ((eps * ci + ri) * (co + ro))
    q_pp = (eps - 1) * (eps * sin_i * sin_o - ri * ro * cphi) / ((eps * ci + ri) * (eps * co + ro))
    J = np.stack([np.stack([q_ss, q_ps], -1), np.stack([q_sp, q_pp], -1)], -2)
    return J, s_i, s_o


def stokes_basis(k):
    """Mitsuba's Stokes basis vector of a beam along k: the first vector of Duff et al. 2017's orthonormal basis
    ("Building an orthonormal basis, revisited", JCGT 6(1), listing 3)."""
    sign = np.where(k[..., 2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + k[..., 2])
    b = k[..., 0] * k[..., 1] * a
    return np.stack([1 + sign * k[..., 0] ** 2 * a, sign * b, -sign * k[..., 0]], -1)


def rotator(k, current, target):
    """Mueller matrix re-expressing a Stokes vector along k from the basis *current* in the basis *target*
    (Mitsuba's ``rotate_stokes_basis``: the signed angle about k, Collett's rotator)."""
    theta = np.arctan2(np.sum(k * np.cross(current, target), -1), np.sum(current * target, -1))
    c, s = np.cos(2 * theta), np.sin(2 * theta)
    R = np.zeros(theta.shape + (4, 4))
    R[..., 0, 0] = R[..., 3, 3] = 1
    R[..., 1, 1] = R[..., 2, 2] = c
    R[..., 1, 2], R[..., 2, 1] = s, -s
    return R


def in_mitsubas_frames(M, w_light, w_view, s_i, s_o):
    """M from the frames (s_i, s_o) onto Mitsuba's Stokes bases of the beams along −ω_light and ω_view."""
    k_in, k_out = -w_light, w_view
    R_in, R_out = rotator(k_in, s_i, stokes_basis(k_in)), rotator(k_out, s_o, stokes_basis(k_out))
    return R_out @ M @ np.swapaxes(R_in, -1, -2)


def _normalized(M):
    return M / M[..., :1, :1]


def _pairs(n, seed):
    """(ω_i, ω_o) with ω_o scattered about ω_i's mirror direction, the half vector ≥ 3° off the normal (no
    coherent part) and θ_o < 85°; float32-exact."""
    rng = np.random.default_rng(seed)
    th, ph = np.radians(rng.uniform(0.0, 75.0, 4 * n)), rng.uniform(0, 2 * np.pi, 4 * n)
    wi = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    wo = wi * [-1.0, -1.0, 1.0] + 0.25 * rng.normal(size=wi.shape)
    wo[:, 2] = np.abs(wo[:, 2])
    wo = _unit(wo)
    h = _unit(wi + wo)
    keep = (h[:, 2] < np.cos(np.radians(3.0))) & (wo[:, 2] > np.cos(np.radians(85.0)))
    f32 = (lambda a: _unit(a[keep][:n]).astype(np.float32).astype(float))
    return f32(wi), f32(wo)


# -- tests ---------------------------------------------------------------------------------------------------------
def test_mueller_of_the_fresnel_jones_matrix_is_mitsubas_specular_reflection():
    """mueller_from_jones(diag(r_s, r_p)) of a metal (n = 0.2 + 3i, e^{−iωt}, Verdet's r_p) is Mitsuba's
    ``specular_reflection``: the Stokes convention, S3's sign included, is Mitsuba's."""
    from waveoptics.renderers.drjit_polar import mueller_from_jones

    mi, _ = _plugin("aluminium")
    n = 0.2 + 3j
    s23 = []
    for theta in np.radians([0.0, 25.0, 50.0, 70.0, 85.0]):
        c, s = np.cos(theta), np.sin(theta)
        t = np.sqrt(n * n - s * s)                   # n cos θ_t
        r_s, r_p = (c - t) / (c + t), (n * n * c - t) / (n * n * c + t)
        zero = (0.0, 0.0)
        got = np.array(mueller_from_jones((((r_s.real, r_s.imag), zero), (zero, (r_p.real, r_p.imag)))))
        assert np.allclose(got, mueller_of(np.diag([r_s, r_p])), atol=1e-12)
        want = np.array(mi.mueller.specular_reflection(mi.Float(c), mi.Complex2f(n.real, n.imag))).reshape(4, 4)
        np.testing.assert_allclose(got, want, atol=2e-6)
        s23.append(abs(want[2, 3]))
    assert max(s23) > 0.1                            # S2 ↔ S3 (a retarder): the sign of S3 is tested


@pytest.mark.parametrize("material", ["1.5+0j", "aluminium"])
def test_diffracted_mueller_matrix_is_germers_jones_matrix_in_mitsubas_frames(material):
    eps = np.asarray(_model(material).base.material.eta(np.array(NODES)), dtype=complex) ** 2
    for radiance in (True, False):
        wi, wo, got = _evaluated(material, radiance)
        assert wi.shape[0] == N_PAIRS and np.all(got[..., 0, 0] > 0)
        # light from ω_o (Mitsuba's wo) to the camera (si.wi) in radiance mode, the other way in importance mode
        w_light, w_view = (wo, wi) if radiance else (wi, wo)
        for i in range(4):
            J, s_i, s_o = germer_jones(w_light, w_view, eps[i % 2])
            want = _normalized(in_mitsubas_frames(mueller_of(J), w_light, w_view, s_i, s_o))
            err = np.abs(_normalized(got[i]) - want).max()
            assert err < ATOL, (radiance, i, err)
        assert np.abs(want[..., 2, 3]).max() > 0.05 or material == "1.5+0j"          # retardance (metal)
        assert np.abs(want[..., 0, 2]).max() > 0.05                                 # out of plane: S2 terms


def test_scalar_variant_gives_the_same_diffracted_mueller_matrix():
    """scalar_spectral_polarized (Python floats through the same code), aluminium, 8 pairs, radiance mode."""
    import drjit as dr

    from waveoptics.renderers.mitsuba_native import register_native

    mi = register_native("scalar_spectral_polarized", model=_model("aluminium"), name="wo_polar_scalar")
    plugin = mi.load_dict({"type": "wo_polar_scalar"})
    wi, wo = _pairs(8, seed=11)
    eps = complex(_model("aluminium").base.material.eta(NODES[0])) ** 2
    J, s_i, s_o = germer_jones(wo, wi, eps)
    want = _normalized(in_mitsubas_frames(mueller_of(J), wo, wi, s_i, s_o))
    for j in range(wi.shape[0]):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*[float(x) for x in wi[j]])
        si.wavelengths = mi.UnpolarizedSpectrum(NODES[0])
        m = plugin.eval(mi.BSDFContext(), si, mi.Vector3f(*[float(x) for x in wo[j]]))
        got = np.array([[np.ravel(np.array(m[r][c], dtype=float))[0] for c in range(4)] for r in range(4)])
        assert got[0, 0] > 0
        assert np.abs(got / got[0, 0] - want[j]).max() < ATOL


@pytest.mark.parametrize("material", ["1.5+0j", "aluminium"])
def test_at_normal_incidence_the_diffracted_light_keeps_the_incident_polarization(material):
    """Light along −ẑ, viewed 1° off the normal at N_PAIRS azimuths: Mitsuba's normal-incidence mirror,
    ``specular_reflection(1, η)``, with the same s axis for both beams, to O(θ_o²) = 3e-4 (measured 1.5e-4)."""
    mi, plugin = _plugin(material)
    phi = np.linspace(0.0, 2 * np.pi, N_PAIRS, endpoint=False) + 0.1
    t = np.radians(1.0)
    view = np.stack([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi), np.full(N_PAIRS, np.cos(t))], -1)
    light = np.tile([0.0, 0.0, 1.0], (N_PAIRS, 1))
    lam = np.tile(np.array(NODES * 2), (N_PAIRS, 1))
    got = np.moveaxis(mueller_matrices(mi, plugin, view, light, lam, mi.TransportMode.Radiance), (0, 1), (-2, -1))
    eta = np.asarray(_model(material).base.material.eta(np.array(NODES)), dtype=complex)
    x = np.tile([1.0, 0.0, 0.0], (N_PAIRS, 1))
    for i in range(4):
        e = mi.Complex2f(float(eta[i % 2].real), float(eta[i % 2].imag))
        mirror = np.array(mi.mueller.specular_reflection(mi.Float(1.0), e)).reshape(4, 4)
        want = _normalized(in_mitsubas_frames(np.broadcast_to(mirror, (N_PAIRS, 4, 4)), light, view, x, x))
        err = np.abs(_normalized(got[i]) - want).max()
        assert err < 5e-4, (i, err)


@pytest.mark.parametrize("material", ["1.5+0j", "aluminium"])
def test_diffracted_mueller_matrix_does_not_depolarize(material):
    wi, _, M = _evaluated(material)
    assert np.all(M[..., 0, 0] > 0)
    N = _normalized(M)
    # Gil & Bernabeu 1985: a Mueller matrix is non-depolarizing iff tr(MᵀM) = 4 M₀₀²
    np.testing.assert_allclose(np.sum(N ** 2, axis=(-2, -1)), 4.0, atol=1e-4)
    rng = np.random.default_rng(8)
    v = _unit(rng.normal(size=(wi.shape[0], 3)))
    S_out = N @ np.concatenate([np.ones((wi.shape[0], 1)), v], -1)[..., None]
    dop = np.linalg.norm(S_out[..., 1:, 0], axis=-1) / S_out[..., 0, 0]
    np.testing.assert_allclose(dop, 1.0, atol=1e-4)


def _glass_sphere_stokes(N=48, spp=32):
    """S0..S3 (N, N, 4), mean over the RGB channels, of a glass sphere (n = 1.5, GGX α = 0.01) with a narrow
    diffracted lobe (width 0.04 in direction cosines, albedo 2π·0.04²·5 = 0.05) under a constant unit sky, seen by
    an orthographic camera that the unit sphere fills (Mitsuba's ``stokes`` integrator)."""
    from waveoptics import brdf
    from waveoptics.request import make_nano
    from waveoptics.renderers.mitsuba_native import register_native
    from waveoptics.scatter.grid import DirectionGrid

    grid = DirectionGrid.hemisphere(64)
    thetas = (0.0, 30.0, 45.0, 55.0, 60.0, 70.0, 80.0)
    U, V = np.meshgrid(grid.u, grid.v)
    lobes = np.zeros((1, len(thetas), len(NODES), grid.n_v, grid.n_u))
    for k, th in enumerate(np.radians(thetas)):
        lobes[0, k] = np.where(grid.inside, 5.0 * np.exp(-((U + np.sin(th)) ** 2 + V ** 2) / (2 * 0.04 ** 2)), 0.0)
    base = brdf.TabulatedTwoScaleBRDF(material="1.5+0j", micro=brdf.Micro(alpha=0.01, ndf="ggx"), kd=0.0,
                                      nano=make_nano("abc:sigma=15nm,B=2um,C=2.6", NODES), wavelengths_nm=NODES,
                                      thetas_deg=thetas, table_grid=grid, table_lobes=lobes, table_phis_deg=(0.0,))
    mi = register_native(VARIANT, model=brdf.SpectralNodes(base, NODES), name="wo_polar_glass_sphere")
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "stokes", "integrator": {"type": "path", "max_depth": 2}},
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": N, "height": N, "pixel_format": "rgb",
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": {"type": "wo_polar_glass_sphere"}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
    })
    img = np.array(mi.render(scene, seed=1), dtype=float)
    bitmap = scene.sensors()[0].film().bitmap()
    names = [bitmap.struct_()[i].name for i in range(bitmap.channel_count())]
    return np.stack([img[..., [names.index(f"S{k}.{c}") for c in "RGB"]].mean(-1) for k in range(4)], -1)


def test_a_polarizer_shows_brewsters_dark_band_on_a_glass_sphere():
    """Per pixel, the light a linear polarizer lets through at its darkest orientation, T = (S0 − √(S1² + S2²))/2,
    over S0 in 2° rings of incidence θ = asin(r): darkest at Brewster's angle arctan 1.5 = 56.3° and there below
    0.02 (measured 0.005 at 56–58°; with the diffracted part a depolarizer: 0.17, darkest at 62–64°). If that part
    were a depolarizer, half the diffracted light, (S0 − flat glass's (R_s + R_p)/2)/2 (Fresnel, written here),
    would pass: the band stays dark because it is not."""
    S = _glass_sphere_stokes()
    N = S.shape[0]
    c = (np.arange(N) + 0.5) / N * 2 - 1
    r = np.hypot(*np.meshgrid(c, c))
    theta = np.degrees(np.arcsin(np.clip(r, 0.0, 1.0)))
    T = (S[..., 0] - np.hypot(S[..., 1], S[..., 2])) / (2 * S[..., 0])
    edges = np.arange(20.0, 74.0, 2.0)                  # r < 0.97: θ < 75.9°
    rings = [(theta >= a) & (theta < a + 2.0) for a in edges]
    T_ring = np.array([T[m].mean() for m in rings])
    brewster = np.degrees(np.arctan(1.5))
    darkest = edges[T_ring.argmin()] + 1.0
    assert abs(darkest - brewster) <= 2.0, (darkest, T_ring.round(4))
    assert T_ring.min() < 0.02
    assert T_ring[(edges < 40) | (edges > 70)].min() > 0.1                       # a band, not a dark sphere

    t = np.radians(brewster)
    ct = np.sqrt(1 - (np.sin(t) / 1.5) ** 2)
    R_s = ((np.cos(t) - 1.5 * ct) / (np.cos(t) + 1.5 * ct)) ** 2
    R_p = ((1.5 * np.cos(t) - ct) / (1.5 * np.cos(t) + ct)) ** 2
    S0 = S[..., 0][rings[T_ring.argmin()]].mean()
    depolarized = (S0 - 0.5 * (R_s + R_p)) / (2 * S0)
    assert depolarized > 10 * T_ring.min(), (depolarized, T_ring.min())
