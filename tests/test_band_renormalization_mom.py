"""Does K, the band series' return of beyond-band multiple-order light to the propagating band (waveoptics/scatter/
band.py BandSeries, docs/physics.md §9), move the Kirchhoff series towards the rigorous answer? (issue 28)

The 1-D analog of BandSeries is written here from its definition, for a Gaussian surface of correlation
σ² exp(−τ²/ℓ²), two-sided PSD W(K) = σ²ℓ/(2√π) e^{−K²ℓ²/4}, in u = K/k (the direction-cosine offset
u = sinθₛ − sinθᵢ). With w(u) = k W(ku)/σ² (unit mass), the 1-D Kirchhoff series (Thorsos 1988; Beckmann &
Spizzichino 1963) on a perfect conductor is

    σ(θₛ) = F²/cosθᵢ · Σ_{m≥1} p_m(g) w^{*m}(u),   p_m = e^{−g} g^m/m!,  g = k²σ²(cosθᵢ + cosθₛ)²,
    F = (1 + cos(θᵢ + θₛ))/(cosθᵢ + cosθₛ),

w^{*m} the m-fold convolution (the transform of c^m); σ is per radian of θₛ, normalized as the method of moments
(waveoptics.scatter.mom). Four versions are compared with the MoM ensemble:

* ``plain``: the series above (= waveoptics.scatter.models1d.kirchhoff_1d; checked below);
* ``plain+K``: its m ≥ 2 part times K = Σ_{m≥2} p_m / Σ_{m≥2} p_m B_m, B_m = ∫ w^{*m} over the band of θ
  (|sinθ + u| ≤ 1, i.e. u ∈ [−1 − sinθ, 1 − sinθ]), averaged over θᵢ and θₛ as band.py does;
* ``band``: band.py's series in 1-D without K: g with σ_rel² (the mean over θᵢ and θₛ of the variance inside
  each one's band), the first term p_1(g) w(u) σ²/σ_rel², the m ≥ 2 terms with w_b^{*m}, w_b = w on |u| ≤ 1
  renormalized (the correlation band-limited at normal incidence, c_b);
* ``band+K``: the same with the m ≥ 2 part times K (B_m of w_b^{*m}): band.py's BandSeries in 1-D.

Measured (MoM: perfect conductor, 40 λ surfaces, Thorsos beam g = 10 λ, 10 nodes per λ, seeded realizations;
ring power = ∫σ_incoherent dθₛ over |sinθₛ − sinθᵢ| in the ring; ratio model/MoM ± MoM standard error): see the
table in :func:`test_in_the_outer_ring_k_is_smaller_than_the_kirchhoff_polarization_error`.

References
----------
.. [1] E. I. Thorsos, "The validity of the Kirchhoff approximation for rough surface scattering using a Gaussian
   roughness spectrum", J. Acoust. Soc. Am. 83(1), 78–92, 1988.
.. [2] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon 1963.
.. [3] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness, renormalized
   scatter).
"""
from __future__ import annotations

import math
import sys

import numpy as np
from scipy import signal, special

from waveoptics.scatter.models1d import kirchhoff_1d
from waveoptics.scatter.mom import MomRequest, mom_scatter

K0 = 2 * math.pi                       # λ = 1
ELL = 0.8                              # ℓ/λ
RINGS = ((0.07, 0.3), (0.3, 0.6), (0.6, 1.0))
SCATTER_DEG = np.linspace(-89.9, 89.9, 1439)
VERSIONS = ("plain", "plain+K", "band", "band+K")
DU = 2e-3


def _weights(deg):
    """Trapezoid weights (radians) of the θₛ grid."""
    t = np.radians(deg)
    w = np.zeros_like(t)
    w[1:] += 0.5 * np.diff(t)
    w[:-1] += 0.5 * np.diff(t)
    return w


def _ring_matrix(theta_i_deg):
    """(n_s, n_rings + 1): ring weights (last column: all angles, the total diffuse reflectance)."""
    du = np.abs(np.sin(np.radians(SCATTER_DEG)) - math.sin(math.radians(theta_i_deg)))
    w = _weights(SCATTER_DEG)
    cols = [w * ((du >= a) & (du < b)) for a, b in RINGS] + [w]
    return np.stack(cols, axis=1)


