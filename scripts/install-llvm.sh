#!/usr/bin/env bash
# Make a libLLVM >= 17 available for Mitsuba 3's LLVM variants (waveoptics render, the plugin's chi2 tests).
# Debian 12's default LLVM 15/16 abort on Mitsuba 3.9's kernels ("Cannot select: fmaximum"); Debian 12 ships
# libllvm19 as a separate package. Idempotent: does nothing when waveoptics already finds LLVM >= 17.
set -euo pipefail
PY=${1:-.venv/bin/python}
probe() { "$PY" - <<'PYEOF' 2>/dev/null
import sys
from waveoptics.renderers.mitsuba import LLVM_MIN, llvm_library
path, major = llvm_library()
sys.exit(0 if path and major >= LLVM_MIN else 1)
PYEOF
}
if probe; then exit 0; fi
if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
  echo "installing Debian's libllvm19 (for Mitsuba 3's LLVM variants)..."
  export DEBIAN_FRONTEND=noninteractive
  { apt-get install -y -qq libllvm19 >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq libllvm19 >/dev/null; }; } \
    || echo "warning: apt-get could not install libllvm19" >&2
  if probe; then exit 0; fi
fi
echo "warning: no libLLVM >= 17 here; Mitsuba's LLVM variants are unavailable (scalar variants still work)." \
     "Install LLVM >= 17 (Debian: apt-get install libllvm19) or set DRJIT_LIBLLVM_PATH" >&2
