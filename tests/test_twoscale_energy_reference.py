"""Issue 28's energy bullet measured against the independent reference: the diffracted light is the light the
coherent part gives up less what masking takes, in the textbook two-scale integral as in the package.

The literal bullet ("diffracted light = light the coherent part gives up, within 1 % for θ_i ≤ 70°; white furnace
(F = 1) ≥ its microfacet albedo") is not a property of the two-scale integral itself. Each facet's nano lobe sends
its light F (1 − A) around the facet's mirror direction, and the height-correlated Smith G2 masks those exits by
1/(1 + Λ(i) + Λ(o)) at each exit o rather than at the mirror direction, and drops the ones below the macro horizon;
the coherent part loses F (1 − A) G2(i, mirror, m) per facet. Near normal incidence the lobe reaches higher θ_o,
where Λ(o) is larger, than the mirror direction (and some of it goes below the horizon): the diffracted light is
less than the coherent loss. From 60° on the mirror directions themselves are the grazing ones and the lobe reaches
lower θ_o: it is more. So the bullet as physics is "diffracted albedo / coherent loss = the reference's ratio", and
"the F = 1 albedo − the microfacet albedo = the reference's gap", each within 1 % of the coherent loss.

Reference (written here and in tests/twoscale_reference.py from the papers; imports nothing from the package but the
facet nano BRDF it integrates, :meth:`TwoScaleBRDF.facet_nano_brdf`, and the coherent fraction A(θ) the coherent
part uses, :meth:`waveoptics.brdf.Nano.coherent_fraction`, whose facet-by-facet agreement is
tests/test_twoscale_facet_frame.py::test_each_facet_scatters_the_light_its_coherent_part_gives_up; or, in
:func:`test_the_ratio_with_the_papers_rayleigh_rice_lobe`, not even those): facets drawn from
the reference's own D(m) cos θ_m sampler, each facet's lobe times the reference's G2 integrated over the facet's
direction-cosine disc by the reference's deterministic quadrature (:func:`facet_energy_terms`); the coherent loss
by the reference's quadrature of its microfacet BRDF minus its coherent part; the same facets' loss at their mirror
directions as a control variate (:func:`reference_energy`). Package albedos by the reference's disc quadrature.

Measured (Al, 550 nm, ABC σ 10 nm, B 2 µm, C 2.6, Beckmann; reference 4000 facets on 16 × 4 facet disc rules,
s.e. ≤ 3.4e-5 absolute, ≤ 0.3 % of the loss; package albedos on the 32 × 4 rule; the tests take 1000-2000 facets on
8 × 4 rules):

====  ====  =======  ========  =========  =========  =======
α     θ_i   D_ref    loss_ref  ratio_ref  ratio_pkg  pkg/ref
====  ====  =======  ========  =========  =========  =======
0.05     0  0.02666  0.02663   1.0012     1.0013     1.0001
0.05    30  0.02029  0.02028   1.0001     1.0005     1.0004
0.05    60  0.01050  0.01054   0.9961     0.9961     1.0000
0.05    70  0.00971  0.00975   0.9962     0.9968     1.0007
0.1      0  0.02643  0.02644   0.9997     0.9991     0.9994
0.1     30  0.02020  0.02023   0.9985     0.9991     1.0006
0.1     60  0.01063  0.01070   0.9935     0.9945     1.0010
0.1     70  0.00981  0.00981   0.9999     1.0009     1.0010
0.3      0  0.02421  0.02468   0.9808     0.9802     0.9994
0.3     30  0.01934  0.01968   0.9827     0.9823     0.9995
0.3     60  0.01164  0.01122   1.0371     1.0383     1.0011
0.3     70  0.01035  0.00975   1.0622     1.0637     1.0013
0.5      0  0.02060  0.02137   0.9640     0.9636     0.9997
0.5     30  0.01788  0.01803   0.9912     0.9908     0.9996
0.5     60  0.01281  0.01231   1.0402     1.0410     1.0008
0.5     70  0.01139  0.01108   1.0273     1.0292     1.0016
====  ====  =======  ========  =========  =========  =======

The reference's own ratio is 0.96-1.06 at α 0.3-0.5 (below 1 up to 30°, above from 60°), within 0.7 % of 1 at
α ≤ 0.1; the package's ratio is the reference's within 0.2 %, its diffracted albedo within 0.16 %. Facets carrying
the papers' first-order Rayleigh-Rice lobe instead, with nothing from the package (:func:`rayleigh_rice_lobe`), give
the same ratios (0.980 / 1.060 at α 0.3, 0° / 70°; 0.966 / 1.039 at α 0.5, 0° / 60°): the ratio is G2's, not the
lobe's.

White furnace (fresnel="one", ABC σ 20 nm as tests/test_tabulated_white_furnace.py; B Beckmann, G GGX):
albedo − microfacet albedo, the reference's D − loss and its s.e. (4000 facets), the pointwise form's (D − (M − C)
on one rule) and the tabulated form's (64² tables, the whole albedo − the reference's microfacet albedo):

======  ====  ========  =========  =====  =========  =========
micro   θ_i   loss_ref  gap_ref    s.e.   pointwise  tabulated
======  ====  ========  =========  =====  =========  =========
B 0.05     0  0.10982   +1.53e-04  8e-07  +1.33e-04  -1.65e-04
B 0.05    30  0.08404   +3.81e-05  4e-07  +6.25e-05  -2.42e-04
B 0.05    60  0.04342   -1.35e-04  1e-06  -1.34e-04  -2.13e-04
B 0.05    70  0.03849   -7.09e-05  3e-06  -3.16e-05  -7.04e-05
B 0.05    80  0.00864   -4.57e-05  2e-06  -2.94e-05  +5.42e-04
B 0.05    85  0.00337   +7.71e-05  3e-06  +7.86e-05  +6.60e-05
B 0.05  89.5  0.00160   +1.04e-05  3e-07  +1.68e-05  +4.11e-04
B 0.3      0  0.10195   -1.20e-03  2e-05  -1.26e-03  -1.33e-03
B 0.3     30  0.08150   -7.06e-04  3e-05  -7.40e-04  -8.26e-04
B 0.3     60  0.04623   +1.06e-03  6e-05  +1.07e-03  +9.97e-04
B 0.3     70  0.03798   +3.12e-04  3e-05  +3.49e-04  +2.74e-04
B 0.3     80  0.02980   -2.93e-04  2e-05  -2.77e-04  -3.78e-04
B 0.3     85  0.02554   -4.80e-04  3e-05  -4.01e-04  -4.93e-04
B 0.3   89.5  0.02164   -4.64e-04  3e-05  -2.83e-04  +9.01e-04
G 0.05     0  0.10867   +6.42e-05  2e-05  -1.25e-04  -4.62e-04
G 0.05    30  0.08358   +2.02e-05  3e-05  -8.67e-05  -4.79e-04
G 0.05    60  0.04388   -6.38e-05  3e-05  -4.09e-05  -2.34e-04
G 0.05    70  0.03802   +9.39e-05  5e-05  +1.38e-04  -1.27e-04
G 0.05    80  0.01242   +1.77e-05  4e-05  +1.53e-04  +6.95e-04
G 0.05    85  0.00771   +2.76e-06  8e-05  +1.83e-04  +2.99e-04
G 0.05  89.5  0.01044   -4.39e-04  2e-04  -2.99e-04  -2.21e-03
======  ====  ========  =========  =====  =========  =========

The textbook integral itself falls 1.2e-3 below the microfacet albedo at B 0.3, 0° (the package 1.26e-3, the
tables 1.33e-3): "≥ the microfacet albedo" is not a bound of the model. The pointwise form is the reference within
1 % of the loss for Beckmann (≤ 0.84 %, at 89.5°), and for G 0.05 within 0.2 % up to 70° and 1.3 % at 89.5° (s.e.
1.9 %); at 80° / 85° it is 1.1 % / 2.3 % over (3.4 / 2.3 s.e.): with 16000 facets the reference's diffracted albedo
is 0.01243 ± 3e-5 / 0.00770 ± 4e-5, the package's 1.2 % / 2.6 % above it with its default 256 facet nodes and
0.01243 / 0.00766 with 2048 (its fixed quadrature of GGX's far facets at grazing light). The tables are the
reference within 0.6 % of the loss up to 70°; from 80° they are up to 1.8e-3 off (G 0.05 at 89.5°, beyond the last
incidence node at 88°; +5.4e-4 at B 0.05, 80°), within the 3e-3 of tests/test_tabulated_white_furnace.py.
"""
from __future__ import annotations

