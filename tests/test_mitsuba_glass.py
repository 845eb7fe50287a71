"""The nano-rough glass in Mitsuba 3 (``waveoptics_glass``, :mod:`waveoptics.renderers.mitsuba_glass`).

* eval and pdf equal the library's :class:`waveoptics.brdf.NanoRoughDielectricBSDF` (float64) at random direction
  pairs on both sides of the surface, in both transport modes (Radiance: the library's directions swapped), in
  spectral and RGB, LLVM and scalar variants (float32 plugin);
* without nano-roughness it is Mitsuba's own ``roughdielectric`` (another program): eval and pdf pointwise (GGX with
  visible-normal sampling; Beckmann eval, whose sampler differs), in reflection and transmission, in both modes, and
  a rendered glass sphere over a checkerboard agrees with Mitsuba's to Monte Carlo noise;
* Mitsuba's own χ² test accepts sample and pdf over the whole sphere (α 0.3, σ 10 nm), light from outside and from
  inside the glass (below and beyond the critical angle).
"""
from __future__ import annotations

import functools
import importlib.util

import numpy as np
import pytest
from mitsuba_helpers import eval_pdf

pytestmark = pytest.mark.skipif(importlib.util.find_spec("mitsuba") is None,
                                reason="Mitsuba 3 (extra 'render') is not installed")

NODES = (450.0, 650.0)
#: float32 plugin against the float64 model: relative error where the value is above 1e-3 of the largest (measured
#: 6e-8, the float32 rounding of the result: the directions are float32-exact)
RTOL = 1e-6
#: the plugin (float32 out of float64) against Mitsuba's float32 roughdielectric: measured 4.2e-6
RTOL_MITSUBA = 2e-5
NANO = "abc:sigma=10nm,B=2um,C=2.6"
ROUGH = dict(material="1.5", alpha=0.3, ndf="ggx", nano="none", shadowing="smith", wavelength_step=94.0)


@functools.lru_cache(maxsize=None)
def _base():
    """The library's nano-rough glass: BK7 (dispersive), GGX α 0.3, height-correlated Smith, σ 10 nm."""
    from waveoptics import brdf, surfaces

    psd = surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6)
    return brdf.NanoRoughDielectricBSDF("glass", brdf.Micro(alpha=0.3, ndf="ggx", shadowing="smith-correlated"),
                                        psd=psd)


def _plugin(variant):
    from waveoptics import brdf
    from waveoptics.renderers.mitsuba_glass import register_glass

    name = "wo_glass_test"
    mi = register_glass(variant, model=brdf.SpectralNodes(_base(), NODES), name=name)
    return mi, mi.load_dict({"type": name})


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _pairs(n, seed, eta=1.5):
    """n (ω_i, ω_o) pairs over the whole sphere below 80° from the normal: a third uniform, a third near the mirror
    direction, a third near the refracted one (Snell's law written here); float32-exact."""
    rng = np.random.default_rng(seed)

    def dirs(k):
        th, ph = np.radians(rng.uniform(0.0, 80.0, k)), rng.uniform(0.0, 2 * np.pi, k)
        s = rng.choice([-1.0, 1.0], k)
        return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), s * np.cos(th)], -1)

    wi, wo = dirs(n), dirs(n)
    a, b = n // 3, 2 * n // 3
    wo[a:b] = _unit(wi[a:b] * [-1.0, -1.0, 1.0] + 0.1 * rng.normal(size=(b - a, 3)))
    t = wi[b:]
    rel = np.where(t[:, 2] > 0, 1.0 / eta, eta)                 # n_i / n_t
    sin_t = np.minimum(rel * np.hypot(t[:, 0], t[:, 1]), 0.95)
    tan = _unit(-t[:, :2] + 1e-12)
    refr = np.concatenate([sin_t[:, None] * tan, -np.sign(t[:, 2:3]) * np.sqrt(1 - sin_t[:, None] ** 2)], -1)
    wo[b:] = _unit(refr + 0.1 * rng.normal(size=refr.shape))
    ok = np.abs(wo[:, 2]) > 0.05
    wi, wo = wi[ok], wo[ok]
    lam = rng.uniform(NODES[0], NODES[-1], (len(wi), 4))
    f32 = (lambda x: x.astype(np.float32).astype(float))
    return f32(wi), f32(wo), f32(lam)


