"""Quickstart: a nano-rough gold surface under daylight, two-scale vs microfacet, in a few lines.

Run:  python examples/quickstart.py [OUTDIR] [--fast]
"""
import sys
from pathlib import Path

import numpy as np

from waveoptics import colour
from waveoptics import simulate

fast = "--fast" in sys.argv
out = Path(next((a for a in sys.argv[1:] if not a.startswith("--")), "out/quickstart"))

# 1. the scene: gold with 12 nm rms nano-roughness (ABC/K-correlation PSD) on GGX micro-facets, light at 30°
sim = simulate.simulate("Au", nano="abc:sigma=12nm,B=2um,C=2.8", micro_alpha=0.05, ndf="ggx",
                        incident=(30.0, 0.0), illuminant="D65", resolution=48 if fast else 128,
                        wavelengths=np.arange(400, 701, 50.0) if fast else None)

# 2. spectral and RGB results
lam = sim.wavelengths_nm
print("wavelengths (nm):", lam)
print("albedo, two-scale :", sim.lobes.albedo().round(4))
print("albedo, microfacet:", sim.lobes.albedo("microfacet").round(4))
print("coherent fraction :", sim.lobes.coherent_specular_fraction().round(4))
rgb, rgb_mf = sim.rgb_albedo(), sim.rgb_albedo("microfacet")
print("linear sRGB albedo:", rgb.round(4), "vs microfacet", rgb_mf.round(4),
      f"ΔE2000 {float(colour.delta_e2000(rgb, rgb_mf)):.2f}")

# 3. files: spectral EXR, previews, spheres, lobes, summary.json
summary = simulate.write_outputs(sim, out, overwrite=True, sphere_size=64 if fast else 256)
print(f"sphere ΔE2000 mean {summary['delta_e2000']['mean']:.2f}; pictures in {out}/")
