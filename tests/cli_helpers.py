"""Running the command line inside the test process: ``run_cli(argv)`` gives the exit code, both streams and the
Python warnings raised, without a subprocess (the tests that need the real console script start one themselves)."""
from __future__ import annotations

import contextlib
import io
import warnings


def run_cli(argv) -> tuple[int, str, str, list]:
    """Run ``waveoptics ARGV`` in-process: (exit code, stdout, stderr, Python warnings raised)."""
    from waveoptics.cli import main

    out, err = io.StringIO(), io.StringIO()
    with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        warnings.simplefilter("always")
        try:
            rc = main(list(argv))
        except SystemExit as exc:  # argparse errors
            rc = exc.code if isinstance(exc.code, int) else 1
    return rc, out.getvalue(), err.getvalue(), [str(w.message) for w in caught]
