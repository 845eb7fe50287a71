"""The threaded build of a tabulated two-scale model (issue 31, a fast first export): the per-wavelength and
per-incidence work spread over threads (:func:`waveoptics.runtime.parallel_map`: band series, albedo tables, the
facet tables, the facet-frame kernel built in the background) gives the serial build's tables bit for bit, and the
table reads of an export (only the nodes that weigh a point) equal a dense bilinear read written here."""
import threading
import time
import warnings

import numpy as np
import pytest

from waveoptics import runtime, scatter
from waveoptics.brdf import Micro, TabulatedTwoScaleBRDF
from waveoptics.request import make_nano
from waveoptics.scatter import band

#: a small model: 32² cells, three incidences, two wavelengths
WAVELENGTHS = (450.0, 650.0)
NANO = "abc:sigma=10nm,B=2um,C=2.6"
PARALLEL_IMAP = runtime.parallel_imap


def _build(material, workers, monkeypatch, nano=NANO):
    """(table, energy scale, threads that ran parallel_map's items) of a fresh model (new Nano, band series
    forgotten, as in a new process) built by *workers* threads; *nano* statistics, or ``"field"``: a generated
    128² ABC height field (seed 1)."""
    monkeypatch.setenv("WAVEOPTICS_WORKERS", str(workers))
    band.band_series_cached.cache_clear()
    threads = set()

    def recorded(fn, items, workers=None):
        def run(item):
            threads.add(threading.get_ident())
            return fn(item)
        return PARALLEL_IMAP(run, items, workers)

    monkeypatch.setattr(runtime, "parallel_imap", recorded)
    made = (make_nano(NANO, WAVELENGTHS, solver="fft", seed=1) if nano == "field" else make_nano(nano, WAVELENGTHS))
    with warnings.catch_warnings():   # a 32² grid under-samples the field's speckle: the same in both builds
        warnings.simplefilter("ignore", scatter.DiffractionWarning)
        tab = TabulatedTwoScaleBRDF(material, Micro(alpha=0.1), nano=made, wavelengths_nm=WAVELENGTHS, resolution=32,
                                    thetas_deg=(40.0, 80.0) if nano == "field" else (0.0, 40.0, 80.0))
    return tab.table, tab._table["energy_scale"], threads


@pytest.mark.parametrize("material", ["Al", "glass"])
def test_threaded_build_equals_serial_build_bit_for_bit(rt, material, monkeypatch):
    """A conductor (coherent fraction 1 − E: the band series and albedo tables built in the coherent lobe's
    wavelength threads) and a dielectric (Debye-Waller coherent fraction: the series built by
    band_series_built, the absolute albedo tables in the facet budget's threads)."""
    serial, s_scale, s_threads = _build(material, 1, monkeypatch)
    threaded, t_scale, t_threads = _build(material, 3, monkeypatch)
    assert s_threads == {threading.get_ident()} and len(t_threads) > 1
    assert np.max(serial) > 0 and np.all(np.isfinite(serial))
    assert np.array_equal(serial, threaded)
    assert np.array_equal(s_scale, t_scale)


@pytest.mark.slow
def test_threaded_build_of_a_height_field_equals_serial_build_bit_for_bit(monkeypatch):
    """A height field (the paraxial route on 32² cells): the wavelengths in threads, its incidences in order (its
    coherent fraction's incidence nodes are cached as the incidences ask for them)."""
    serial, s_scale, _ = _build("Al", 1, monkeypatch, nano="field")
    threaded, t_scale, t_threads = _build("Al", 3, monkeypatch, nano="field")
    assert len(t_threads) > 1 and np.max(serial) > 0
    assert np.array_equal(serial, threaded)
    assert np.array_equal(s_scale, t_scale)


def test_parallel_map_keeps_order_and_uses_threads():
    seen = set()
    lock = threading.Lock()
    barrier = threading.Barrier(2, timeout=10)

    def fn(x):
        if x < 2:   # the first two items meet: they run at the same time, in two threads
            barrier.wait()
        with lock:
            seen.add(threading.get_ident())
        return x * x

    assert runtime.parallel_map(fn, range(20), workers=2) == [x * x for x in range(20)]
    assert len(seen) == 2 and threading.get_ident() not in seen


