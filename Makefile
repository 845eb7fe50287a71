# The two commands of the README. Both set up .venv (Python >= 3.10, the package, an OpenCL CPU runtime).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test test-fast durations setup clean docs docs-render bench

# pytest-xdist workers: one per core (2 on CI)
JOBS ?= auto

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/install-opencl.sh scripts/install-llvm.sh
	@test -x $(PY) || $(PYTHON) -m venv $(VENV) || { \
	  echo "python3 -m venv failed; trying Debian's python3-venv"; \
	  apt-get update -qq && apt-get install -y -qq python3-venv >/dev/null && $(PYTHON) -m venv $(VENV); }
	$(PY) -m pip install -q --disable-pip-version-check -e '.[test,instruments,render]'
	bash scripts/install-opencl.sh $(PY)
	bash scripts/install-llvm.sh $(PY)
	@touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/waveoptics info
	$(VENV)/bin/waveoptics simulate -o out/demo --overwrite
	$(VENV)/bin/waveoptics render --material gold --micro-alpha 0.05 --nano abc:sigma=50nm,B=1um,C=2.6 \
		--environment studio --no-ground --sphere-size 128 --spp 256 -o out/render --overwrite

# one thread per pytest-xdist worker: the workers already use every core. OpenBLAS's threads spin while they wait
# for a core (tests/test_band_renormalization_mom.py's group, 2 workers: 82 -> 34 s wall, 95 -> 54 s of CPU), and
# the library's own (WAVEOPTICS_WORKERS, runtime.cpu_workers) contend with the other worker's (the whole suite
# 543 -> 492 s on 2 cores); tests/test_facet_table_reads.py and test_frame_sampling_warnings.py set their own
# worker counts to test the threaded paths (bit for bit against serial runs, warnings from threads)
TEST_ENV := OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 WAVEOPTICS_WORKERS=1

# whole files to each worker, the longest first (tests/conftest.py): a file's fixtures and caches are built once;
# a worker that crashes (a hung test, faulthandler_timeout) is restarted at most twice
test: $(STAMP)
	$(TEST_ENV) $(PY) -m pytest -q -ra -n $(JOBS) --dist loadfile --no-loadscope-reorder --max-worker-restart 2

# the edit loop: everything but the slow tests (marked by hand, or recorded above 0.5 s in tests/durations.json), <= 2 min
test-fast: $(STAMP)
	$(TEST_ENV) $(PY) -m pytest -q -ra -n $(JOBS) --dist loadfile --no-loadscope-reorder -m "not slow"

# re-measure every test's wall time into tests/durations.json (which tests make test-fast leaves out)
durations: $(STAMP)
	$(TEST_ENV) $(PY) -m pytest -q -ra -n $(JOBS) --store-durations

# recompute every docs page's data (slow: benchmarks and studies) and render it
docs: $(STAMP)
	$(PY) scripts/make_docs.py

# re-render the pages from the committed docs/data/*.json after editing docs/templates/*.md (seconds)
docs-render: $(STAMP)
	$(PY) scripts/make_docs.py --render-only

bench: $(STAMP)
	$(PY) -m waveoptics bench

clean:
	rm -rf $(VENV) out build dist .pytest_cache
