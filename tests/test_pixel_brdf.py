"""Per-pixel footprint BRDFs (waveoptics.scatter.pixel) at real footprint sizes against direct sums written here:
the windowed Kirchhoff integral in float64 (np.exp over complex128), the patch NDF, coherence windows, and the
closed form of a flat Gaussian footprint."""
import math

import numpy as np
import pytest

from waveoptics.surfaces import Footprint, footprint_box, tiled
from waveoptics.scatter import pixel

DX = 0.1e-6
SIG = 5e-6           # footprint width
LAM = 550.0


@pytest.fixture(scope="module")
def field():
    """A 1 mm × 1 mm Gaussian random field (σ = 20 nm, T = 1 µm) at 0.1 µm: 10⁸ samples, generated per patch."""
    return tiled.PSDField("gaussian", 20e-9, 1e-6, (10000, 10000), DX, seed=17)


def _dir(u, v):
    return np.array([u, v, math.sqrt(1 - u * u - v * v)])


def _reference_f(field, fp_x, fp_y, sig, wi, wo, lam_nm):
    """f = K |ΔxΔy Σ G e^{ik s·r}|² / (Σ G² ΔxΔy), K = |s|⁴/(4 λ² cos θ_i cos θ_o (cos θ_i + cos θ_o)²) (Beckmann &
    Spizzichino 1963 ch. 3 with a Gaussian window, Yan et al. 2018 eq. 6), over the samples within 3√2 σ of the
    centre (the footprint truncated to its circle r²/σ² ≤ 18, G ≥ e⁻⁹; samples on the circle itself count, to
    1e-9 of 18: centres on the grid put lattice points there), in float64 with np.exp of complex128; wo (n, 3)."""
    i0, i1 = math.floor((fp_x - 4.5 * sig) / DX), math.ceil((fp_x + 4.5 * sig) / DX) + 1
    j0, j1 = math.floor((fp_y - 4.5 * sig) / DX), math.ceil((fp_y + 4.5 * sig) / DX) + 1
    h = field.patch(i0, j0, i1 - i0, j1 - j0).heights
    X = (i0 + np.arange(i1 - i0))[None, :] * DX - fp_x
    Y = (j0 + np.arange(j1 - j0))[:, None] * DX - fp_y
    G = np.exp(-(X * X + Y * Y) / (2 * sig * sig)) * ((X * X + Y * Y) / (sig * sig) <= 18 * (1 + 1e-9))
    lam = lam_nm * 1e-9
    out = []
    for w in np.atleast_2d(wo):
        s = wi + w
        U = np.sum(G * np.exp(2j * np.pi / lam * (s[0] * X + s[1] * Y + s[2] * h))) * DX * DX
        K = np.dot(s, s) ** 2 / (4 * lam ** 2 * wi[2] * w[2] * (wi[2] + w[2]) ** 2)
        out.append(K * abs(U) ** 2 / (np.sum(G * G) * DX * DX))
    return np.array(out)


def _grid():
    """11 × 11 direction cosines around the mirror direction of ω_i = (0.3, 0.1), step 0.006 (the coherent peak's
    width λ/(2πσ) is 0.018)."""
    u = -0.3 + 0.006 * np.arange(-5, 6)
    v = -0.1 + 0.006 * np.arange(-5, 6)
    U, V = np.meshgrid(u, v)
    return np.array([_dir(a, b) for a, b in zip(U.ravel(), V.ravel())])


FP5 = Footprint(503.37e-6, 251.91e-6, SIG)


@pytest.fixture(scope="module")
def reference(field):
    return _reference_f(field, FP5.x, FP5.y, SIG, _dir(0.3, 0.1), _grid(), LAM)


@pytest.mark.parametrize("backend,precision,tol_energy,tol_peak", [
    ("opencl", "float64", 1e-9, 1e-9), ("opencl", "float32", 1e-4, 1e-3), ("numpy", None, 1e-9, 1e-9)])