def test_parallel_map_with_one_worker_runs_in_the_calling_thread(monkeypatch):
    monkeypatch.setenv("WAVEOPTICS_WORKERS", "1")
    assert runtime.parallel_map(lambda x: threading.get_ident(), range(5)) == [threading.get_ident()] * 5
    assert list(runtime.parallel_imap(str, [3, 1, 2], workers=4)) == ["3", "1", "2"]
    assert runtime.parallel_map(str, []) == []


def test_a_parallel_map_inside_an_item_runs_in_that_items_thread():
    def outer(x):
        me = threading.get_ident()
        inner = runtime.parallel_map(lambda y: (threading.get_ident(), x * 10 + y), range(4), workers=2)
        assert all(t == me for t, _ in inner)
        return [v for _, v in inner]

    assert runtime.parallel_map(outer, range(3), workers=2) == [[x * 10 + y for y in range(4)] for x in range(3)]


def test_parallel_map_raises_the_first_failing_items_exception():
    done = []

    def fn(x):
        if x == 3:
            raise ValueError(f"item {x}")
        time.sleep(0.01)
        done.append(x)
        return x

    with pytest.raises(ValueError, match="item 3"):
        runtime.parallel_map(fn, range(200), workers=2)
    assert 3 <= len(done) < 150   # the items not started when it failed are dropped (all 199: 1 s of sleeps)


@pytest.mark.parametrize("diffraction", ["kirchhoff", "rayleigh-rice"])
def test_the_kernel_built_in_the_background_is_the_one_the_model_launches(rt, diffraction, monkeypatch):
    """warm_facet_frame_kernel's switches are those of the model's own launches: after it, building the model
    builds no other program (the programs counted from none)."""
    from waveoptics.brdf.facet_frame_cl import warm_facet_frame_kernel
    from waveoptics.scatter import get_model

    monkeypatch.setattr(runtime, "_programs", {})
    micro, nano = Micro(alpha=0.1), make_nano(NANO, (550.0,))
    warm_facet_frame_kernel(micro, nano, get_model(diffraction, perturbative=True)).join()
    assert runtime.program_cache_size() == 1
    tab = TabulatedTwoScaleBRDF("gold", micro, nano=nano, wavelengths_nm=(550.0,), resolution=24, thetas_deg=(30.0,),
                                diffraction=diffraction)
    assert np.max(tab.table) > 0
    assert runtime.program_cache_size() == 1


def test_export_reads_equal_a_dense_bilinear_read(rt):
    """f_diff at light directions on and between θ nodes, read by the model (only the nodes with weight > 0),
    against the blend of both bracketing nodes' lobes read bilinearly at the turned directions (written here)."""
    tab = TabulatedTwoScaleBRDF("gold", Micro(alpha=0.1), nano=make_nano(NANO, (550.0,)), wavelengths_nm=(550.0,),
                                resolution=32, thetas_deg=(0.0, 30.0, 60.0))
    grid = tab.grid
    rng = np.random.default_rng(7)
    r = 0.8 * np.sqrt(rng.uniform(0.0, 1.0, 300))   # exit directions away from the rim (no rim filling read)
    ph = rng.uniform(-np.pi, np.pi, 300)
    wo = np.stack([r * np.cos(ph), r * np.sin(ph), np.sqrt(1.0 - r * r)], axis=-1)
    nodes = np.radians([0.0, 30.0, 60.0])
    for theta in np.radians([30.0, 41.0, 60.0]):
        wi = np.broadcast_to([np.sin(theta), 0.0, np.cos(theta)], wo.shape)
        got = tab._f_diffraction(wi, wo, 550.0)
        f = np.interp(theta, nodes, np.arange(3.0))
        num = den = 0.0
        for k in sorted({int(np.floor(f)), min(int(np.floor(f)) + 1, 2)}):
            w = 1.0 - abs(f - k)
            beta = theta - nodes[k]
            u = wo[:, 0] * np.cos(beta) + wo[:, 2] * np.sin(beta)
            z = -wo[:, 0] * np.sin(beta) + wo[:, 2] * np.cos(beta)
            # the tabulated lobe with the cells beyond the disc's rim filled (the model's own look-up table)
            lobe = np.where(z > 0, grid.interpolate(tab._lookup_table()[0, k, 0], u, wo[:, 1]), 0.0)
            num = num + w * lobe
            den = den + w * (z > 0)
        ref = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
        assert np.max(ref) > 0
        np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12 * np.max(ref))
