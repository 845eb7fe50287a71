"""Fresnel reflectance against closed-form limits, and the OpenCL twin against NumPy."""
import numpy as np
import pytest

from waveoptics.materials import fresnel
from waveoptics.errors import WaveopticsError
from conftest import KERNEL_ATOL

ETAS = [1.0 + 0j, 1.333 + 0j, 1.5 + 0j, 2.42 + 0j, 0.2 + 3.1j, 0.47 + 2.4j, 1.4 + 7.5j, 10 + 100j, 0.7 + 0j,
        2.9 + 0.3j]


@pytest.mark.parametrize("eta", ETAS)
def test_normal_incidence_matches_closed_form(eta):
    n, k = eta.real, eta.imag
    expect = ((n - 1) ** 2 + k ** 2) / ((n + 1) ** 2 + k ** 2)
    assert fresnel.F(1.0, eta) == pytest.approx(expect, abs=1e-12)
    assert fresnel.F0(eta) == pytest.approx(expect, abs=1e-12)


@pytest.mark.parametrize("eta", ETAS)
def test_grazing_incidence_reflects_everything(eta):
    # R -> 1 as theta -> 90 deg (exactly 1 at cos = 0); continuous approach from 89.9999 deg
    assert fresnel.F(0.0, eta) == 1.0
    c = np.cos(np.radians(89.9999))
    assert fresnel.F(c, eta) > 0.99 or eta == 1.0 + 0j


@pytest.mark.parametrize("n", [1.2, 1.5, 2.0, 3.5])
def test_conductor_with_zero_k_equals_dielectric_formula(n):
    th = np.radians(np.linspace(0, 89.9, 200))
    ci = np.cos(th)
    st = np.sin(th) / n
    ct = np.sqrt(1 - st ** 2)
    rs = ((ci - n * ct) / (ci + n * ct)) ** 2
    rp = ((n * ci - ct) / (n * ci + ct)) ** 2  # Born & Wolf 1.5 (20)
    Rs, Rp = fresnel.F_sp(ci, n + 0j)
    np.testing.assert_allclose(Rs, rs, atol=1e-13)
    np.testing.assert_allclose(Rp, rp, atol=1e-13)


@pytest.mark.parametrize("n", [1.333, 1.5, 2.42])
def test_p_reflectance_vanishes_at_brewster(n):
    _, Rp = fresnel.F_sp(np.cos(fresnel.brewster_angle(n)), n)
    assert Rp < 1e-20


def test_total_internal_reflection_for_n_below_one():
    n = 1 / 1.5
    crit = np.arcsin(n)
    th = np.linspace(crit + 1e-6, np.pi / 2, 50)
    np.testing.assert_allclose(fresnel.F(np.cos(th), n), 1.0, atol=1e-12)


def test_no_interface_no_reflection():
    th = np.radians(np.linspace(0, 89.0, 90))
    np.testing.assert_allclose(fresnel.F(np.cos(th), 1.0), 0.0, atol=1e-15)


def test_bounded_everywhere_including_extreme_angles():
    th = np.radians(np.array([0, 1e-6, 30, 60, 89, 89.9, 89.999, 89.9999, 90]))
    cos = np.concatenate([np.cos(th), [-0.5, 1.0 + 1e-12]])
    for eta in ETAS:
        r = fresnel.F(cos, eta)
        assert np.all(np.isfinite(r)) and np.all((r >= 0) & (r <= 1))


@pytest.mark.parametrize("n, bound", [(1.3, 0.07), (1.4, 0.05), (1.5, 0.037), (1.6, 0.033), (1.8, 0.036),
                                      (2.0, 0.045), (2.42, 0.077)])
def test_schlick_error_bound_for_dielectrics(n, bound):
    """Schlick vs exact: max abs error over 0-90 deg (it peaks near 84 deg); bounds documented in docs."""
    c = np.cos(np.radians(np.linspace(0, 90, 9001)))
    err = np.abs(fresnel.F_schlick(c, fresnel.F0(n)) - fresnel.F(c, n))
    assert err.max() < bound
    assert err.max() > 0.6 * bound  # it is an approximation: the bound is tight, not vacuous
    assert err[c > 0.5].max() < 0.025  # within 60 deg of the normal the error stays below 0.025