def test_sigma_5um_footprint_matches_a_float64_direct_sum(field, reference, backend, precision, tol_energy,
                                                          tol_peak):
    """σ = 5 µm (a box of 401² samples) at 121 directions about the mirror direction (the NumPy twin at the central
    25): energy Σ f du dv and peak."""
    wi = _dir(0.3, 0.1)
    wo, ref = _grid(), reference
    if backend == "numpy":
        keep = (np.abs(np.arange(121) % 11 - 5) <= 2) & (np.abs(np.arange(121) // 11 - 5) <= 2)
        wo, ref = wo[keep], ref[keep]
    fp = FP5
    r = pixel.pixel_brdf(field, [fp] * len(wo), wi, wo, [LAM], None, backend=backend, precision=precision)
    assert r.ok.all()
    f = r.wave[:, 0]
    assert abs(np.sum(f) / np.sum(ref) - 1) < tol_energy
    assert abs(f.max() / ref.max() - 1) < tol_peak
    assert np.argmax(f) == np.argmax(ref)
    assert np.max(np.abs(f - ref)) / ref.max() < 10 * tol_peak


def test_three_wavelengths_and_the_geometric_ndf(field):
    """Each wavelength at its own k; the patch NDF P22 = Σ G N(∇h − t; σ_s²)/Σ G with central differences,
    D = P22/cos⁴θ_h, f = D/(4 cos θ_i cos θ_o) (Yan et al. 2016; Heitz 2014)."""
    wi, wo = _dir(0.2, -0.3), _dir(-0.25, 0.28)
    fp = Footprint(300.02e-6, 700.4e-6, 3e-6)
    lam = [450.0, 550.0, 650.0]
    fw, fg = pixel.footprint_brdf(field, fp, wi, wo, lam, None, slope_sigma=0.02, precision="float64")
    for k, l in enumerate(lam):
        assert fw[k] == pytest.approx(_reference_f(field, fp.x, fp.y, 3e-6, wi, wo, l)[0], rel=1e-9)
    i0, i1 = math.floor((fp.x - 13.5e-6) / DX), math.ceil((fp.x + 13.5e-6) / DX) + 1
    j0, j1 = math.floor((fp.y - 13.5e-6) / DX), math.ceil((fp.y + 13.5e-6) / DX) + 1
    h = field.patch(i0 - 1, j0 - 1, i1 - i0 + 2, j1 - j0 + 2).heights
    gx = (h[1:-1, 2:] - h[1:-1, :-2]) / (2 * DX)
    gy = (h[2:, 1:-1] - h[:-2, 1:-1]) / (2 * DX)
    X = (i0 + np.arange(i1 - i0))[None, :] * DX - fp.x
    Y = (j0 + np.arange(j1 - j0))[:, None] * DX - fp.y
    G = np.exp(-(X * X + Y * Y) / (2 * 9e-12)) * ((X * X + Y * Y) / 9e-12 <= 18 * (1 + 1e-9))       # the 3√2 σ circle
    hv = (wi + wo) / np.linalg.norm(wi + wo)
    t = -hv[:2] / hv[2]
    N = np.exp(-((gx - t[0]) ** 2 + (gy - t[1]) ** 2) / (2 * 0.02 ** 2)) / (2 * np.pi * 0.02 ** 2)
    D = np.sum(G * N) / np.sum(G) / hv[2] ** 4
    assert fg == pytest.approx(np.full(3, D / (4 * wi[2] * wo[2])), rel=1e-9)


def test_coherence_windows_add_as_intensities(field):
    """σ_c = 2 µm over a σ = 5 µm footprint: f = Σ_k w_k f_k over windows on the lattice c + σ_c (m, n), |m|, |n| ≤
    ⌊2σ/σ_c⌋, w_k ∝ G(c_k) (Yan et al. 2018 §4), each f_k the direct sum of a window of width σ_c."""
    wi, wo = _dir(0.3, 0.1), _dir(-0.31, -0.1)
    fp = Footprint(411.1e-6, 622.2e-6, SIG)
    f, _ = pixel.footprint_brdf(field, fp, wi, wo, [LAM], None, coherence_m=2e-6, precision="float64")
    m = np.arange(-5, 6)
    ref, wsum = 0.0, 0.0
    for a in m:
        for b in m:
            cx, cy = fp.x + 2e-6 * a, fp.y + 2e-6 * b
            w = math.exp(-((cx - fp.x) ** 2 + (cy - fp.y) ** 2) / (2 * SIG ** 2))
            ref += w * _reference_f(field, cx, cy, 2e-6, wi, wo, LAM)[0]
            wsum += w
    assert f[0] == pytest.approx(ref / wsum, rel=1e-9)
    coherent, _ = pixel.footprint_brdf(field, fp, wi, wo, [LAM], None, precision="float64")
    assert coherent[0] != pytest.approx(f[0], rel=1e-3)


def test_flat_footprint_equals_the_closed_form():
    """A flat field: f = K 4π σ² exp(−q²σ²), q = k (s_x, s_y) (the Fourier transform of a Gaussian), to the
    window's truncation (it keeps 1 − e⁻⁹ of Σ G, so the peak is 2 e⁻⁹ = 2.5e-4 low)."""
    flat = tiled.PSDField("gaussian", 0.0, 1e-6, (2000, 2000), DX)
    wi = _dir(0.3, 0.1)
    wo = np.array([_dir(-0.3 + d, -0.1) for d in (0.0, 0.004, 0.01, 0.02)])
    r = pixel.pixel_brdf(flat, [Footprint(100e-6, 100e-6, SIG)] * 4, wi, wo, [LAM], None)
    k = 2 * np.pi / (LAM * 1e-9)
    s = wi + wo
    q2 = k * k * (s[:, 0] ** 2 + s[:, 1] ** 2)
    K = np.sum(s * s, axis=1) ** 2 / (4 * (LAM * 1e-9) ** 2 * wi[2] * wo[:, 2] * (wi[2] + wo[:, 2]) ** 2)
    closed = K * 4 * np.pi * SIG ** 2 * np.exp(-q2 * SIG ** 2)
    assert np.max(np.abs(r.wave[:, 0] - closed)) < 1e-3 * closed[0]


def test_grouping_into_regions_does_not_change_the_result(field):
    rng = np.random.default_rng(3)
    fps = [Footprint(float(x), float(y), float(s)) for x, y, s in
           zip(rng.uniform(100e-6, 200e-6, 12), rng.uniform(100e-6, 140e-6, 12), rng.uniform(1e-6, 3e-6, 12))]
    wi, wo = _dir(0.1, 0.2), _dir(-0.1, -0.21)
    a = pixel.pixel_brdf(field, fps, wi, wo, [500.0, 600.0], "Al", precision="float64")
    b = pixel.pixel_brdf(field, fps, wi, wo, [500.0, 600.0], "Al", precision="float64", max_region_samples=1)
    assert np.allclose(a.wave, b.wave, rtol=1e-12, atol=0) and np.allclose(a.geometric, b.geometric, rtol=1e-12)
    edge = pixel.pixel_brdf(field, [Footprint(1e-6, 5e-6, 1e-6)], wi, wo, [500.0])
    assert not edge.ok[0] and np.isnan(edge.wave[0, 0])


def test_kernel_visits_the_ellipse_and_equals_its_twin(field):
    """Oblique, eccentric, turned footprints (σ_1/σ_2 up to 6): the kernel sums only each footprint's 3√2 σ ellipse
    (q ≤ 18 (1 + 1e-9)), equal to the NumPy twin to float64 rounding (1e-12 of Σ G) with central differences and
    with given slopes, on three wavelengths; the samples it reports are the ellipses' samples counted here by brute
    force over the box (at most π/4 of a box's samples, down to 0.3 of them for these ellipses)."""
    rng = np.random.default_rng(11)
    fps = [Footprint(float(x), float(y), float(s1), float(s1 / e), float(a)) for x, y, s1, e, a in
           zip(rng.uniform(40e-6, 60e-6, 24), rng.uniform(40e-6, 60e-6, 24), rng.uniform(0.5e-6, 2.5e-6, 24),
               rng.uniform(1.0, 6.0, 24), rng.uniform(0.0, 180.0, 24))]
    h = field.patch(0, 0, 1000, 1000).heights
    slopes = (rng.normal(0, 0.05, h.shape), rng.normal(0, 0.05, h.shape))
    s, t = np.array([0.3, -0.2, 1.9]), np.array([0.01, -0.02])
    boxes, geo, counted, in_box = [], [], [], []
    for fp in fps:
        b = footprint_box(fp, DX, DX, 3 * math.sqrt(2))
        Ci = np.linalg.inv(fp.covariance)
        geo.append([fp.x - b[0] * DX, fp.y - b[1] * DX, Ci[0, 0], Ci[0, 1], Ci[1, 1], *s, *t, 18 * (1 + 1e-9), 0.0])
        boxes.append(b)
        X = np.arange(b[0], b[2])[None, :] * DX - fp.x
        Y = np.arange(b[1], b[3])[:, None] * DX - fp.y
        counted.append(int(np.sum(Ci[0, 0] * X * X + 2 * Ci[0, 1] * X * Y + Ci[1, 1] * Y * Y <= 18 * (1 + 1e-9))))
        in_box.append((b[2] - b[0]) * (b[3] - b[1]))
    boxes, geo = np.array(boxes), np.array(geo)
    np.testing.assert_array_equal(pixel.ellipse_samples(fps, DX, DX), counted)
    ratio = np.array(counted) / np.array(in_box)
    assert ratio.min() < 0.35 and ratio.max() < math.pi / 4 + 0.01
    lam = [450.0, 550.0, 650.0]
    for given in (None, slopes):
        cl = pixel.footprint_sums(h, DX, DX, boxes, geo, lam, 0.02, slopes=given, precision="float64")
        tw = pixel.footprint_sums_numpy(h, DX, DX, boxes, geo, lam, 0.02, given)
        W = tw[:, 2 * len(lam) + 1]
        assert np.max(np.abs(cl - tw) / W[:, None]) < 1e-12
        assert np.all(tw[:, -1] > 0)