import numpy as np
import pytest

import twoscale_reference as R
from waveoptics import scatter, surfaces
from waveoptics.brdf import MicrofacetBRDF, Micro, Nano, TabulatedTwoScaleBRDF, TwoScaleBRDF
from waveoptics.materials import get_material

LAM = 550.0
NANO = Nano(model=surfaces.PSDModel("abc", 10e-9, B=2e-6, C=2.6))
NANO_20 = Nano(model=surfaces.PSDModel("abc", 20e-9, B=2e-6, C=2.6))
EPS = complex(scatter.permittivity(get_material("aluminium"), LAM))
#: |package − reference| ≤ TOL × the coherent loss + K_SE × (the reference's standard error + its inner rule's error)
TOL, K_SE = 0.01, 3.0
#: the package's albedos: the reference's disc rule at these orders; its error estimate is the change at half the
#: angles (the angles limit it here: halving the radial order instead moves the diffracted albedo by ≤ 4e-4 of itself);
#: the microfacet lobe's rule error cancels in the coherent loss M − C (same rule, same lobe)
PKG_RULE = (32, 4)


def from_facet_frame(w, m):
    """The inverse of :func:`twoscale_reference.to_facet_frame`: the same Rodrigues rotation about v = m × z with the
    opposite angle, x − v × x + v × (v × x) / (1 + c), taking z to m."""
    w, m = np.broadcast_arrays(np.asarray(w, float), np.asarray(m, float))
    v = np.stack([m[..., 1], -m[..., 0], np.zeros_like(m[..., 0])], axis=-1)
    vx = np.cross(v, w)
    return w - vx + np.cross(v, vx) / (1.0 + m[..., 2])[..., None]


