"""The Dr.Jit two-scale BSDF (``waveoptics_native``, :mod:`waveoptics.renderers.mitsuba_native`).

* eval and pdf equal the NumPy model's (its float64 twin) at 300 random direction pairs, half of them near the
  specular direction, in scalar and LLVM variants, for a metal (also with rim tables, read beyond θ_o 65°), an
  anisotropic micro roughness with multiple scattering, and a dielectric with a diffuse substrate (Beckmann,
  separable Smith);
* the sampler maps the same uniform numbers to the same directions as the NumPy model's;
* Mitsuba's own χ² test accepts sample and pdf (metal at 30° and 80°, anisotropic with multiple scattering at 45°
  and 80°, dielectric with diffuse at 0° and 80°);
* without nano-roughness it is Mitsuba's ``roughconductor`` (another program): eval and pdf pointwise (measured
  1.2e-6), a rendered sphere (mean relative pixel difference measured 0.7 % at 128 spp, 0.34 % at 512: Monte Carlo
  noise; bound 2 %), and in polarized variants every element of its Mueller matrix (measured 5e-7 of the largest);
* the polarized diffracted part: tests/test_mitsuba_polarized.py.
"""
from __future__ import annotations

import functools
import importlib.util

import numpy as np
import pytest
from mitsuba_helpers import eval_pdf, mueller_matrices

pytestmark = pytest.mark.skipif(importlib.util.find_spec("mitsuba") is None,
                                reason="Mitsuba 3 (extra 'render') is not installed")

NODES = (450.0, 650.0)
#: float32 evaluation against the float64 model: relative error where the value is above 1e-3 of the largest
RTOL = 2e-5


def _lobes(n_phi, thetas, grid, seed):
    """Lobe tables (n_φ, n_θ, n_λ, n_v, n_u) in 1/sr: a Gaussian about each node's mirror point whose width grows
    with θ and λ, with 20 % cell-to-cell noise, zero beyond the horizon. The Dr.Jit BSDF must read any table as the
    NumPy model does; computing real lobes (waveoptics.brdf.evaluate) would take most of the test's time."""
    rng = np.random.default_rng(seed)
    U, V = np.meshgrid(grid.u, grid.v)
    out = np.zeros((n_phi, len(thetas), len(NODES), grid.n_v, grid.n_u))
    for p in range(n_phi):
        ph = 2 * np.pi * p / n_phi
        for k, th in enumerate(np.radians(thetas)):
            mu, mv = -np.sin(th) * np.cos(ph), -np.sin(th) * np.sin(ph)
            for j, lam in enumerate(NODES):
                width = 0.08 + 0.1 * th + 1e-4 * lam
                lobe = np.exp(-((U - mu) ** 2 + (V - mv) ** 2) / (2 * width ** 2))
                lobe = lobe * (1 + 0.2 * rng.uniform(size=U.shape))
                out[p, k, j] = np.where(grid.inside, 0.4 * lobe / width ** 2, 0.0)
    return out


def _rim(thetas, seed):
    """Rim tables (n_θ, n_λ, n_cos, n_φ) (waveoptics.brdf.tabulated_rim's layout): smooth in cos θ_o and φ_o,
    different at each node, with 20 % node-to-node noise; the Dr.Jit BSDF must read them as the NumPy model does."""
    from waveoptics.brdf.tabulated_rim import rim_cos_nodes, rim_phi_nodes

    rng = np.random.default_rng(seed)
    c, p = np.meshgrid(rim_cos_nodes(), rim_phi_nodes(), indexing="ij")
    out = np.stack([np.stack([(0.3 + k + j + np.cos(p) ** 2 + c) * (1 + 0.2 * rng.uniform(size=c.shape))
                              for j in range(len(NODES))]) for k in range(len(thetas))])
    return 0.05 * out


