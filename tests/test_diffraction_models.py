"""Diffraction models (issue 13): Kirchhoff, GHS, RGHS, OHS, ROHS (docs/physics.md §10). Each factor against its
formula written here, the flat-patch limit (albedo = F for every model), the σ → 0 limit (the same coherent lobe and
specular fraction), the frozen phase of OHS solved exactly by one transform, and the order of the differences on a
rough surface (the reference code of Yan et al. 2018 measures OHS and ROHS furthest from Kirchhoff, RGHS closest)."""
from __future__ import annotations

import numpy as np
import pytest

from waveoptics import scatter, surfaces
from waveoptics.units import direction_from_angles

LAM = 550.0
MODELS = ("kirchhoff", "ghs", "rghs", "ohs", "rohs")


def factor_reference(name, ci, co, s2, lam_m):
    if name == "kirchhoff":
        return s2 ** 2 / (4 * lam_m ** 2 * ci * co * (ci + co) ** 2)
    if name in ("ghs", "ohs"):
        return co / (lam_m ** 2 * ci)
    return (ci + co) ** 2 / (4 * lam_m ** 2 * ci * co)


@pytest.mark.parametrize("name", MODELS)
def test_factors_match_their_formulas_and_agree_at_the_mirror(name):
    wi = direction_from_angles(35.0, 10.0)
    wo = direction_from_angles(np.array([0.0, 20.0, 50.0, 80.0]), np.array([190.0, 100.0, 0.0, 250.0]))
    K = scatter.DIFFRACTION_MODELS[name].K(wi, wo, LAM)
    s2 = np.sum((wi + wo) ** 2, axis=-1)
    np.testing.assert_allclose(K, factor_reference(name, wi[2], wo[:, 2], s2, LAM * 1e-9), rtol=1e-12)
    mirror = np.array([-wi[0], -wi[1], wi[2]])
    assert float(scatter.DIFFRACTION_MODELS[name].K(wi, mirror, LAM)) == pytest.approx(1 / (LAM * 1e-9) ** 2)
    assert float(scatter.DIFFRACTION_MODELS[name].K(wi, np.array([0.0, 1.0, 0.0]), LAM)) == 0.0   # horizon


@pytest.mark.parametrize("name", MODELS)
def test_flat_patch_reflects_fresnel_in_every_model(name):
    hf = surfaces.flat(28.8e-6, 128)
    res = scatter.scatter(hf, (30.0, 0.0), [LAM], 0.9, resolution=128, diffraction=name)
    assert res.albedo[0] == pytest.approx(0.9, rel=2e-3)
    assert res.info["diffraction"] == name


def test_smooth_limit_gives_the_same_coherent_lobe_in_every_model():
    hf = surfaces.gaussian(0.05e-9, 1e-6, 32e-6, 128, seed=3)
    results = {m: scatter.scatter(hf, (30.0, 0.0), [LAM], 1.0, resolution=96, diffraction=m) for m in MODELS}
    ref = results["kirchhoff"]
    for m, r in results.items():
        assert r.coherent_specular_fraction[0] == pytest.approx(1.0, abs=1e-4)
        assert r.albedo[0] == pytest.approx(ref.albedo[0], rel=2e-3)
    # PSD route: the scattered lobe vanishes as σ² when σ → 0 in every model (first order)
    wo = direction_from_angles(np.array([20.0, 40.0]), 180.0)
    wi = direction_from_angles(30.0, 0.0)
    for m in MODELS:
        small, ref_ = (scatter.scattered_lobe(wi, wo, LAM, surfaces.PSDModel("gaussian", sigma=s, T=1e-6),
                                              diffraction=m) for s in (1e-12, 1e-9))
        np.testing.assert_allclose(small / ref_, 1e-6, rtol=1e-3)


def test_ohs_frozen_phase_is_one_exact_transform(rt):
    hf = surfaces.gaussian(30e-9, 1e-6, 64 * 137.5e-9, 64, seed=1)
    smp = scatter.samples(hf)
    wi = direction_from_angles(40.0, 0.0)
    grid = scatter.DirectionGrid.hemisphere(48)
    U, info = scatter.field_fft(smp, wi, grid, LAM, frozen_cos_sum=2.0)
    assert info["bands"] == 1 and info["transforms"] == 1
    d = grid.directions()[grid.inside]
    coef = scatter.phase_coefficients(smp, wi, d, [LAM], frozen_cos_sum=2.0)
    np.testing.assert_allclose(U[grid.inside], scatter.kirchhoff_U(smp, coef), rtol=1e-9,
                               atol=1e-9 * float(np.sum(smp.w)) * smp.dx * smp.dy)


