"""Shared fixtures: OpenCL runtime chosen like pyopencl's test suite (WAVEOPTICS_DEVICE / PYOPENCL_TEST),
precision parametrization with float64 gated on device support, and tolerances kept in one place."""
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from waveoptics import runtime as _runtime

#: kernel-vs-NumPy tolerances per precision (absolute, on quantities of order 1)
KERNEL_ATOL = {"float32": 2e-5, "float64": 1e-12}


@pytest.fixture(scope="session")
def rt():
    """The OpenCL Runtime under test (skips with the install hint when there is no OpenCL)."""
    if not _runtime.opencl_available():
        pytest.skip(_runtime.INSTALL_HINT)
    return _runtime.get_runtime()


@pytest.fixture(params=["float32", "float64"])
def precision(request, rt):
    """Both precisions; float64 only where the device supports it."""
    if request.param == "float64" and not rt.fp64:
        pytest.skip(f"device {rt.name!r} has no fp64")
    return request.param


@pytest.fixture
def rng():
    """A seeded generator (seed 12345)."""
    return np.random.default_rng(12345)


#: a cost model timed by ``planning.costmodel.calibrate`` on a quiet 2-core machine (10 s to time), seeded into the
#: tests' cache so that each pytest-xdist worker does not spend that time re-timing it, and the planner's estimates
#: are the same on every run; the tests of the calibration itself time their own (tests/test_cache.py,
#: test_planning.py::test_estimate_tracks_measured_time)
SEEDED_COST_MODEL = {"call": 0.00357, "cell": 1.004e-06, "cell_wl": 0.0, "diffuse_cell_wl": 8.69e-07,
                     "psd_wl": 0.00121, "psd_cell_wl": 2.44e-05, "psd_term": 7.09e-07, "fft_unit": 4.55e-09,
                     "band_wl": 0.830, "calibration_s": 9.84}


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory):
    """The per-user cache (cost-model calibration, plans) lives in a temporary directory during the tests."""
    import os

    from waveoptics import cache

    old = os.environ.get("WAVEOPTICS_CACHE_DIR")
    if os.environ.get("PYTEST_XDIST_WORKER"):
        # one cache for all pytest-xdist workers of this run (their base temps share a parent made for the run):
        # a renderer model table one worker built is not built again by the other; entries are written
        # atomically (a temporary file moved into place), so the workers cannot see half a file
        shared = tmp_path_factory.getbasetemp().parent / "wocache"
        shared.mkdir(exist_ok=True)
        os.environ["WAVEOPTICS_CACHE_DIR"] = str(shared)
    else:
        os.environ["WAVEOPTICS_CACHE_DIR"] = str(tmp_path_factory.mktemp("wocache"))
    cache.put("calibration", "cost_model", SEEDED_COST_MODEL)
    yield
    if old is None:
        os.environ.pop("WAVEOPTICS_CACHE_DIR", None)
    else:
        os.environ["WAVEOPTICS_CACHE_DIR"] = old


#: measured wall time of every test (s, setup + call + teardown) on a 2-core machine, written by ``make durations``
#: (``pytest --store-durations``); a test recorded above SLOW_S is marked ``slow`` and left out of ``make test-fast``
DURATIONS = Path(__file__).with_name("durations.json")
SLOW_S = 0.5


def pytest_addoption(parser):
    parser.addoption("--store-durations", action="store_true",
                     help="write every test's wall time to tests/durations.json (make durations)")


def pytest_collection_modifyitems(config, items):
    """Mark the slow tests, and order the files by their recorded time, longest first (each file's tests in their
    own order): ``make test`` hands whole files to the pytest-xdist workers (``--dist loadfile``), so a file's
    module fixtures and in-process caches (band series, models) are built once, not on every worker (measured on
    5 fixture-heavy files: 13 % less CPU), and longest-first keeps the workers' ends together (the longest-
    processing-time rule; Graham 1969: with pytest-xdist's own reordering by test count, ``--no-loadscope-reorder``
    in the Makefile turns it off, a file of few long tests came last and one worker ran alone for 90 s)."""
    recorded = json.loads(DURATIONS.read_text()) if DURATIONS.exists() else {}
    per_file: dict = {}
    for item in items:
        t = recorded.get(item.nodeid, 0.0)
        if t > SLOW_S:
            item.add_marker(pytest.mark.slow)
        per_file[item.nodeid.split("::")[0]] = per_file.get(item.nodeid.split("::")[0], 0.0) + t
    items.sort(key=lambda it: -per_file[it.nodeid.split("::")[0]])   # stable: a file's order is kept


_measured: dict = {}


def pytest_runtest_logreport(report):
    _measured[report.nodeid] = _measured.get(report.nodeid, 0.0) + report.duration


def pytest_sessionfinish(session, exitstatus):
    config = session.config
    if config.getoption("--store-durations") and not hasattr(config, "workerinput"):
        DURATIONS.write_text(json.dumps({k: round(v, 3) for k, v in sorted(_measured.items())}, indent=0) + "\n")


@pytest.fixture(autouse=True)
def _process_settings_restored():
    """A command's process-wide settings (``--max-memory`` sets ``WAVEOPTICS_MAX_MEMORY`` for the rest of its
    process) end with the test that ran the command in-process: a 100 kB budget of one test refused every later
    surface of its pytest-xdist worker."""
    import os

    old = os.environ.get("WAVEOPTICS_MAX_MEMORY")
    yield
    if old is None:
        os.environ.pop("WAVEOPTICS_MAX_MEMORY", None)
    else:
        os.environ["WAVEOPTICS_MAX_MEMORY"] = old
