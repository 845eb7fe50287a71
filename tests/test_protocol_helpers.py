"""The sampling helpers every BRDF of waveoptics.brdf.protocol shares: cosine-weighted hemisphere sampling
(Malley's method; Pharr, Jakob & Humphreys, pbrt-v4, §A.5.3), the choice of a lobe with a remapped uniform number
(pbrt-v4 §2.4) and the input checks. Each is tested against its distribution written here (Kolmogorov-Smirnov
tests with scipy.stats, seeded), not against the module's own functions."""
import numpy as np
import pytest
from scipy import stats

from waveoptics.brdf.protocol import broadcast_pair, check_uniform, lobe_choice, pdf_cosine, sample_cosine
from waveoptics.errors import FieldError


def test_cosine_sampling_has_the_cosine_law():
    """For density cos θ / π: cos²θ is uniform on [0, 1] and φ uniform on [0, 2π)."""
    u = np.random.default_rng(1).random((20000, 2))
    d = sample_cosine(u)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
    assert np.all(d[:, 2] >= 0)
    assert stats.kstest(d[:, 2] ** 2, "uniform").pvalue > 0.01
    assert stats.kstest(np.mod(np.arctan2(d[:, 1], d[:, 0]), 2 * np.pi) / (2 * np.pi), "uniform").pvalue > 0.01


def test_cosine_density_integrates_to_one_over_the_hemisphere_and_is_zero_below():
    th = np.linspace(0, np.pi / 2, 2001)
    # ∫ cosθ/π dω = 2π ∫ cosθ sinθ/π dθ over [0, π/2]
    wo = np.stack([np.sin(th), 0 * th, np.cos(th)], axis=-1)
    assert 2 * np.pi * np.trapezoid(pdf_cosine(wo) * np.sin(th), th) == pytest.approx(1.0, abs=1e-6)
    assert pdf_cosine(np.array([0.0, 0.6, -0.8])) == 0.0


def test_a_lobe_is_chosen_with_its_probability_and_the_number_is_remapped_uniform():
    rng = np.random.default_rng(2)
    n = 40000
    probs = [np.full(n, 0.2), np.full(n, 0.5), np.full(n, 0.3)]
    idx, u = lobe_choice(rng.random(n), probs)
    counts = np.bincount(idx, minlength=3)
    assert stats.chisquare(counts, n * np.array([0.2, 0.5, 0.3])).pvalue > 0.01
    for j in range(3):
        assert stats.kstest(u[idx == j], "uniform").pvalue > 0.01
    assert np.all((u >= 0) & (u < 1))


def test_unnormalized_and_zero_probabilities():
    u0 = np.array([0.1, 0.6, 0.99])
    idx, _ = lobe_choice(u0, [np.array([1.0, 1.0, 0.0]), np.array([1.0, 1.0, 0.0])])
    assert idx.tolist()[:2] == [0, 1]        # weights 1 : 1, not normalized by the caller
    idx, _ = lobe_choice(np.array([0.5]), [np.array([0.0]), np.array([2.0])])
    assert idx.tolist() == [1]               # a lobe of probability 0 is never chosen


@pytest.mark.parametrize("u", [np.array([0.5, 1.0]), np.array([[-0.1, 0.5]]), np.array([0.2, 0.3, 0.4]),
                               np.array([np.nan, 0.5])])
def test_uniform_numbers_outside_the_unit_square_are_refused_naming_u(u):
    with pytest.raises(FieldError) as err:
        check_uniform(u)
    assert err.value.field == "u"


def test_pairs_broadcast_and_flatten():
    wi = np.array([0.0, 0.0, 1.0])
    wo = np.tile([0.6, 0.0, 0.8], (4, 5, 1))
    a, b, lam, shape = broadcast_pair(wi, wo, 550.0)
    assert shape == (4, 5) and a.shape == b.shape == (20, 3) and lam.shape == (20,)
    with pytest.raises(FieldError):
        broadcast_pair(wi, wo, -1.0)
