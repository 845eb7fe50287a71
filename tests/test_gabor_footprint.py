"""Yan et al. (2018)'s Gabor-kernel evaluation of one footprint (waveoptics.scatter.gabor) and the library's direct
sum (waveoptics.scatter.pixel) against references written here: the closed form of a Gaussian-windowed plane wave
(a tilted plane), a float64 direct sum over a random field's samples, and a direct sum over the surface
h − ½ σ_k² ∇²h that the Gabor evaluation's first-order error predicts (issue 32)."""
import math

import numpy as np
import pytest

from waveoptics.errors import FieldError
from waveoptics.scatter import gabor, pixel
from waveoptics.surfaces import Footprint, generators
from waveoptics.surfaces.heightfield import HeightField

LAM = 500.0
K = 2 * np.pi / (LAM * 1e-9)


def _dir(u, v):
    return np.array([u, v, math.sqrt(1 - u * u - v * v)])


def _K(wi, wo):
    """|s|⁴ / (4 λ² cos θ_i cos θ_o (cos θ_i + cos θ_o)²) (Beckmann & Spizzichino 1963 ch. 3), wo (n, 3)."""
    s = wi + wo
    lam = LAM * 1e-9
    return np.sum(s * s, axis=1) ** 2 / (4 * lam ** 2 * wi[2] * wo[:, 2] * (wi[2] + wo[:, 2]) ** 2)


def _direct_U(h, X, Y, G, dA, wi, wo):
    """ΔxΔy Σ_j G_j e^{i k s·(x_j − c, h_j)} in float64 (np.exp of complex128), one direction at a time."""
    return np.array([np.sum(G * np.exp(1j * K * ((wi + w)[0] * X + (wi + w)[1] * Y + (wi + w)[2] * h))) * dA
                     for w in wo])


# --- (a) a tilted plane: the closed form ---------------------------------------------------------------------

def test_tilted_plane_equals_the_fourier_transform_of_a_gaussian():
    """h = a x + b y + h₀: U = e^{i k s_z h(c)} 2π √det Σ exp(−½ qᵀ Σ q), q = k (s_x + s_z a, s_y + s_z b). An
    elliptical, turned footprint on a grid with Δx ≠ Δy; the Gabor evaluation is exact there (to the box's
    truncation: 3e-9 at 6 widths), the direct sum (its window truncated where G < e⁻⁹) and the Gabor evaluation at
    4 widths are within their truncation (~1.3e-4 of the peak U)."""
    dx, dy, a, b, h0 = 0.1e-6, 0.08e-6, 0.03, -0.02, 5e-9
    ny, nx = 330, 270
    hf = HeightField(a * (np.arange(nx) * dx)[None, :] + b * (np.arange(ny) * dy)[:, None] + h0, dx, dy)
    fp = Footprint(13.03e-6, 13.21e-6, 2e-6, 1.5e-6, 30.0)
    wi = _dir(0.3, 0.1)
    mirror = (-0.3 - 1.9 * a, -0.1 - 1.9 * b)
    wo = np.array([_dir(mirror[0] + du, mirror[1] + dv) for du in (0.0, 0.01, 0.03, 0.1) for dv in (0.0, 0.02)])
    s = wi + wo
    q = np.stack([K * (s[:, 0] + s[:, 2] * a), K * (s[:, 1] + s[:, 2] * b)], axis=1)
    c1, s1 = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    R = np.array([[c1, -s1], [s1, c1]])
    Sigma = R @ np.diag([4e-12, 2.25e-12]) @ R.T
    closed = (np.exp(1j * K * s[:, 2] * (a * fp.x + b * fp.y + h0)) * 2 * np.pi * math.sqrt(np.linalg.det(Sigma))
              * np.exp(-0.5 * np.einsum("ni,ij,nj->n", q, Sigma, q)))
    peak = np.abs(closed).max()
    U6 = gabor.gabor_footprint_field(hf, fp, wi, wo, [LAM], n_sigma=6)[:, 0]
    assert np.max(np.abs(U6 - closed)) < 1e-7 * peak
    U4 = gabor.gabor_footprint_field(hf, fp, wi, wo, [LAM])[:, 0]
    assert np.max(np.abs(U4 - closed)) < 3e-4 * peak
    # the BRDFs: f = K |U|² / (π √det Σ), the direct sum's Σ G² ΔxΔy = π √det Σ to the box's truncation
    f_closed = _K(wi, wo) * np.abs(closed) ** 2 / (math.pi * math.sqrt(np.linalg.det(Sigma)))
    f_gabor = gabor.gabor_footprint_brdf(hf, fp, wi, wo, [LAM])[:, 0]
    f_direct = pixel.pixel_brdf(hf, [fp] * len(wo), wi, wo, [LAM], backend="numpy").wave[:, 0]
    assert np.max(np.abs(f_gabor - f_closed)) < 6e-4 * f_closed.max()
    assert np.max(np.abs(f_direct - f_closed)) < 6e-4 * f_closed.max()