def _assert_close(got, want, what, rtol=RTOL):
    scale = np.maximum(np.abs(want), 1e-3 * np.abs(want).max())
    rel = np.abs(got - want) / scale
    worst = np.unravel_index(rel.argmax(), rel.shape)
    assert rel.max() < rtol, f"{what}: largest relative error {rel.max():.3g} at {worst}"


def _library(wi, wo, lam, radiance, rgb):
    """f |cos θ_o| (n, channels) and pdf (n,) from the library model: f linear in λ between the nodes (or the
    sRGB matrix of the nodes), the pdf of the node nearest the hero wavelength (or the mean of the nodes')."""
    from waveoptics import colour

    base = _base()
    a, b = (wo, wi) if radiance else (wi, wo)
    f_nodes = np.stack([base.eval(a, b, lam_j) for lam_j in NODES], -1)          # (n, 2)
    p_nodes = np.stack([base.pdf(wi, wo, lam_j) for lam_j in NODES], -1)
    if rgb:
        f = f_nodes @ colour.reflectance_to_rgb_matrix(np.array(NODES), "D65", "sRGB")
        p = p_nodes.mean(-1)
    else:
        t = (lam - NODES[0]) / (NODES[1] - NODES[0])
        f = (1 - t) * f_nodes[:, :1] + t * f_nodes[:, 1:]
        p = np.where(lam[:, 0] - NODES[0] < NODES[1] - lam[:, 0], p_nodes[:, 0], p_nodes[:, 1])
    return f * np.abs(wo[:, 2:3]), p


@pytest.mark.parametrize("variant,n", [("llvm_ad_spectral", 400), ("llvm_ad_rgb", 400), ("scalar_spectral", 60),
                                       ("scalar_rgb", 60)])
def test_eval_and_pdf_equal_the_library_glass_on_both_sides(variant, n):
    mi, plugin = _plugin(variant)
    wi, wo, lam = _pairs(n, seed=len(variant))
    cross = (wi[:, 2] > 0) != (wo[:, 2] > 0)
    assert 0.3 < cross.mean() < 0.7 and 0.3 < (wi[:, 2] > 0).mean() < 0.7
    for mode in (mi.TransportMode.Radiance, mi.TransportMode.Importance):
        got, pdf = eval_pdf(mi, plugin, wi, wo, lam, mi.BSDFContext(mode))
        want, want_pdf = _library(wi, wo, lam, mode == mi.TransportMode.Radiance, not mi.is_spectral)
        assert want[cross].max() > 0.1 and want[~cross].max() > 0.1
        _assert_close(got, want, f"eval {mode}")
        _assert_close(pdf, want_pdf, f"pdf {mode}")


def test_radiance_mode_is_the_adjoint():
    """Transmitted pairs: the Radiance value of (wi, wo) is the Importance value of (wo, wi) times |cos wo|/|cos wi|
    (one BSDF read along the light or against it)."""
    mi, plugin = _plugin("llvm_ad_spectral")
    wi, wo, lam = _pairs(300, seed=5)
    rad, _ = eval_pdf(mi, plugin, wi, wo, lam, mi.BSDFContext(mi.TransportMode.Radiance))
    imp, _ = eval_pdf(mi, plugin, wo, wi, lam, mi.BSDFContext(mi.TransportMode.Importance))
    _assert_close(rad, imp * np.abs(wo[:, 2:3] / wi[:, 2:3]), "adjoint")


def _reference(mi, ndf):
    return mi.load_dict({"type": "roughdielectric", "distribution": ndf, "alpha": 0.3, "int_ior": 1.5,
                         "ext_ior": 1.0})