def _facet_lobe(f_nano, wi, m, i_m, alpha, ndf, n_angle, n_gauss):
    """I(m) = ∫ f_n(i_m, o_m) G2(i, o, m) d²o_m over facet m's direction-cosine disc (d²o_m = |o·m| dω_o), by the
    reference's :func:`twoscale_reference.disc_quadrature` about the facet's mirror point; exits below the macro
    horizon count 0 (G2 = 0 there). m, i_m: (P, 3)."""
    xy, wq = (np.stack(a) for a in zip(*[R.disc_quadrature(-c[:2], n_angle, n_gauss) for c in i_m]))
    o_m = np.concatenate([xy, np.sqrt(np.clip(1.0 - np.sum(xy * xy, -1), 0.0, 1.0))[..., None]], axis=-1)
    mb = np.broadcast_to(m[:, None], o_m.shape)
    fn = f_nano(np.broadcast_to(i_m[:, None], o_m.shape).reshape(-1, 3), o_m.reshape(-1, 3), LAM)
    g = R.G2(np.broadcast_to(wi, o_m.shape), from_facet_frame(o_m, mb), mb, alpha, ndf)
    return np.sum(wq * np.asarray(fn, float).reshape(wq.shape) * g, axis=1)


def facet_energy_terms(f_nano, scattered, wi, m, alpha, ndf, n_angle=8, n_gauss=4, chunk=256):
    """Per-facet terms of the diffracted albedo and of the coherent loss at facets m drawn with density D(m) cos θ_m.

    Swapping the integrals of the diffracted albedo (Walter et al. 2007's rough-surface integral with a BRDF on each
    facet, integrated over ω_o with cos θ_o; |o·m| dω_o is the area element of the facet's direction-cosine disc):

        D = ∫ f_diff cos θ_o dω_o = ∫ D(m) (i·m)/cos θ_i I(m) dm,  I(m) = ∫ f_n(i_m, o_m) G2(i, o, m) d²o_m;

    the coherent loss ∫ (1 − A) F G2 D(h) / (4 cos θ_i cos θ_o) cos θ_o dω_o with dω_o = 4 (i·h) dω_h (Walter
    et al. 2007 eq. 14) is the same facet sum of L(m) = F (1 − A)(i·m) · G2(i, 2 (i·m) m − i, m).

    Parameters
    ----------
    f_nano : callable (wi (N, 3), wo (N, 3), λ) -> (N,) in 1/sr, the facet's lobe in its own frame
    scattered : callable cos θ -> F(θ) (1 − A(θ)), the light a facet's coherent part gives up
    wi : (3,) unit, macro frame
    m : (n, 3) micro normals drawn by :func:`twoscale_reference.sample_ndf`
    n_angle, n_gauss : the facet disc's rule (:func:`twoscale_reference.disc_quadrature`)

    Returns
    -------
    w, I, L : arrays (n,): D ≈ mean(w I), loss ≈ mean(w L), w = (i·m)⁺ / (cos θ_i cos θ_m)

    References
    ----------
    Walter et al., EGSR 2007, eqs. 8 and 14; Heitz, JCGT 3(2) 2014, eq. 99 (G2).
    """
    n_facets = m.shape[0]
    ci = m @ wi
    on = np.flatnonzero(ci > 0)
    w = np.where(ci > 0, ci / (wi[2] * m[:, 2]), 0.0)
    I, L = np.zeros(n_facets), np.zeros(n_facets)
    i_m = R.to_facet_frame(np.broadcast_to(wi, m.shape), m)
    for a in range(0, on.size, chunk):
        k = on[a:a + chunk]
        I[k] = _facet_lobe(f_nano, wi, m[k], i_m[k], alpha, ndf, n_angle, n_gauss)
        mirror = 2.0 * ci[k, None] * m[k] - wi
        L[k] = scattered(ci[k]) * R.G2(np.broadcast_to(wi, mirror.shape), mirror, m[k], alpha, ndf)
    return w, I, L


