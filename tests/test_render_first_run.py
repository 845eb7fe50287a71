"""A fast first run (issue 31, part 3): the band series of every wavelength node a renderer's model is built at stay
in memory together (an LRU cache smaller than the nodes was evicted on every look-up), and the tabulated lobes of
a renderer's model are kept in the per-user cache under a key of every parameter and the code's version, so a
second run reads them instead of computing them."""
import numpy as np
import pytest

from waveoptics import cache
from waveoptics.renderers import model as rmodel
from waveoptics.scatter import band

#: a small model: two wavelength nodes (360, 830 nm), a 24² grid
SMALL = dict(material="gold", alpha=0.2, nano="abc:sigma=10nm,B=2um,C=2.6", wavelength_step_nm=470.0,
             resolution=24)


def test_band_cache_holds_every_wavelength_node_of_the_default_and_a_10nm_render():
    assert band.band_series_cached.cache_parameters()["maxsize"] == band.BAND_CACHE_SIZE
    assert band.BAND_CACHE_SIZE >= len(rmodel.wavelength_nodes()) == 25
    assert band.BAND_CACHE_SIZE >= len(rmodel.wavelength_nodes(10.0))


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("WAVEOPTICS_CACHE_DIR", str(tmp_path / "c"))
    return tmp_path / "c"


def _pairs(n=400, seed=3):
    rng = np.random.default_rng(seed)
    def dirs():
        th = np.arccos(np.sqrt(rng.uniform(0.02, 1.0, n)))
        ph = rng.uniform(-np.pi, np.pi, n)
        return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)
    return dirs(), dirs()


def test_a_second_build_reads_the_lobes_and_evaluates_the_same(cache_dir, monkeypatch):
    from waveoptics.brdf import tabulated

    first = rmodel.renderer_brdf(**SMALL)
    files = list((cache_dir / "arrays" / rmodel.TABLE_CACHE_KIND).glob("*.npz"))
    assert len(files) == 1

    def boom(*a, **k):
        raise AssertionError("the lobes were computed again")

    monkeypatch.setattr(tabulated, "evaluate", boom)
    wi, wo = _pairs()
    ref = {lam: first.eval(wi, wo, lam) for lam in (360.0, 595.0, 830.0)}
    nodes = rmodel.wavelength_nodes(SMALL["wavelength_step_nm"])
    tables = {lam: band.band_series(first.base.nano.model, lam).albedo_tables() for lam in nodes}
    assert all(tables.values())
    band.band_series_cached.cache_clear()   # the band series forgotten, as in a new process
    second = rmodel.renderer_brdf(**SMALL)
    for lam in (360.0, 595.0, 830.0):
        a, b = ref[lam], second.eval(wi, wo, lam)
        assert np.all(np.isfinite(a)) and np.max(a) > 0
        # stored as float32, the precision of the facet tables the lobes are computed from
        np.testing.assert_allclose(b, a, rtol=1e-6, atol=1e-9 * np.max(a))
    # the entry also holds the albedo tables of A(θ_d): the model read from it builds no band series' tables
    # (~0.2 s CPU a wavelength node) and uses the very tables the first build computed
    for lam in nodes:
        bs = band.band_series(second.base.nano.model, lam)
        assert "_arrays" not in bs.__dict__, "the band series' tables were built"
        for key, tab in tables[lam].items():
            for got, want in zip(bs.albedo_tables()[key], tab):
                np.testing.assert_array_equal(got, want)
    np.testing.assert_allclose(second.base.table, first.base.table, rtol=1e-6, atol=0)
    # with the rim tables (waveoptics.brdf.tabulated_rim), which the read takes beyond θ_o 65°
    assert first.base.rim_table is not None
    np.testing.assert_allclose(second.base.rim_table, first.base.rim_table, rtol=1e-6, atol=0)
    with pytest.raises(AssertionError, match="computed again"):
        rmodel.renderer_brdf(**dict(SMALL, cache=False))


def test_every_parameter_changes_the_key():
    from waveoptics import brdf
    from waveoptics.request import make_nano
    from waveoptics.surfaces import HeightField

    nodes = rmodel.wavelength_nodes(470.0)
    nano = make_nano("abc:sigma=10nm,B=2um,C=2.6", nodes)
    common = dict(material="gold", micro=brdf.Micro(alpha=0.2, ndf="ggx"), diffraction="kirchhoff")
    base = cache.key_digest(rmodel.table_key(nano, nodes, 24, common))
    assert cache.key_digest(rmodel.table_key(nano, nodes, 24, dict(common))) == base
    changed = [
        rmodel.table_key(nano, nodes, 32, common),
        rmodel.table_key(nano, rmodel.wavelength_nodes(235.0), 24, common),
        rmodel.table_key(make_nano("abc:sigma=11nm,B=2um,C=2.6", nodes), nodes, 24, common),
        rmodel.table_key(nano, nodes, 24, dict(common, material="copper")),
        rmodel.table_key(nano, nodes, 24, dict(common, material="f0:0.9")),
        rmodel.table_key(nano, nodes, 24, dict(common, micro=brdf.Micro(alpha=0.21, ndf="ggx"))),
        rmodel.table_key(nano, nodes, 24, dict(common, micro=brdf.Micro(alpha=0.2, ndf="beckmann"))),
        rmodel.table_key(nano, nodes, 24, dict(common, diffraction="ghs")),
    ]
    rng = np.random.default_rng(0)
    h = rng.normal(size=(16, 16)) * 1e-8
    hf_keys = []
    for heights, dx in ((h, 5e-8), (h, 6e-8), (h + np.eye(16) * 1e-12, 5e-8)):
        hf_keys.append(rmodel.table_key(brdf.Nano(surface=HeightField(heights, dx)), nodes, 24, common))
    digests = [cache.key_digest(k) for k in changed + hf_keys]
    assert base not in digests and len(set(digests)) == len(digests)


def test_an_unwritable_cache_only_costs_time(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("WAVEOPTICS_CACHE_DIR", str(blocker / "c"))
    m = rmodel.renderer_brdf(**SMALL)
    assert np.max(m.base.table) > 0