def _beckmann_a(w, alpha=0.3):
    return np.abs(w[:, 2]) / (alpha * np.hypot(w[:, 0], w[:, 1]))


def _g1_exact(w):
    """Beckmann's Smith G1 = 2 / (1 + erf(a) + exp(−a²)/(a √π)), a = 1/(α tan θ) (Walter et al. 2007, eq. 25)."""
    from scipy.special import erf

    a = _beckmann_a(w)
    return 2.0 / (1.0 + erf(a) + np.exp(-a * a) / (a * np.sqrt(np.pi)))


def _g1_rational(w):
    """The rational approximation of it that Mitsuba's Beckmann uses (Walter et al. 2007, eq. 27)."""
    a = _beckmann_a(w)
    return np.where(a < 1.6, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a), 1.0)


@pytest.mark.parametrize("ndf", ["ggx", "beckmann"])
def test_without_nano_roughness_it_is_mitsubas_roughdielectric(ndf):
    """σ = 0, separable Smith, constant η = 1.5 (air outside: Mitsuba's ext_ior default is 1.000277): f cos θ_o in
    reflection and transmission, both sides and both transport modes; the pdf for GGX (both sample visible normals;
    Mitsuba's Beckmann sampler does too, the library's draws D cos θ_m). Mitsuba's Beckmann G1 is the rational
    approximation of Walter et al. (eq. 27; 0.35 %), the library's the exact one: the test takes Mitsuba's value
    times the ratio of the two, written here (without it the largest difference is 0.62 %, with it 4e-6)."""
    from waveoptics.renderers.mitsuba_glass import GLASS_PLUGIN_NAME, register_glass

    mi = register_glass("llvm_ad_spectral")
    ours = mi.load_dict({"type": GLASS_PLUGIN_NAME, **dict(ROUGH, ndf=ndf)})
    ref = _reference(mi, ndf)
    wi, wo, lam = _pairs(900, seed=9)
    cross = (wi[:, 2] > 0) != (wo[:, 2] > 0)
    for mode in (mi.TransportMode.Radiance, mi.TransportMode.Importance):
        ctx = mi.BSDFContext(mode)
        got, pdf = eval_pdf(mi, ours, wi, wo, lam, ctx)
        want, want_pdf = eval_pdf(mi, ref, wi, wo, lam, ctx)
        if ndf == "beckmann":
            want = want * (_g1_exact(wi) * _g1_exact(wo) / (_g1_rational(wi) * _g1_rational(wo)))[:, None]
        for side in (cross, ~cross):
            assert want[side].max() > 0.1
            np.testing.assert_allclose(got[side], want[side], rtol=RTOL_MITSUBA, atol=1e-6 * want.max())
            if ndf == "ggx":
                np.testing.assert_allclose(pdf[side], want_pdf[side], rtol=RTOL_MITSUBA, atol=1e-6 * want_pdf.max())


@pytest.mark.parametrize("theta_deg", [70.0, 150.0])
def test_without_nano_roughness_the_sampled_weights_average_as_mitsubas(theta_deg):
    """The mean of sample()'s weight (the albedo R + T of single scattering, in Radiance mode scaled by the η² of
    the transmitted part) equals that of Mitsuba's roughdielectric, from either side and in both modes, to 4
    standard errors (100 000 samples each; the samplers differ, so the two means are independent)."""
    import drjit as dr

    from waveoptics.renderers.mitsuba_glass import GLASS_PLUGIN_NAME, register_glass

    mi = register_glass("llvm_ad_rgb")
    ours, ref = mi.load_dict({"type": GLASS_PLUGIN_NAME, **ROUGH}), _reference(mi, "ggx")
    rng = np.random.default_rng(int(theta_deg))
    n, t = 100_000, np.radians(theta_deg)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(float(np.sin(t)), 0.0, float(np.cos(t)))
    s1 = mi.Float(rng.uniform(size=n).astype(np.float32))
    s2 = mi.Point2f(rng.uniform(size=(2, n)).astype(np.float32))
    for mode in (mi.TransportMode.Radiance, mi.TransportMode.Importance):
        stats = []
        for bsdf in (ours, ref):
            bs, weight = bsdf.sample(mi.BSDFContext(mode), si, s1, s2)
            w = np.array(weight, dtype=float).reshape(3, -1)[1]
            stats.append((w.mean(), w.std() / np.sqrt(n)))
        (a, ea), (b, eb) = stats
        assert b > 0.4 and abs(a - b) < 4 * np.hypot(ea, eb), (mode, stats)