def test_invalid_index_rejected():
    with pytest.raises(WaveopticsError, match="extinction"):
        fresnel.F(1.0, 1.5 - 0.1j)
    with pytest.raises(WaveopticsError, match="real part"):
        fresnel.F(1.0, -1.5)


@pytest.mark.opencl
def test_opencl_twin_matches_numpy(rt, precision, rng):
    cos = np.concatenate([rng.uniform(0, 1, 2000), [0.0, 1.0, -0.1, np.cos(np.radians(89.9999))]])
    etas = np.array(ETAS)[rng.integers(0, len(ETAS), cos.size)]
    Rs, Rp = fresnel.F_sp(cos, etas)
    cRs, cRp, cR = fresnel.F_sp_cl(cos, etas, runtime=rt, precision=precision)
    tol = KERNEL_ATOL[precision] * (50 if precision == "float32" else 1)  # k = 100 loses digits in float32
    np.testing.assert_allclose(cRs, Rs, atol=tol)
    np.testing.assert_allclose(cRp, Rp, atol=tol)
    np.testing.assert_allclose(cR, 0.5 * (Rs + Rp), atol=tol)
    f0 = rng.uniform(0, 1, cos.size)
    np.testing.assert_allclose(fresnel.F_schlick_cl(cos, f0, runtime=rt, precision=precision),
                               fresnel.F_schlick(cos, f0), atol=KERNEL_ATOL[precision])


def test_facet_polarized_reflectance_by_projecting_the_field():
    """Out of the plane of incidence, the s field of the macro frame projected on the facet's own s and p
    directions (a Jones-vector construction written here) gives the library's F_s and F_p (Priest & Germer 2000)."""
    from waveoptics.units import direction_from_angles

    eta = 0.2 + 3.1j
    wi = direction_from_angles(40.0, 25.0)
    for wo in direction_from_angles(np.array([10.0, 35.0, 70.0]), np.array([120.0, 260.0, 200.0])):
        h = (wi + wo) / np.linalg.norm(wi + wo)
        cos_d = float(h @ wi)
        rs, rp = fresnel.F_sp(cos_d, eta)
        e_s = np.cross([0.0, 0.0, 1.0], wi)
        e_s /= np.linalg.norm(e_s)                       # macro s field, in the incident wavefront
        e_p = np.cross(wi, e_s)                          # macro p field, in the incident wavefront
        t_s = np.cross(h, wi)
        t_s /= np.linalg.norm(t_s)                       # facet s direction
        t_p = np.cross(wi, t_s)                          # facet p direction (also in the wavefront)
        for field, pol in ((e_s, "s"), (e_p, "p")):
            ref = float(rs) * float(field @ t_s) ** 2 + float(rp) * float(field @ t_p) ** 2
            got = float(fresnel.F_facet_polarized(wi, wo, eta, pol))
            assert got == pytest.approx(ref, rel=1e-12)


def test_relative_facet_fresnel_is_the_facet_reflectance_over_the_specular_one():
    """RelativeFacetFresnel (the weight of a nano lobe's light in the share it scatters): 1 in the mirror direction
    for unpolarized, s and p light, and F(θ_h)/F(θ_i) elsewhere, with F from the Fresnel equations written here
    (Born & Wolf §13.4) for n = 1.5 + 0.02i."""
    from waveoptics.materials import RelativeFacetFresnel, get_material

    mat = get_material("1.5+0.02j")
    n = 1.5 + 0.02j

    def F(c):
        t = np.sqrt(n * n - (1 - c * c))
        return 0.5 * (abs((c - t) / (c + t)) ** 2 + abs((n * n * c - t) / (n * n * c + t)) ** 2)

    wi = np.array([np.sin(0.6), 0.0, np.cos(0.6)])
    mirror = wi * np.array([-1.0, -1.0, 1.0])
    for pol in ("unpolarized", "s", "p"):
        assert float(RelativeFacetFresnel(mat, pol).at(wi, mirror, 550.0)) == pytest.approx(1.0, abs=1e-12)
    wo = np.array([0.3, 0.4, np.sqrt(1 - 0.25)])
    h = (wi + wo) / np.linalg.norm(wi + wo)
    ratio = float(RelativeFacetFresnel(mat).at(wi, wo, 550.0))
    assert ratio == pytest.approx(F(float(h @ wi)) / F(wi[2]), rel=1e-9)
    assert float(RelativeFacetFresnel(None).at(wi, wo, 550.0)) == 1.0