# --- (b) a random field at σ = 5 µm: both against a float64 direct sum ----------------------------------------

DX, SIG = 0.1e-6, 5e-6
STEP, HALF = 0.01, 7                       # 15 × 15 directions, ±0.07 about the mirror (speckle ≈ 0.016)


@pytest.fixture(scope="module")
def random_case():
    """A Gaussian random field (σ = 20 nm, T = 1 µm, seed 5) at 0.1 µm, a σ = 5 µm footprint, ω_i = (0.3, 0.1)
    and 225 ω_o about the mirror direction; the reference f over the ±5σ box (G ≤ 4e-6 beyond, so the box's
    truncation is below 1e-5 of the peak U)."""
    hf = generators.gaussian(20e-9, 1e-6, (64e-6, 64e-6), (640, 640), seed=5)
    fp = Footprint(32.03e-6, 31.96e-6, SIG)
    wi = _dir(0.3, 0.1)
    m = STEP * np.arange(-HALF, HALF + 1)
    wo = np.array([_dir(-0.3 + u, -0.1 + v) for v in m for u in m])
    i0, i1 = math.floor((fp.x - 5 * SIG) / DX), math.ceil((fp.x + 5 * SIG) / DX) + 1
    j0, j1 = math.floor((fp.y - 5 * SIG) / DX), math.ceil((fp.y + 5 * SIG) / DX) + 1
    X = (np.arange(i0, i1) * DX - fp.x)[None, :]
    Y = (np.arange(j0, j1) * DX - fp.y)[:, None]
    G = np.exp(-(X * X + Y * Y) / (2 * SIG * SIG))
    U = _direct_U(hf.heights[j0:j1, i0:i1], X, Y, G, DX * DX, wi, wo)
    f_ref = _K(wi, wo) * np.abs(U) ** 2 / (np.sum(G * G) * DX * DX)
    return hf, fp, wi, wo, f_ref


def _errors(f, ref):
    return abs(np.sum(f) / np.sum(ref) - 1), abs(f.max() / ref.max() - 1)


def test_random_field_direct_sum_meets_the_issue_targets(random_case):
    """pixel.footprint_brdf's NumPy twin (its window truncated where G < e⁻⁹) against the float64 sum over ±5σ:
    energy (Σ f on the grid) and peak within the issue's 1e-4 and 1e-3 (measured 1.8e-7 and 2.4e-4, the
    truncation; 7e-7 and 2.3e-4 with the ±4σ box summed before)."""
    hf, fp, wi, wo, ref = random_case
    f = np.array([pixel.footprint_brdf(hf, fp, wi, w, [LAM], backend="numpy")[0][0] for w in wo[112:113]])
    r = pixel.pixel_brdf(hf, [fp] * len(wo), wi, wo, [LAM], backend="numpy").wave[:, 0]
    assert f[0] == pytest.approx(r[112], rel=1e-12)
    e_energy, e_peak = _errors(r, ref)
    assert e_energy < 1e-4 and e_peak < 1e-3
    assert np.argmax(r) == np.argmax(ref)


def test_random_field_gabor_evaluation(random_case):
    """The Gabor evaluation (σ_k = Δ/2, the ±5σ box of the reference) against the same float64 sum: its
    linearization lowers energy and peak by a few 1e-3 (measured 2.0e-3 and 2.3e-3), 16× less at σ_k = Δ/8
    (peak 1.4e-4: the error ∝ σ_k², module doc)."""
    hf, fp, wi, wo, ref = random_case
    f = gabor.gabor_footprint_brdf(hf, fp, wi, wo, [LAM], n_sigma=5)[:, 0]
    e_energy, e_peak = _errors(f, ref)
    assert e_energy < 4e-3 and e_peak < 4e-3
    assert np.argmax(f) == np.argmax(ref)
    top = int(np.argmax(ref))
    f8 = gabor.gabor_footprint_brdf(hf, fp, wi, wo[top], [LAM], n_sigma=5, kernel_sigma=0.125)[0, 0]
    assert 12 < e_peak / abs(f8 / ref[top] - 1) < 20