def _glass_render(mi, bsdf, spp, seed):
    """32² px: a glass sphere in front of a diffuse checkerboard, under a uniform sky (no sun: its caustics through
    the glass are the noisiest paths of a path tracer)."""
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 8},
        "sensor": {"type": "perspective", "fov": 35,
                   "to_world": T().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 32, "height": 32, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "back": {"type": "rectangle", "to_world": T().translate([0, 0, -2]).scale(3),
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "checkerboard", "to_uv": T().scale(4)}}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}},
    })
    return np.array(mi.render(scene, seed=seed), dtype=float)


def test_without_nano_roughness_the_render_is_mitsubas_roughdielectric():
    """16 spp: the mean pixel difference from Mitsuba's render (seed 1) is within 1.3 times that of Mitsuba's own
    render with another seed (the noise; measured 0.95 times), and the mean over the sphere's pixels agrees within
    2 % (measured 0.07 %; 0.4 % at 256 spp, where two seeds of Mitsuba's differ by 0.1 %)."""
    from waveoptics.renderers.mitsuba_glass import GLASS_PLUGIN_NAME, register_glass

    mi = register_glass("llvm_ad_spectral")
    ours = _glass_render(mi, {"type": GLASS_PLUGIN_NAME, **ROUGH}, 16, seed=3)
    ref = _glass_render(mi, _reference(mi, "ggx"), 16, seed=1)
    ref2 = _glass_render(mi, _reference(mi, "ggx"), 16, seed=2)
    assert np.all(np.isfinite(ours)) and ours.max() > 0
    yy, xx = np.mgrid[:32, :32]
    sphere = (xx - 15.5) ** 2 + (yy - 15.5) ** 2 < 12.0 ** 2          # fov 35° at 4.5: radius ≈ 14.5 px
    lum = (lambda img: img.mean(-1))
    noise = np.abs(lum(ref2) - lum(ref))[sphere].mean()
    diff = np.abs(lum(ours) - lum(ref))[sphere].mean()
    assert diff < 1.3 * noise, (diff, noise)
    assert abs(lum(ours)[sphere].mean() / lum(ref)[sphere].mean() - 1) < 0.02


@pytest.mark.parametrize("theta_deg", [40.0, 145.0, 120.0])
def test_mitsubas_chi2_accepts_sample_and_pdf_over_the_sphere(theta_deg):
    """llvm_ad_rgb (the two nodes' mixture): light from outside at 40°, from inside at 35° and at 60° (beyond the
    critical angle 41° of BK7: the transmitted lobe is the microfacets' and the nano-roughness' only)."""
    mi, _ = _plugin("llvm_ad_rgb")
    _assert_chi2(mi, "wo_glass_test", theta_deg)


def _assert_chi2(mi, name, theta_deg):
    """Mitsuba's χ² test of the registered plugin *name* over the sphere (200 000 samples, 101 bins, seed 7) for
    light at *theta_deg* (azimuth 0.4 rad); returns ω_i."""
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    t = np.radians(theta_deg)
    wi = mi.Vector3f(float(np.sin(t) * np.cos(0.4)), float(np.sin(t) * np.sin(0.4)), float(np.cos(t)))
    sample_func, pdf_func = BSDFAdapter(name, {"type": name}, wi=wi)
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func, sample_dim=3,
                         sample_count=200_000, res=101, ires=8, seed=7)
    assert chi2.run(), chi2.messages
    return wi