@functools.lru_cache(maxsize=None)
def _model(case):
    from waveoptics import brdf
    from waveoptics.request import make_nano
    from waveoptics.scatter.grid import DirectionGrid

    grid = DirectionGrid.hemisphere(24)
    thetas = (0.0, 30.0, 60.0, 80.0)
    n_phi = 4 if case == "anisotropic" else 1
    common = dict(wavelengths_nm=NODES, thetas_deg=thetas, table_grid=grid,
                  table_lobes=_lobes(n_phi, thetas, grid, seed=n_phi),
                  table_phis_deg=tuple(360.0 * p / n_phi for p in range(n_phi)))
    if case in ("metal", "rim"):   # rim: with rim tables, read beyond θ_o 65°
        base = brdf.TabulatedTwoScaleBRDF(material="aluminium", micro=brdf.Micro(alpha=0.2, ndf="ggx"),
                                          nano=make_nano("abc:sigma=15nm,B=2um,C=2.6", NODES),
                                          table_rim=_rim(thetas, 7) if case == "rim" else None, **common)
    elif case == "anisotropic":
        base = brdf.TabulatedTwoScaleBRDF(material="gold", micro=brdf.Micro(alpha=0.1, alpha_y=0.3, ndf="ggx"),
                                          nano=make_nano("abc:sigma=15nm,B=2um,C=2.6", NODES),
                                          multiple_scattering=True, **common)
    else:   # dielectric; burley and oren-nayar: its diffuse substrate with each model's own roughness
        rough = {"burley": dict(diffuse="burley", diffuse_roughness=0.8),
                 "oren-nayar": dict(diffuse="oren-nayar", diffuse_sigma=0.5)}.get(case, {})
        base = brdf.TabulatedTwoScaleBRDF(material="1.5+0j", micro=brdf.Micro(alpha=0.15, ndf="beckmann",
                                                                             shadowing="smith"),
                                          kd=0.5, nano=make_nano("abc:sigma=20nm,B=2um,C=2.6", NODES), **rough,
                                          **common)
    return brdf.SpectralNodes(base, NODES)


def _plugin(variant, case):
    from waveoptics.renderers.mitsuba_native import register_native

    mi = register_native(variant, model=_model(case), name=f"wo_native_{case}")
    return mi, f"wo_native_{case}"


def _pairs(n, seed):
    """n (ω_i, ω_o) pairs below 85°, the first half within ~5° of the mirror direction; float32-exact."""
    rng = np.random.default_rng(seed)

    def dirs(k):
        th, ph = np.radians(rng.uniform(0.0, 85.0, k)), rng.uniform(0.0, 2 * np.pi, k)
        return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)

    wi, wo = dirs(n), dirs(n)
    h = n // 2
    wo[:h] = wi[:h] * [-1.0, -1.0, 1.0] + 0.08 * rng.normal(size=(h, 3))
    wo[:h, 2] = np.abs(wo[:h, 2])
    wo[:h] /= np.linalg.norm(wo[:h], axis=1)[:, None]
    lam = rng.uniform(NODES[0], NODES[-1], (n, 4))
    f32 = (lambda a: a.astype(np.float32).astype(float))
    return f32(wi), f32(wo), f32(lam)


def _assert_close(got, want, what):
    scale = np.maximum(np.abs(want), 1e-3 * np.abs(want).max())
    rel = np.abs(got - want) / scale
    worst = np.unravel_index(rel.argmax(), rel.shape)
    assert rel.max() < RTOL, f"{what}: largest relative error {rel.max():.3g} at {worst}"


@pytest.mark.parametrize("variant,case", [("llvm_ad_rgb", "metal"), ("llvm_ad_rgb", "anisotropic"),
                                          ("llvm_ad_rgb", "dielectric"), ("scalar_rgb", "metal"),
                                          ("scalar_rgb", "dielectric"), ("llvm_ad_spectral", "anisotropic"),
                                          ("scalar_spectral", "dielectric"), ("scalar_rgb", "burley"),
                                          ("scalar_rgb", "oren-nayar"), ("llvm_ad_rgb", "rim"),
                                          ("scalar_rgb", "rim"), ("scalar_rgb", "anisotropic")])
def test_eval_and_pdf_equal_the_numpy_model(variant, case):
    mi, name = _plugin(variant, case)
    model = _model(case)
    plugin = mi.load_dict({"type": name})
    wi, wo, lam = _pairs(300, seed=len(case) + len(variant))
    got, pdf = eval_pdf(mi, plugin, wi, wo, lam)
    if mi.is_spectral:
        want = model.eval(wi[:, None, :], wo[:, None, :], lam) * wo[:, 2:3]
        want_pdf = model.pdf(wi, wo, lam[:, 0])
    else:
        want = model.eval_rgb(wi, wo) * wo[:, 2:3]
        want_pdf = model.pdf_rgb(wi, wo)
    assert np.all(want_pdf > 0) and want.max() > 0
    _assert_close(got, want, "eval")
    _assert_close(pdf, want_pdf, "pdf")