class Series1D:
    """The m-fold convolutions w^{*m} and w_b^{*m} (m = 1..m_max) on a u grid, and their in-band shares."""

    def __init__(self, k_ell, m_max):
        n = int(round((m_max + 1) / DU))
        self.u = np.arange(-n, n + 1) * DU
        self.kl = k_ell
        full = k_ell / (2 * math.sqrt(math.pi)) * np.exp(-(k_ell * self.u) ** 2 / 4)
        band = np.where(np.abs(self.u) <= 1 + 1e-12, full, 0.0)
        self.band_mass = float(np.sum(band) * DU)           # σ_b²/σ² at normal incidence
        self.conv = {}
        for name, w1 in (("full", full), ("band", band / self.band_mass)):
            cur, out = w1, [w1]
            for _ in range(m_max - 1):
                cur = signal.fftconvolve(cur, w1, mode="same") * DU
                out.append(cur)
            self.conv[name] = np.array(out)                  # (m_max, n_u)

    def inband(self, name, sin_theta):
        """B_m(θ) = ∫ w^{*m} over u ∈ [−1 − |sinθ|, 1 − |sinθ|] (W is even: the sign of θ does not matter), from
        the cumulative trapezoid integral of each w^{*m}."""
        s = np.abs(np.atleast_1d(np.asarray(sin_theta, float)))
        conv = self.conv[name]
        cdf = np.concatenate([np.zeros((conv.shape[0], 1)), np.cumsum(0.5 * (conv[:, 1:] + conv[:, :-1]), axis=1)
                              * DU], axis=1)
        return np.stack([np.interp(1 - s, self.u, c) - np.interp(-1 - s, self.u, c) for c in cdf])   # (m, n_s)

    def sigma_rel2(self, sin_theta):
        """σ_rel²/σ² at θ: W's mass inside u ∈ [−1 − |s|, 1 − |s|] (closed form, erf)."""
        s = np.abs(np.asarray(sin_theta, float))
        return 0.5 * (special.erf(self.kl * (1 + s) / 2) + special.erf(self.kl * (1 - s) / 2))


def model_sigma(series, k_sigma, theta_i_deg, theta_s_deg, version):
    """σ(θₛ) (per radian) of one of :data:`VERSIONS` (module doc)."""
    ti, ts = math.radians(theta_i_deg), np.radians(theta_s_deg)
    si, ss, ci, cs = math.sin(ti), np.sin(ts), math.cos(ti), np.cos(ts)
    u = ss - si
    banded = version.startswith("band")
    rel = 0.5 * (series.sigma_rel2(si) + series.sigma_rel2(ss)) if banded else np.ones_like(ss)
    g = (k_sigma * (ci + cs)) ** 2 * rel
    m = np.arange(1, series.conv["full"].shape[0] + 1)[:, None]
    p = np.exp(-g + m * np.log(g) - special.gammaln(m + 1))                 # (m_max, n_s)
    name = "band" if banded else "full"
    wm = np.stack([np.interp(u, series.u, c) for c in series.conv[name]])   # (m_max, n_s)
    first = p[0] * np.interp(u, series.u, series.conv["full"][0]) / rel
    rest = np.sum(p[1:] * wm[1:], axis=0)
    if version.endswith("+K"):
        num = p[1:].sum(axis=0)
        kk = [num / np.sum(p[1:] * series.inband(name, s)[1:], axis=0) for s in (np.full_like(ss, si), ss)]
        rest = rest * 0.5 * (kk[0] + kk[1])
    F = (1 + np.cos(ti + ts)) / (ci + cs)
    return F ** 2 / ci * (first + rest)


def measure(sigma_wl, pol, n_real, seed=0, thetas=(0.0, 20.0)):
    """{θᵢ: {'mom': (mean, se) over rings + total, version: model ring powers}} for σ/λ, ℓ/λ = 0.8."""
    res = mom_scatter(MomRequest(sigma_wl, ELL, tuple(thetas), pol, None, 40.0, 10.0, 10.0, n_real, seed,
                                 tuple(SCATTER_DEG)))
    ks = K0 * sigma_wl
    series = Series1D(K0 * ELL, int((2 * ks) ** 2 + 12 * 2 * ks + 12))
    out = {}
    for i, t in enumerate(res.theta_deg):
        R = _ring_matrix(t)
        samples = res.sigma_incoherent_samples[:, i, :] @ R                  # (M, rings + 1)
        row = {"mom": (samples.mean(axis=0), samples.std(axis=0, ddof=1) / math.sqrt(n_real)), "samples": samples}
        for v in VERSIONS:
            row[v] = model_sigma(series, ks, t, SCATTER_DEG, v) @ R
        out[float(t)] = row
    return out