def test_render_command_takes_the_rough_dielectric_with_nano(tmp_path):
    """``waveoptics render --model rough-dielectric --nano ...`` (8² px, 2 spp): the glass plugin beside Mitsuba's
    roughdielectric, every output written, the sphere lit in both."""
    import json

    from cli_helpers import run_cli

    from waveoptics.io.files import read_exr
    from waveoptics.renderers.scene import sphere_mask

    out = tmp_path / "o"
    rc, _, err, _ = run_cli(["render", "--model", "rough-dielectric", "--material", "glass", "--micro-alpha", "0.2",
                             "--ndf", "ggx", "--nano", NANO, "--wavelength-step", "470nm", "--variant", "llvm_ad_rgb",
                             "--sphere-size", "8", "--spp", "2", "--no-ground", "-o", str(out)])
    assert rc == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["model"]["model"] == "rough-dielectric" and s["model"]["nano"] == NANO
    assert s["bsdf"] == "plugin" and s["reference"] == "roughdielectric"
    assert any("first-order scatter" in n for n in s["reference_notes"])
    on = sphere_mask(8)
    for name in ("wave", "reference"):
        ch, _ = read_exr(out / f"{name}.exr")
        rgb = ch["RGB"] if "RGB" in ch else np.stack([ch["R"], ch["G"], ch["B"]], -1)
        assert np.all(np.isfinite(rgb)) and rgb[on].mean() > 0.01, name


def test_render_job_refuses_what_the_glass_does_not_take_naming_fields(tmp_path):
    from waveoptics.errors import FieldError
    from waveoptics.renderers.jobs import render_job
    from waveoptics.renderers.requests import RenderRequest

    glass = dict(model="rough-dielectric", material="glass", nano="none", wavelength_step="470nm",
                 variant="llvm_ad_rgb", sphere_size=8, spp=1)
    for request, fields in ((RenderRequest(**dict(glass, model="nope")), ("model",)),
                            (RenderRequest(**dict(glass, kd=0.5)), ("model", "kd")),
                            (RenderRequest(**dict(glass, bsdf="native")), ("bsdf", "model")),
                            (RenderRequest(**dict(glass, material="gold")), ("material",))):
        with pytest.raises(FieldError) as exc:
            render_job(request, tmp_path / "o", overwrite=True)
        assert exc.value.fields[:len(fields)] == fields and "--" not in str(exc.value), str(exc.value)


@pytest.mark.parametrize("variant", ["llvm_ad_mono", "scalar_spectral_polarized"])
def test_mono_and_polarized_variants_are_refused_in_one_line(variant):
    from waveoptics.errors import WaveopticsError
    from waveoptics.renderers.mitsuba_glass import register_glass

    with pytest.raises(WaveopticsError, match="no form for Mitsuba variant") as exc:
        register_glass(variant)
    assert "\n" not in str(exc.value)


def test_render_command_takes_the_nano_frame(tmp_path):
    """``render --model rough-dielectric --nano-frame facet`` (8² px, 1 spp): the two-scale glass (nano lobes in each
    facet's frame) renders, its summary names the frame, and the sphere differs from the default macro frame's
    (the same seeds: only the model differs); the twoscale model refuses the option, naming both fields."""
    import json

    from cli_helpers import run_cli

    from waveoptics.errors import FieldError
    from waveoptics.io.files import read_exr
    from waveoptics.renderers.jobs import render_job
    from waveoptics.renderers.requests import RenderRequest
    from waveoptics.renderers.scene import sphere_mask

    base = ["render", "--model", "rough-dielectric", "--material", "glass", "--micro-alpha", "0.3", "--ndf", "ggx",
            "--nano", NANO, "--wavelength-step", "470nm", "--variant", "llvm_ad_rgb", "--sphere-size", "8", "--spp",
            "1", "--no-ground"]
    rgb = {}
    for frame in ("macro", "facet"):
        out = tmp_path / frame
        extra = [] if frame == "macro" else ["--nano-frame", frame]
        rc, _, err, _ = run_cli(base + extra + ["-o", str(out)])
        assert rc == 0, err
        s = json.loads((out / "summary.json").read_text())
        assert s["model"]["nano_frame"] == frame, s["model"]
        ch, _ = read_exr(out / "wave.exr")
        rgb[frame] = ch["RGB"] if "RGB" in ch else np.stack([ch["R"], ch["G"], ch["B"]], -1)
    on = sphere_mask(8)
    assert np.all(np.isfinite(rgb["facet"])) and rgb["facet"][on].mean() > 0.01
    assert np.max(np.abs(rgb["facet"][on] - rgb["macro"][on])) > 1e-4
    with pytest.raises(FieldError) as exc:
        render_job(RenderRequest(nano_frame="facet", sphere_size=8, spp=1, variant="llvm_ad_rgb"), tmp_path / "t",
                   overwrite=True)
    assert exc.value.fields[:2] == ("nano_frame", "model"), str(exc.value)


