"""The bookkeeping of waveoptics.scatter.solvers: the solver registry, the split of one patch into tiles that stand
in for realizations, and the memory estimate checked before any work."""
import numpy as np
import pytest

from waveoptics.errors import FieldError, WaveopticsError
from waveoptics.scatter.solvers import (SOLVERS, get_solver, memory_estimate, split_patch, tile_layout)
from waveoptics.surfaces import HeightField


@pytest.mark.parametrize("shape, n", [((64, 64), 4), ((64, 128), 8), ((30, 90), 3), ((16, 16), 1), ((8, 8), 16)])
def test_tiles_cover_the_patch_as_squarely_as_possible(shape, n):
    a, b = tile_layout(shape, n)
    assert a * b == n and shape[0] // a >= 2 and shape[1] // b >= 2
    # no other split of n into a' x b' gives tiles closer to square (ratio written out here)
    ratio = lambda a_, b_: abs(np.log((shape[1] / b_) / (shape[0] / a_)))   # noqa: E731
    others = [(x, n // x) for x in range(1, n + 1) if n % x == 0 and shape[0] // x >= 2 and shape[1] // (n // x) >= 2]
    assert ratio(a, b) <= min(ratio(*o) for o in others) + 1e-12


@pytest.mark.parametrize("n", [0, -1, 2.5, "x", True, 10**9])
def test_impossible_tilings_are_refused_in_one_line(n):
    with pytest.raises(WaveopticsError) as err:
        tile_layout((16, 16), n)
    assert "\n" not in str(err.value)


def test_tiles_put_back_together_are_the_patch():
    h = np.random.default_rng(3).normal(size=(24, 36))
    hf = HeightField(h, 1e-7, 2e-7)
    tiles = split_patch(hf, 6)
    a, b = tile_layout(h.shape, 6)
    rows = [np.hstack([t.heights for t in tiles[i * b:(i + 1) * b]]) for i in range(a)]
    np.testing.assert_array_equal(np.vstack(rows), h)
    assert all(t.dx == 1e-7 and t.dy == 2e-7 for t in tiles)


def test_memory_grows_with_cells_wavelengths_and_samples():
    base = memory_estimate(64, 64, 1)
    assert memory_estimate(128, 128, 1) == pytest.approx(4 * base, rel=0.01)
    assert memory_estimate(64, 64, 8) > memory_estimate(64, 64, 2) > base
    assert memory_estimate(64, 64, 1, (512, 512)) > base


def test_solvers_by_name_and_unknown_ones_refused_naming_the_field():
    for name in SOLVERS:
        assert get_solver(name) is not None
    with pytest.raises(FieldError) as err:
        get_solver("nosuch")
    assert err.value.field == "solver" and "direct" in str(err.value)