def test_models_part_from_kirchhoff_in_the_documented_order():
    """One rough Gaussian surface at θ_i = 30°: the lobes' relative L2 distance from Kirchhoff is smallest for RGHS
    and largest for the OHS family, as in the reference code of Yan et al. 2018 (docs/physics.md §10)."""
    hf = surfaces.gaussian(60e-9, 1.2e-6, 128 * 137.5e-9, 128, seed=2)
    res = {m: scatter.scatter(hf, (30.0, 0.0), [LAM], 1.0, resolution=96, diffraction=m).brdf[0] for m in MODELS}
    ref = res["kirchhoff"]
    dist = {m: float(np.linalg.norm(res[m] - ref) / np.linalg.norm(ref)) for m in MODELS if m != "kirchhoff"}
    assert dist["rghs"] < dist["ghs"] < min(dist["ohs"], dist["rohs"])
    assert dist["rghs"] < 0.05


def test_unknown_model_is_refused_naming_the_allowed_ones():
    with pytest.raises(ValueError, match="unknown diffraction model 'hs'.*allowed: ghs, kirchhoff, ohs, rghs, rohs"):
        scatter.scatter(surfaces.flat(8e-6, 32), (0.0, 0.0), [LAM], resolution=16, diffraction="hs")


def test_one_vocabulary_and_every_front_end(tmp_path, capsys):
    """The CLI choices are the registry's names; simulate, scatter and the request take the model and say which."""
    import json

    from waveoptics import vocabulary
    from waveoptics.cli import main
    from waveoptics.errors import FieldError
    from waveoptics.request import SimulationRequest

    assert tuple(scatter.DIFFRACTION_MODELS) == vocabulary.DIFFRACTION
    with pytest.raises(FieldError, match="unknown diffraction 'hs'"):
        SimulationRequest(diffraction="hs")
    out = tmp_path / "sim"
    assert main(["simulate", "-o", str(out), "--wavelengths", "450,650", "--resolution", "24", "--no-spheres",
                 "--diffraction", "ghs", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["parameters"]["diffraction"] == "ghs"
    hf = tmp_path / "h.npz"
    surfaces.save(surfaces.gaussian(20e-9, 1e-6, 16e-6, 64, seed=1), hf)
    assert main(["scatter", "--surface", str(hf), "--material", "Al", "--incident", "20", "--wavelengths", "550",
                 "--resolution", "32", "--diffraction", "rghs", "-o", str(tmp_path / "sc"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["info"]["diffraction"] == "rghs"


def test_polarized_flat_patch_reflects_rs_and_rp():
    """Polarized incident light (issue 13): a flat patch reflects R_s(θ_i) or R_p(θ_i) of the Fresnel equations,
    written here from Born & Wolf, and their mean unpolarized; rough lobes average to the unpolarized one."""
    import cmath
    import math

    n = 1.5 + 0.0j
    theta = math.radians(50.0)
    ct = cmath.sqrt(1 - (math.sin(theta) / n) ** 2)
    rs = abs((math.cos(theta) - n * ct) / (math.cos(theta) + n * ct)) ** 2
    rp = abs((n * math.cos(theta) - ct) / (n * math.cos(theta) + ct)) ** 2
    hf = surfaces.flat(28.8e-6, 128)
    got = {p: scatter.scatter(hf, (50.0, 0.0), [LAM], "1.5", resolution=128, polarization=p).albedo[0]
           for p in ("s", "p", "unpolarized")}
    assert got["s"] == pytest.approx(rs, rel=5e-3)
    assert got["p"] == pytest.approx(rp, rel=2e-2)          # R_p is small here: the spike's F(θ_d) spread matters
    assert got["unpolarized"] == pytest.approx(0.5 * (rs + rp), rel=5e-3)
    rough = surfaces.gaussian(40e-9, 1e-6, 32e-6, 128, seed=1)
    lobes = {p: scatter.scatter(rough, (30.0, 20.0), [LAM], "Au", resolution=64, polarization=p).brdf[0]
             for p in ("s", "p", "unpolarized")}
    np.testing.assert_allclose(0.5 * (lobes["s"] + lobes["p"]), lobes["unpolarized"], rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="complex index"):
        scatter.scatter(hf, (50.0, 0.0), [LAM], 0.9, resolution=16, polarization="s")
