"""Benchmarks: the project's kernels against what a user would otherwise write, in one run on one machine.

Measured (each a function returning plain data; :func:`run_all` runs them all, ``waveoptics bench`` prints them
and ``scripts/docs_performance.py`` turns them into ``docs/performance.md``):

* :func:`direct_kernels` — the direct Kirchhoff sum (docs/physics.md §1) on one problem: the project's OpenCL kernel
  (float32, float64, fast-math), the kernel it replaced (``kirchhoff_U_sinpi``, run as it was: driver-chosen
  work-groups), the naive OpenCL kernel (``kirchhoff_U_naive``: float phase k s·x in radians,
  native_sin/native_cos, driver-chosen work-groups), a plain NumPy direct sum (``exp(1j k s·r) @ w``) and the
  project's float64 NumPy twin :func:`waveoptics.scatter.kirchhoff_U`: throughput in terms/s (sample ×
  direction × wavelength), the ratio to the naive kernel and to NumPy, and the error against the twin relative to
  Σ w dx dy.
* :func:`direct_scaling` — time of the same against the number of samples and of directions (four sizes each).
* :func:`fft_backends` — 2-D complex FFT throughput (points/s) of numpy.fft, scipy.fft (pocketfft, 1 and 2
  workers), pyFFTW (planned FFTW objects, if installed) and pyvkfft on the OpenCL device (if installed;
  device-resident data, transfers excluded).
* :func:`fft_pipeline` — the ``fft`` solver (:func:`waveoptics.scatter.field_fft`, chirp-z onto the direction
  grid, frozen v_z and banded Taylor series) against the NumPy FFT pipeline a user would write (zero-padded
  ``numpy.fft.fft2`` of w·exp(i v_z h), bilinear interpolation of the field onto the grid), over four patch sizes,
  with errors against the direct sum on a subset of cells.
* :func:`footprint_evaluations` — one Gaussian footprint (σ = 2, 5, 10 µm at 0.1 µm spacing) at a few direction
  pairs by the direct sum (:func:`waveoptics.scatter.pixel_brdf`, NumPy twin and OpenCL kernel) and by Yan et
  al. 2018's Gabor kernels (:func:`waveoptics.scatter.gabor_footprint_brdf`): time per pair, and the errors of
  energy and peak against an exact float64 sum over ±5σ (:func:`footprint_exact_brdf`).
* :func:`brdf_eval_rates` — ``eval()`` evaluations per second of the microfacet BRDF and of the two-scale BRDF
  (pointwise quadrature, tabulated), batched and in a Python loop.
* :func:`simulate_times` — wall and CPU time (s) of ``simulate()`` with every field at its default (the first call
  of the process apart, then the best of the next ones) against the same request without the sphere renders'
  table (``--no-spheres``), in one process.
* :func:`math_errors` — largest absolute error of the device's sin/cos/sinpi/cospi/native_/half_ built-ins and of
  the kernels' own sin/cos polynomial (``kernels/wo_sincos.h``) against float64 NumPy, on reduced (|x| ≤ π) and
  large (|x| ≤ 10⁴) arguments.

Times are the best of several repeats (wall clock, after a warm-up call that builds the kernels). They depend on
the machine and on its load; :func:`machine` records what it was.

Files: common (timer, machine record, test problem), baselines (what a user would otherwise write, and the launch code
of the benchmark-only kernels), model_speed (the BRDF models' and simulate's times, in public names only, so that
``scripts/bench_vs_08faf07.py`` runs the same file on an older tree), measures (the kernels' benchmarks and
:func:`run_all`), tables (:func:`report`, :func:`write_report`).

References
----------
.. [1] docs/physics.md §1 (direct sum and its cost O(samples × directions)); Rabiner, Schafer & Rader 1969 (chirp-z).
.. [2] M. Frigo, S. G. Johnson, "The design and implementation of FFTW3", Proc. IEEE 93(2), 2005.
"""
from .common import (WAVELENGTH_NM, best_time, machine)
from .baselines import (numpy_direct_sum, footprint_exact_brdf, NAIVE, kirchhoff_U_sinpi_cl, kirchhoff_U_naive_cl, numpy_fft_pipeline)
from .model_speed import (brdf_eval_rates, SIMULATE_QUICK, SIMULATE_UNITS, simulate_times)
from .measures import (MATH_FUNCTIONS, large_patch_errors, direct_kernels, direct_scaling, fft_backends,
    fft_pipeline, math_errors, fft_threads, footprint_evaluations, run_all)
from .tables import (report, simulate_table, REPORT_FILES, write_report)
from . import common, baselines, model_speed, measures, tables  # noqa: F401

__all__ = common.__all__ + baselines.__all__ + model_speed.__all__ + measures.__all__ + tables.__all__