# --- (c) convergence as the texel shrinks relative to λ -------------------------------------------------------

_P = (3.1e-6, 2.7e-6, 3.7e-6)


def _smooth(X, Y):
    """A smooth surface (m) and its Laplacian: three sinusoids of 40 nm (28 nm) amplitude, periods 2.7-3.7 µm."""
    a = (2 * np.pi / _P[0], 2 * np.pi / _P[1], 2 * np.pi / _P[2])
    t1, t2, t3 = a[0] * X + 0.3, a[1] * Y + 1.1, a[2] * (X + 0.6 * Y)
    h = 40e-9 * (np.sin(t1) + np.cos(t2) + 0.7 * np.sin(t3))
    lap = -40e-9 * (a[0] ** 2 * np.sin(t1) + a[1] ** 2 * np.cos(t2) + 0.7 * a[2] ** 2 * 1.36 * np.sin(t3))
    return h, lap


def test_gabor_error_falls_as_texel_squared_and_is_the_laplacian_shift():
    """At Δ = λ/4, λ/8, λ/16 (σ_k = Δ/2, σ = 1.5 µm footprint, ±6σ boxes): the error of U against the direct sum
    falls 4× per halving (measured 1.3e-2, 3.3e-3, 8.4e-4 of the peak), and against a direct sum over
    h − ½ σ_k² ∇²h (the first-order error, module doc) what is left falls 16× (4e-4, 2.6e-5, 1.6e-6)."""
    sig, ns = 1.5e-6, 6
    wi = _dir(0.3, 0.1)
    wo = np.array([_dir(-0.3 + a, -0.1 + b) for a in (-0.1, -0.05, 0.0, 0.05, 0.1) for b in (-0.06, 0.0, 0.06)])
    errs, rests = [], []
    for div in (4, 8, 16):
        dx = LAM * 1e-9 / div
        n = int(math.ceil(2 * ns * sig / dx)) + 8
        x = np.arange(n) * dx
        h, _ = _smooth(x[None, :], x[:, None])
        fp = Footprint((n // 2 + 0.3) * dx, (n // 2 - 0.2) * dx, sig)
        i0, i1 = math.floor((fp.x - ns * sig) / dx), math.ceil((fp.x + ns * sig) / dx) + 1
        xs = np.arange(i0, i1) * dx
        hb, lap = _smooth(xs[None, :], xs[:, None])
        X, Y = xs[None, :] - fp.x, xs[:, None] - fp.y
        G = np.exp(-(X * X + Y * Y) / (2 * sig * sig))
        U_ref = _direct_U(hb, X, Y, G, dx * dx, wi, wo)
        U_shift = _direct_U(hb - 0.5 * (dx / 2) ** 2 * lap, X, Y, G, dx * dx, wi, wo)
        U = gabor.gabor_footprint_field(HeightField(h, dx), fp, wi, wo, [LAM], n_sigma=ns)[:, 0]
        peak = np.abs(U_ref).max()
        errs.append(np.max(np.abs(U - U_ref)) / peak)
        rests.append(np.max(np.abs(U - U_shift)) / peak)
    assert errs[0] < 2e-2 and errs[2] < 1.2e-3
    for e1, e2 in zip(errs, errs[1:]):
        assert 3.5 < e1 / e2 < 4.5
    for e1, e2 in zip(rests, rests[1:]):
        assert e1 / e2 > 10
    assert all(r < e / 20 for r, e in zip(rests, errs))


def test_bad_input_names_fields():
    hf = HeightField(np.zeros((50, 50)), 0.1e-6)
    wi = _dir(0.1, 0.0)
    with pytest.raises(FieldError, match="kernel_sigma"):
        gabor.gabor_kernels(hf, Footprint(2.5e-6, 2.5e-6, 0.3e-6), kernel_sigma=0.0)
    with pytest.raises(FieldError, match="leaves the field"):
        gabor.gabor_footprint_field(hf, Footprint(0.5e-6, 2.5e-6, 0.3e-6), wi, wi * [-1, -1, 1], [LAM])
    with pytest.raises(FieldError, match="above the surface"):
        gabor.gabor_footprint_brdf(hf, Footprint(2.5e-6, 2.5e-6, 0.3e-6), wi, wi * [1, 1, -1], [LAM])