COATED = "BK7|MgF2:100nm"


@functools.lru_cache(maxsize=None)
def _coated_plugin(variant):
    """The coated rough glass (BK7 under 100 nm of MgF₂, GGX α 0.3, no nano-roughness) in the glass plugin."""
    from waveoptics import brdf
    from waveoptics.renderers.mitsuba_glass import register_glass

    base = brdf.RoughDielectricBSDF(COATED, brdf.Micro(alpha=0.3, ndf="ggx", shadowing="smith-correlated"))
    return register_glass(variant, model=brdf.SpectralNodes(base, NODES), name="wo_coated_test")


@pytest.mark.parametrize("theta_deg", [40.0, 145.0])
def test_a_coated_glass_passes_mitsubas_chi2_and_refracts_into_its_substrate(theta_deg):
    """A thin-film stack on the glass (issue 33): Mitsuba's χ² accepts sample and pdf over the sphere, from outside
    and from inside, and the transmitted samples carry the substrate's relative index (BK7's own, from the
    material database, not the stack's code): the films change what a facet reflects and transmits, not the medium
    the light refracts into."""
    import drjit as dr

    from waveoptics.materials import get_material

    mi = _coated_plugin("llvm_ad_rgb")
    t = np.radians(theta_deg)
    wi = _assert_chi2(mi, "wo_coated_test", theta_deg)
    bsdf = mi.load_dict({"type": "wo_coated_test"})
    rng = np.random.default_rng(3)
    n = 4000
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = wi
    bs, _ = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.uniform(size=n).astype(np.float32)),
                        mi.Point2f(rng.uniform(size=(2, n)).astype(np.float32)))
    wo_z, eta = np.array(bs.wo.z, dtype=float), np.array(bs.eta, dtype=float)
    crossed = (wo_z * np.cos(t) < 0) & (np.array(bs.pdf, dtype=float) > 0)
    assert crossed.sum() > 100
    n_bk7 = np.real(get_material("BK7").eta(np.array(NODES)))
    want = n_bk7 if np.cos(t) > 0 else 1.0 / n_bk7
    assert np.all(np.min(np.abs(eta[crossed][:, None] - want[None, :]), axis=1) < 1e-5)


def test_render_command_takes_a_coated_glass(tmp_path):
    """``waveoptics render --model rough-dielectric --material 'BK7|MgF2:100nm' --nano none``: the glass plugin
    beside Mitsuba's roughdielectric of the bare substrate, which the notes name."""
    import json

    from cli_helpers import run_cli

    out = tmp_path / "o"
    rc, _, err, _ = run_cli(["render", "--model", "rough-dielectric", "--material", COATED, "--micro-alpha", "0.2",
                             "--ndf", "ggx", "--nano", "none", "--wavelength-step", "470nm", "--variant",
                             "llvm_ad_rgb", "--sphere-size", "8", "--spp", "2", "--no-ground", "-o", str(out)])
    assert rc == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["bsdf"] == "plugin" and s["reference"] == "roughdielectric"
    assert any("bare substrate BK7" in n for n in s["reference_notes"])