def _table(results):
    """Lines of ratios model/MoM (the VERSIONS, then ± the MoM's relative standard error) per ring and the total."""
    lines = []
    for (sig, pol), per_theta in results.items():
        for t, row in per_theta.items():
            mean, se = row["mom"]
            cells = []
            for j in range(len(RINGS) + 1):
                ratios = " ".join(f"{row[v][j] / mean[j]:.3f}" for v in VERSIONS)
                cells.append(f"{ratios} ±{se[j] / mean[j]:.3f}")
            lines.append(f"σ={sig} {pol} θi={t:g}: " + " | ".join(cells))
    return "\n".join(lines)


def unpolarized(s_row, p_row):
    """The row of unpolarized light: the mean of s and p per realization (the same surfaces in both)."""
    samples = 0.5 * (s_row["samples"] + p_row["samples"])
    n = samples.shape[0]
    row = {"mom": (samples.mean(axis=0), samples.std(axis=0, ddof=1) / math.sqrt(n)), "samples": samples}
    row.update({v: s_row[v] for v in VERSIONS})         # the Kirchhoff models do not depend on s/p on a conductor
    return row


def test_convolutions_and_plain_series_match_the_closed_form():
    """The numerical w^{*m} against the closed form kℓ/(2√(πm)) e^{−(kℓu)²/(4m)}, and the ``plain`` version
    against the Thorsos-Beckmann series written out in waveoptics.scatter.models1d."""
    s = Series1D(K0 * ELL, 12)
    for m in (1, 2, 5, 12):
        ref = s.kl / (2 * math.sqrt(math.pi * m)) * np.exp(-(s.kl * s.u) ** 2 / (4 * m))
        assert np.max(np.abs(s.conv["full"][m - 1] - ref)) < 1e-6 * ref.max(), m
    assert np.allclose(s.conv["band"].sum(axis=1) * DU, 1.0, atol=1e-9)   # unit mass
    for t in (0.0, 20.0):
        ref, _ = kirchhoff_1d(t, SCATTER_DEG, K0 * 0.08, K0 * ELL)
        got = model_sigma(s, K0 * 0.08, t, SCATTER_DEG, "plain")
        assert np.max(np.abs(got - ref)) < 1e-5 * ref.max()     # linear interpolation in u (Δu = 2e-3)


TEST_REALIZATIONS = 48