def _mean_se(x):
    return float(np.mean(x)), float(np.std(x, ddof=1) / np.sqrt(x.size))


def reference_energy(f_nano, A, F, wi, alpha, ndf="beckmann", n_facets=1000, check=128, seed=1):
    """The reference's coherent loss, diffracted albedo and white-furnace gap at incidence *wi* for facets carrying
    the lobe *f_nano* (the facet frame, 1/sr), coherent fraction *A* and Fresnel factor *F* (callables of cos θ).

    loss = M − C, the reference's quadrature (:func:`twoscale_reference.albedo_quadrature`, ``quad`` its error
    estimate) of its microfacet BRDF with F less its coherent part (:func:`twoscale_reference.coherent_part`);
    D = mean(w I) − β (mean(w L) − loss), the facets' loss w L as a control variate (its mean is loss; β its
    regression coefficient, Glasserman 2004 §4.1: I is close to L, the light masking moves is small), ``se`` its
    standard error; gap = D − loss = (C + D) − M. ``err``: the facet disc rule's error, the first *check* facets'
    mean of w (I − I₂) with I₂ on the rule of twice its orders.

    References
    ----------
    P. Glasserman, *Monte Carlo Methods in Financial Engineering*, Springer 2004, §4.1 (control variates, the
    regression coefficient); Walter et al., EGSR 2007, eq. 20 (the microfacet BRDF); Davies 1954 and
    docs/physics.md §7 (the coherent part).
    """
    def lost(x, y):   # microfacet BRDF with F − coherent part: the albedo of this difference is M − C
        Fd = F(np.clip(np.sum(x * R.half_vector(x, y), -1), 0.0, 1.0))
        return R.microfacet_brdf(x, y, alpha, Fd, ndf) - R.coherent_part(x, y, alpha, A, F, ndf)

    loss, quad = R.albedo_quadrature(lost, wi)
    m = R.sample_ndf(alpha, n_facets, np.random.default_rng(seed), ndf)
    w, I, L = facet_energy_terms(f_nano, lambda c: F(c) * (1.0 - A(c)), wi, m, alpha, ndf)
    x, y = w * I, w * L
    beta = np.cov(x, y)[0, 1] / np.var(y, ddof=1)
    gap = float(np.mean(x) - beta * (np.mean(y) - loss)) - loss
    se = float(np.std(x - beta * y, ddof=2) / np.sqrt(x.size))
    _, I2, _ = facet_energy_terms(f_nano, lambda c: 0.0 * c, wi, m[:check], alpha, ndf, 16, 8)
    err = abs(float(np.mean(x[:check] - w[:check] * I2)))
    return dict(loss=loss, D=loss + gap, gap=gap, se=se, err=err, quad=quad, loss_mc=_mean_se(y))