@pytest.mark.parametrize("case", ["metal", "anisotropic", "dielectric"])
def test_sampler_maps_uniform_numbers_as_the_numpy_model(case):
    """The same u gives the same ω_o at every node (up to float32: samples whose point lies within rounding of the
    horizon may be valid in one and not in the other, measured 0.05 %)."""
    from waveoptics.renderers.drjit_twoscale import DrJitTwoScale

    mi, _ = _plugin("llvm_ad_rgb", case)
    model = _model(case)
    tab = DrJitTwoScale(model, mi)
    rng = np.random.default_rng(3)
    n = 3000
    wi, _, _ = _pairs(n, seed=4)
    u = rng.uniform(0.0, 1.0, (n, 2)).astype(np.float32).astype(float)
    for j, lam in enumerate(NODES):
        wo = tab.sample_node(mi.Vector3f(np.ascontiguousarray(wi.T.astype(np.float32))),
                             mi.Point2f(np.ascontiguousarray(u.T.astype(np.float32))), j)
        got = np.array(wo, dtype=float).reshape(3, -1).T
        want = model.base._sample1(wi, u.copy(), lam)
        bad = np.abs(got - want).max(axis=1) > 2e-3
        assert bad.mean() < 2e-3, (lam, bad.mean())


@pytest.mark.parametrize("case,theta_deg", [("metal", 30.0), ("metal", 80.0), ("anisotropic", 45.0),
                                            ("anisotropic", 80.0), ("dielectric", 0.0), ("dielectric", 80.0)])
def test_mitsubas_chi2_accepts_sample_and_pdf(case, theta_deg):
    mi, name = _plugin("llvm_ad_rgb", case)
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    t = np.radians(theta_deg)
    wi = mi.Vector3f(float(np.sin(t) * np.cos(0.4)), float(np.sin(t) * np.sin(0.4)), float(np.cos(t)))
    sample_func, pdf_func = BSDFAdapter(name, {"type": name}, wi=wi)
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func, sample_dim=3,
                         sample_count=200_000, res=101, ires=8, seed=7)
    assert chi2.run(), chi2.messages


def test_mitsubas_chi2_accepts_the_spectral_sampler():
    """llvm_ad_spectral, anisotropic case at 60°: the hero wavelength's node sampler and its density (Mitsuba's
    adapter leaves the wavelengths at 0, so this one sets them)."""
    import drjit as dr

    mi, name = _plugin("llvm_ad_spectral", "anisotropic")
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    t = np.radians(60.0)
    wi = mi.Vector3f(float(np.sin(t) * np.cos(0.4)), float(np.sin(t) * np.sin(0.4)), float(np.cos(t)))
    plugin = mi.load_dict({"type": name})

    def context(n):
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = wi
        lam = (600.0, 460.0, 520.0, 640.0)
        si.wavelengths = mi.Spectrum(*[mi.Float(np.full(n, x, dtype=np.float32)) for x in lam])
        return si

    def sample_func(sample, *args):
        bs, weight = plugin.sample(mi.BSDFContext(), context(dr.width(sample)), sample[0],
                                   mi.Vector2f([sample[1], sample[2]]))
        w = dr.full(mi.Float, 1.0, dr.width(weight))
        w[dr.all(weight == 0)] = 0
        return bs.wo, w

    def pdf_func(wo, *args):
        return plugin.pdf(mi.BSDFContext(), context(dr.width(wo)), wo)

    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func, sample_dim=3,
                         sample_count=200_000, res=101, ires=8, seed=7)
    assert chi2.run(), chi2.messages


ROUGH = dict(material="0.2+3j", alpha=0.3, ndf="ggx", nano="none", shadowing="smith", wavelength_step=94.0)


