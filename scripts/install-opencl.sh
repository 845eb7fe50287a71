#!/usr/bin/env bash
# Make an OpenCL CPU runtime available to the virtual environment's pyopencl.
# Preferred: Debian's pocl-opencl-icd (measured ~20x faster than the PyPI PoCL 3.0 build on a Kirchhoff sum).
# Fallback (no root / no apt): the PyPI package pocl-binary-distribution, with a warning.
# Idempotent: does nothing when pyopencl already sees a platform.
set -euo pipefail
PY=${1:-.venv/bin/python}
probe() { "$PY" - <<'PYEOF' 2>/dev/null
import pyopencl as cl, sys
try:
    sys.exit(0 if any(p.get_devices() for p in cl.get_platforms()) else 1)
except Exception:
    sys.exit(1)
PYEOF
}
if probe; then exit 0; fi
if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
  echo "installing Debian's pocl-opencl-icd (OpenCL CPU runtime)..."
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq && apt-get install -y -qq pocl-opencl-icd ocl-icd-libopencl1 >/dev/null \
    || echo "warning: apt-get could not install pocl-opencl-icd" >&2
  if probe; then exit 0; fi
fi
echo "warning: Debian's pocl-opencl-icd is not usable here (needs root and apt); falling back to the PyPI" \
     "package pocl-binary-distribution, which is much slower (about 20x on the Kirchhoff kernel)" >&2
"$PY" -m pip install -q "pocl-binary-distribution>=3.0"
probe || { echo "error: no OpenCL platform after installing PoCL" >&2; exit 1; }
