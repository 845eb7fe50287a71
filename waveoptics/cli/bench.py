"""``waveoptics bench``: the project's kernels against a NumPy direct sum, a naive OpenCL kernel, NumPy/SciPy/FFTW
FFTs and a NumPy FFT pipeline, plus the measured error of the device's math built-ins (logic in
:mod:`waveoptics.bench`). Prints Markdown tables (or JSON with --json); ``-o DIR`` also writes ``bench.json`` and
``bench.md``.
"""
from __future__ import annotations

from ..io.files import prepare_outdir
from ._common import add_common, add_output, emit, progress

#: files of ``bench -o DIR`` (:data:`waveoptics.bench.REPORT_FILES`, kept here so that building the parser
#: imports nothing heavy)
FILES = ("bench.json", "bench.md")


def register(sub) -> None:
    p = sub.add_parser("bench", help="benchmark the kernels against NumPy and naive alternatives",
                       description="Measure, in one run on this machine, the direct Kirchhoff kernel (float32, "
                                   "float64, fast-math) against a naive native_sin OpenCL kernel, a NumPy direct sum "
                                   "and the NumPy twin; FFT implementations; the fft solver against a NumPy FFT "
                                   "pipeline; scaling with samples and directions; math built-in errors; BRDF eval() "
                                   "rates; simulate() at its defaults against --no-spheres.")
    p.add_argument("--quick", action="store_true", help="small sizes only (seconds; for smoke tests)")
    add_output(p, required=False, note="a directory: also write bench.json and bench.md")
    add_common(p)
    p.set_defaults(func=run)


def run(args) -> int:

    from .. import bench
    from ..runtime import get_runtime

    out = prepare_outdir(args.output, overwrite=args.overwrite, expected=FILES) if args.output else None
    rt = get_runtime(args.device)
    bar = progress(total=9, desc="bench", args=args)
    res = bench.run_all(rt, quick=args.quick, progress=bar.update)
    bar.close()
    text = bench.report(res)
    if out is not None:
        bench.write_report(out, res, text, overwrite=args.overwrite)
    emit(args, res, text)
    return 0