def package_lobe(b):
    """(f_nano, A, F) of a :class:`TwoScaleBRDF` for :func:`reference_energy`: its facet nano BRDF, the coherent
    fraction its coherent part uses, and F from the reference's Fresnel equations (1 with ``fresnel="one"``)."""
    one = b.fresnel == "one"

    def F(c):
        return np.ones_like(np.asarray(c, float)) if one else R.fresnel_R(c, EPS)

    def A(c):
        return b.nano.coherent_fraction(c, LAM, b.diffraction, None if one else b.material)
    return b.facet_nano_brdf, A, F


def rayleigh_rice_lobe(sigma_nm=10.0, B_nm=2000.0, C=2.6, n_theta=128):
    """(f_nano, A, F) written from the papers alone: the reference's first-order Rayleigh-Rice lobe of the ABC PSD on
    Al (:func:`twoscale_reference.rayleigh_rice_nano`), the coherent fraction A = 1 − TIS(θ)/R(θ), the complement of
    the light that lobe scatters (its total integrated scatter by the reference's quadrature, interpolated in cos θ
    between *n_theta* incidences: within 6e-4 of the quadrature up to 84°, 0.8 % at 89.7°), and the Fresnel
    reflectance R.

    References
    ----------
    Elson & Bennett, JOSA 69(1) 1979; Church, Jenkinson & Zavada, Opt. Eng. 18(2) 1979; Stover 2012 ch. 4.
    """
    psd = R.abc_psd(sigma_nm, B_nm, C)
    mu = np.linspace(1.0, 1e-3, n_theta)
    tis = np.array([R.rayleigh_rice_tis(np.degrees(np.arccos(c)), LAM, psd, EPS, n_angle=64, n_gauss=6)[0] for c in mu])

    def F(c):
        return R.fresnel_R(c, EPS)

    def A(c):
        c = np.clip(np.asarray(c, float), 1e-3, 1.0)
        return 1.0 - np.interp(c, mu[::-1], tis[::-1]) / F(c)
    return R.rayleigh_rice_nano(psd, EPS), A, F