def test_without_nano_roughness_it_is_mitsubas_roughconductor_pointwise():
    """σ = 0 and separable Smith: f cos θ_o and pdf equal Mitsuba's roughconductor (GGX, visible normals) of the
    same α and constant η, k (float32 on both sides). Spectral, where a constant index is the same at every λ (in
    RGB the colour matrix of the nodes maps white to (1, 1, 1) only within 2e-4)."""
    from waveoptics.renderers.mitsuba_native import NATIVE_PLUGIN_NAME, register_native

    mi = register_native("llvm_ad_spectral")
    ours = mi.load_dict({"type": NATIVE_PLUGIN_NAME, **ROUGH})
    ref = mi.load_dict({"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "eta": 0.2, "k": 3.0})
    wi, wo, lam = _pairs(400, seed=9)
    got, pdf = eval_pdf(mi, ours, wi, wo, lam)
    want, want_pdf = eval_pdf(mi, ref, wi, wo, lam)
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-6 * want.max())
    np.testing.assert_allclose(pdf, want_pdf, rtol=1e-4, atol=1e-6 * want_pdf.max())


def _sphere_render(mi, bsdf, spp):
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 3},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 32, "height": 32, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.3, 0.3]}},
        "sun": {"type": "directional", "direction": [-0.5, -0.6, -0.6], "irradiance": {"type": "rgb",
                                                                                       "value": [3, 3, 3]}},
    })
    return np.array(mi.render(scene, seed=1), dtype=float)


def test_without_nano_roughness_the_render_is_mitsubas_roughconductor():
    from waveoptics.renderers.mitsuba_native import NATIVE_PLUGIN_NAME, register_native

    mi = register_native("llvm_ad_spectral")
    ours = _sphere_render(mi, {"type": NATIVE_PLUGIN_NAME, **ROUGH}, 128)
    ref = _sphere_render(mi, {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "eta": 0.2,
                              "k": 3.0}, 128)
    assert np.all(np.isfinite(ours)) and ours.max() > 0
    mask = ref.sum(-1) > 1e-3 * ref.sum(-1).max()
    diff = np.abs(ours - ref)[mask].mean() / ref[mask].mean()
    assert diff < 0.02, diff


def test_polarized_without_nano_roughness_is_mitsubas_polarized_roughconductor():
    """Every Mueller element, in both transport modes (the frames of the Stokes vectors follow the light)."""
    from waveoptics.renderers.mitsuba_native import NATIVE_PLUGIN_NAME, register_native

    mi = register_native("llvm_ad_spectral_polarized")
    ours = mi.load_dict({"type": NATIVE_PLUGIN_NAME, **ROUGH})
    ref = mi.load_dict({"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "eta": 0.2, "k": 3.0})
    wi, wo, lam = _pairs(300, seed=12)
    for mode in (mi.TransportMode.Radiance, mi.TransportMode.Importance):
        got, want = mueller_matrices(mi, ours, wi, wo, lam, mode), mueller_matrices(mi, ref, wi, wo, lam, mode)
        assert np.abs(want[0, 1]).max() > 0.05 * want[0, 0].max()          # it does polarize
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5 * np.abs(want).max())


def test_polarized_intensity_is_the_unpolarized_model():
    """M₀₀ of the polarized BSDF is the NumPy model's f cos θ_o (the polarization of the diffracted part, normalized
    by its own M₀₀, leaves the intensity unchanged; tests/test_mitsuba_polarized.py tests the rest)."""
    mi, name = _plugin("llvm_ad_spectral_polarized", "metal")
    model = _model("metal")
    wi, wo, lam = _pairs(300, seed=13)
    got = mueller_matrices(mi, mi.load_dict({"type": name}), wi, wo, lam, mi.TransportMode.Radiance)[0, 0].T
    want = model.eval(wi[:, None, :], wo[:, None, :], lam) * wo[:, 2:3]
    _assert_close(got, want, "M00")


def test_polarized_monochrome_variants_are_refused_in_one_line():
    from waveoptics.errors import WaveopticsError
    from waveoptics.renderers.mitsuba_native import register_native

    with pytest.raises(WaveopticsError, match="no polarized monochrome form") as exc:
        register_native("llvm_ad_mono_polarized")
    assert "\n" not in str(exc.value)


def test_mono_variant_gives_the_luminance_of_the_rgb_value():
    """Mitsuba's mono variants: Y of linear sRGB (ITU-R BT.709 weights, written here) of the model's RGB f."""
    mi, name = _plugin("llvm_ad_mono", "dielectric")
    model = _model("dielectric")
    wi, wo, lam = _pairs(200, seed=2)
    got, pdf = eval_pdf(mi, mi.load_dict({"type": name}), wi, wo, lam)
    want = (model.eval_rgb(wi, wo) * wo[:, 2:3]) @ np.array([0.212671, 0.715160, 0.072169])
    _assert_close(got[:, 0], want, "mono eval")
    _assert_close(pdf, model.pdf_rgb(wi, wo), "mono pdf")