def test_in_the_outer_ring_k_is_smaller_than_the_kirchhoff_polarization_error():
    """σ/λ = 0.08, ℓ/λ = 0.8 (kσ = 0.50, kℓ = 5.0; the case of the 2-D xfail), θᵢ = 0° and 20°, outer ring
    0.6 ≤ |sinθₛ − sinθᵢ| < 1, 48 realizations per polarization (the same surfaces in s and p; seed 7, about 8 s
    of one core). What this ensemble resolves, and asserts:

    * K's factor on the ring, (band+K)/band = 1.118 at 0°, 1.067 at 20° (1.06/1.03 at σ/λ = 0.05, 1.19/1.12 at
      0.12), is much smaller than the ring's polarization split on a perfect conductor, MoM p/s = 1.75 and 1.81
      here (1.81/1.82 over 400 realizations), to which the Kirchhoff series (the same for s and p) is blind;
    * s: the series is above the MoM already without K (band/MoM = 1.18 ± 0.065, 1.31 ± 0.083 here; 1.26 and 1.36
      ± 0.02 over 560): K moves it away (1.32, 1.40 here; 1.41, 1.45 over 560);
    * p: the series is below the MoM even with K (band+K/MoM = 0.753 ± 0.054, 0.769 ± 0.067 here; 0.78, 0.80
      ± 0.02 over 560): K moves it towards, not there (band 0.67, 0.72 here; 0.69, 0.75 over 560).

    Unpolarized (the mean of s and p per realization), pooled over 560 realizations (160 with seeds 1005/1008/1012
    and 400 with 2005/2008/2012, ``python tests/test_band_renormalization_mom.py N SEED0``), ratio model/MoM,
    band → band+K, ± the MoM standard error:

    ============  ==============================  ==============================  ==============================
    σ/λ, θᵢ       ring [0.3, 0.6)                 ring [0.6, 1.0)                 total diffuse reflectance
    ============  ==============================  ==============================  ==============================
    0.05, 0°      0.996 → 1.007 ± 0.017           0.911 → 0.965 ± 0.015           0.990 → 0.997 ± 0.012
    0.05, 20°     0.986 → 1.002 ± 0.017           0.933 → 0.964 ± 0.019           0.988 → 0.998 ± 0.012
    0.08, 0°      1.002 → 1.030 ± 0.013           0.895 → 1.001 ± 0.016           0.997 → 1.020 ± 0.008
    0.08, 20°     0.992 → 1.032 ± 0.014           0.964 → 1.029 ± 0.019           0.998 → 1.029 ± 0.009
    0.12, 0°      1.002 → 1.069 ± 0.011           0.859 → 1.021 ± 0.015           0.986 → 1.048 ± 0.004
    0.12, 20°     0.988 → 1.080 ± 0.012           0.971 → 1.086 ± 0.016           0.989 → 1.065 ± 0.005
    ============  ==============================  ==============================  ==============================

    (the inner ring [0.07, 0.3): every version within 0.99-1.06; the plain series, not band-limited, is within 2 %
    of ``band`` in the inner and middle rings and the total, and 2-13 % higher in the outer ring, most at 0°.)
    So for unpolarized light K moves the outermost ring towards the MoM in four of the six cases, to the other
    side by as much at σ/λ = 0.08, 20° (0.964 → 1.029 ± 0.019) and away at σ/λ = 0.12, 20° (0.971 → 1.086);
    it moves the ring [0.3, 0.6) and the total diffuse reflectance away from it for
    σ/λ ≥ 0.08 (total: without K within 1.4 %, with K 2-3 % high at 0.08 and 5-6.5 % high at 0.12). Where the
    band series without K falls short of the MoM it does so in the outer ring only, while K returns the
    beyond-band share to every ring in proportion to the series' shape. This 48-realization ensemble does not
    resolve the unpolarized differences (its standard error in the outer ring is 6-7 %): it asserts only that
    both stay within 20 %.
    Checks of the MoM at σ/λ = 0.12 (band/MoM, s | p, outer ring, 0° and 20°): 15 nodes per λ (64 realizations)
    1.23, 1.35 | 0.72, 0.85; an 80 λ surface with a 20 λ beam (32 realizations) 1.13, 1.23 | 0.68, 0.80; against
    1.15, 1.24 | 0.69, 0.81 (400 at 10 nodes per λ, 40 λ): the polarization split holds. In the inner ring at
    σ/λ = 0.12 the 400-realization ensemble (band/MoM 0.985 in s at 0°) differs from the other three (0.91-0.93)
    by about 4 standard errors, reproducibly and in both halves of it: the standard errors may understate the
    ensemble-to-ensemble scatter there; the outer ring agrees across the four ensembles within their errors
    (0°: 1.13-1.23 ± 0.02-0.05 in s, 0.68-0.72 in p) and the total within 3 %.
    """
    res = {pol: measure(0.08, pol, TEST_REALIZATIONS, seed=7) for pol in ("s", "p")}
    res["unpol"] = {t: unpolarized(res["s"][t], res["p"][t]) for t in res["s"]}
    print(_table({(0.08, pol): r for pol, r in res.items()}))
    j = 2                                                                    # the outer ring, 0.6 ≤ |Δu| < 1
    for t in (0.0, 20.0):
        (ms, ses), (mp, sep) = (res[pol][t]["mom"][:2] for pol in ("s", "p"))
        mu = res["unpol"][t]["mom"][0]
        band, band_k = res["s"][t]["band"][j], res["s"][t]["band+K"][j]
        k_factor, split = band_k / band, mp[j] / ms[j]
        assert 1.03 < k_factor < 1.15 and split > 1.4 and split > k_factor + 0.25, (t, k_factor, split)
        assert band - ms[j] > 2 * ses[j], (t, band / ms[j], ses[j] / ms[j])          # s: K moves it away
        assert mp[j] - band_k > 3 * sep[j], (t, band_k / mp[j], sep[j] / mp[j])      # p: K moves it towards
        assert 0.8 < band / mu[j] < band_k / mu[j] < 1.2, (t, band / mu[j], band_k / mu[j])


if __name__ == "__main__":    # the report's table: python tests/test_band_renormalization_mom.py N_REALIZATIONS SEED0
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    seed0 = int(sys.argv[2]) if len(sys.argv) > 2 else 1000
    print("ratios model/MoM: " + " ".join(VERSIONS) + " ± MoM se; rings " + str(RINGS) + " | total")
    for sig in (0.05, 0.08, 0.12):
        res = {pol: measure(sig, pol, n, seed=seed0 + round(sig * 100)) for pol in ("s", "p")}
        res["unpol"] = {t: unpolarized(res["s"][t], res["p"][t]) for t in res["s"]}
        print(_table({(sig, pol): r for pol, r in res.items()}), flush=True)
        for t in res["s"]:
            print(f"σ={sig} θi={t:g} MoM ring powers s/p: " + " ".join(
                f"{a:.4g}/{b:.4g}" for a, b in zip(res["s"][t]["mom"][0], res["p"][t]["mom"][0])), flush=True)