def package_albedos(b, wi, micro):
    """Albedos of the package's diffracted and coherent parts and of its microfacet BRDF (same F) on the reference's
    disc rule (:data:`PKG_RULE`), and the diffracted part's error estimate (the rule at half its angles)."""
    mf = MicrofacetBRDF(b.material, micro, fresnel=b.fresnel)
    n_angle, n_gauss = PKG_RULE
    out = {}
    for key, order in (("rule", (n_angle, n_gauss)), ("half", (n_angle // 2, n_gauss))):
        xy, wq = R.disc_quadrature(-wi[:2], *order)
        wo = np.concatenate([xy, np.sqrt(np.clip(1.0 - np.sum(xy * xy, -1), 0.0, 1.0))[:, None]], axis=-1)
        wib = np.broadcast_to(wi, wo.shape)
        parts = b.eval_parts(wib, wo, LAM)
        out[key] = dict(D=float(wq @ parts["diffraction"]), C=float(wq @ parts["coherent"]),
                        M=float(wq @ mf.eval(wib, wo, LAM)))
    p = out["rule"]
    return dict(p, loss=p["M"] - p["C"], err=abs(p["D"] - out["half"]["D"]))


def _assert_energy(ref, pkg, what):
    """Diffracted albedo, its ratio to the coherent loss and the gap D − loss, package against the reference."""
    noise = K_SE * (ref["se"] + ref["err"]) + pkg["err"]
    ratio_ref, ratio_pkg = ref["D"] / ref["loss"], pkg["D"] / pkg["loss"]
    assert ref["quad"] < 0.25 * TOL * ref["loss"] and pkg["err"] < 0.5 * TOL * pkg["D"], (what, ref["quad"], pkg["err"])
    assert abs(pkg["D"] - ref["D"]) <= TOL * ref["D"] + noise, (what, pkg["D"], ref["D"])
    assert abs(ratio_pkg - ratio_ref) <= TOL * ratio_ref + noise / ref["loss"], (what, ratio_pkg, ratio_ref)
    gap_pkg = pkg["D"] - pkg["loss"]
    assert abs(gap_pkg - ref["gap"]) <= TOL * ref["loss"] + noise, (what, gap_pkg, ref["gap"])


def _energy(micro, nano, theta, fresnel="exact", diffraction="kirchhoff", lobe=None, n_facets=None):
    """The reference's and the package's energies (1000 facets, 2000 from 60° where the light masking moves and its
    variance are larger); the reference carries *lobe* (f_nano, A, F), or the package's own facet lobe."""
    n_facets = n_facets or (2000 if theta >= 60.0 else 1000)
    b = TwoScaleBRDF("aluminium", micro, nano=nano, fresnel=fresnel, diffraction=diffraction)
    wi = R.direction(theta)
    kw = micro.kw()
    ref = reference_energy(*(lobe or package_lobe(b)), wi, kw["alpha"], kw["ndf"], n_facets=n_facets)
    return ref, package_albedos(b, wi, micro)


FAST = [(0.3, 70.0)]


def _assert_not_one(ref):
    """The reference's own ratio is far from 1 (the literal bullet is not the textbook integral's), and the facets'
    loss at their mirror directions is the quadrature's loss (the change of variables ω_o → m) within 3 s.e."""
    assert abs(ref["D"] / ref["loss"] - 1.0) > 0.015
    loss_mc, se = ref["loss_mc"]
    assert abs(loss_mc - ref["loss"]) <= 3.0 * se + ref["quad"]


@pytest.mark.parametrize("alpha,theta", FAST)
def test_diffracted_light_is_the_coherent_loss_less_what_masking_takes(alpha, theta):
    """The package's diffracted albedo, its ratio to the coherent loss (microfacet-with-F albedo − coherent albedo)
    and the difference D − loss equal the reference's within 1 % of the loss + 3 s.e. (module table: ≤ 0.2 %); the
    reference's own ratio is 1.062 here."""
    ref, pkg = _energy(Micro(alpha=alpha, ndf="beckmann"), NANO, theta)
    _assert_energy(ref, pkg, (alpha, theta))
    _assert_not_one(ref)


@pytest.mark.parametrize("alpha,theta", [(0.3, 0.0)])
def test_the_ratio_with_the_papers_rayleigh_rice_lobe(alpha, theta):
    """A reference that takes nothing from the package: facets carrying the reference's own first-order
    Rayleigh-Rice lobe and coherent fraction 1 − TIS/R (:func:`rayleigh_rice_lobe`). Its ratio is the Kirchhoff
    lobe's: 0.9802 / 1.0603 / 0.9656 / 1.0391 (± 0.0000 / 0.0018 / 0.0010 / 0.0017, 4000 facets) at α 0.3, 0° / 70°
    and α 0.5, 0° / 60°, against 0.981 / 1.062 / 0.964 / 1.040 in the module table; and the package's
    ``diffraction="rayleigh-rice"`` form is it within 1 % of the loss + 3 s.e. (measured ratios 0.9797 / 1.0615 /
    0.9652 / 1.0393, diffracted albedos within 0.12 %; the suite runs α 0.3, 0° for time, the other three were
    measured with this test parametrized over them)."""
    ref, pkg = _energy(Micro(alpha=alpha, ndf="beckmann"), NANO, theta, diffraction="rayleigh-rice",
                       lobe=rayleigh_rice_lobe())
    _assert_energy(ref, pkg, ("rayleigh-rice", alpha, theta))
    _assert_not_one(ref)


@pytest.mark.slow
@pytest.mark.parametrize("alpha,theta", [(0.1, 60.0), (0.5, 0.0), (0.5, 60.0)])
def test_energy_table_against_the_reference(alpha, theta):
    """Three more rows of the module table (the ratio below 1 and above it at α 0.5), as the fast test; the whole
    table was measured with this test parametrized over it (the suite's time allows these)."""
    ref, pkg = _energy(Micro(alpha=alpha, ndf="beckmann"), NANO, theta)
    _assert_energy(ref, pkg, (alpha, theta))


def test_white_furnace_gap_is_the_reference_gap():
    """F = 1 (σ 20 nm), Beckmann α 0.3, 0°: the pointwise two-scale albedo − its microfacet albedo equals the
    reference's C + D − M within 1 % of the coherent loss + 3 s.e.: −1.20e-3 ± 2e-5 (reference), −1.26e-3 (package):
    below the microfacet albedo, as the textbook integral is."""
    ref, pkg = _energy(Micro(alpha=0.3, ndf="beckmann"), NANO_20, 0.0, "one")
    _assert_energy(ref, pkg, "white furnace")
    assert ref["gap"] < -0.005 * ref["loss"]


WHITE_SURFACES = [("beckmann", 0.05), ("beckmann", 0.3), ("ggx", 0.05)]
#: the tabulated form's white-furnace gap from 80° on: |tabulated − reference| allowed (measured ≤ 1.8e-3; its
#: lobes are read between incidence nodes, the last one at 88°, tests/test_tabulated_white_furnace.py)
TAB_GRAZING = 2.5e-3


#: the suite's share of the white-furnace table (the whole of it measured with WHITE_SURFACES and 0-89.5°)
WHITE_RUN = [("beckmann", 0.3)]


@pytest.fixture(scope="module", params=WHITE_RUN, ids=[f"{n}-{a}" for n, a in WHITE_RUN])
def white_table(request):
    ndf, alpha = request.param
    micro = Micro(alpha=alpha, ndf=ndf)
    return micro, TabulatedTwoScaleBRDF("aluminium", micro, nano=NANO_20, wavelengths_nm=(LAM,), resolution=64,
                                        fresnel="one")


@pytest.mark.slow
@pytest.mark.parametrize("theta", [60.0, 89.5])
def test_white_furnace_table_against_the_reference(white_table, theta):
    """F = 1 (σ 20 nm): pointwise as the fast test, up to 89.5°. Tabulated (64² tables): albedo − the reference's
    microfacet albedo within 1 % of the coherent loss of the reference's gap up to 70° (measured ≤ 0.6 %), within
    :data:`TAB_GRAZING` from 80° (module table)."""
    micro, tab = white_table
    ref, pkg = _energy(micro, NANO_20, theta, "one")
    _assert_energy(ref, pkg, (micro, theta))
    kw, wi = micro.kw(), R.direction(theta)
    T, eT = R.albedo_quadrature(lambda x, y: tab.eval(x, y, LAM), wi)
    M1, eM1 = R.albedo_quadrature(lambda x, y: R.microfacet_brdf(x, y, kw["alpha"], 1.0, kw["ndf"]), wi)
    allowed = TOL * ref["loss"] if theta <= 70.0 else TAB_GRAZING
    assert abs(T - M1 - ref["gap"]) <= allowed + K_SE * (ref["se"] + ref["err"]) + eT + eM1, (T - M1, ref["gap"])
