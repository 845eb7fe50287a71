"""The two-scale BRDF as a function a renderer can call: evaluate, importance-sample, integrate.

Gold with GGX micro-facets (α = 0.1) carrying ABC nano-roughness (σ = 10 nm): f(ω_i, ω_o, λ) at a few direction
pairs, its parts, a Monte Carlo albedo from its own sampler against the quadrature albedo, and a sphere rendered
per pixel under a directional light.

Run:  python examples/brdf_function.py [OUTDIR] [--fast]
"""
import sys
from pathlib import Path

import numpy as np

import waveoptics as wo
from waveoptics import colour
from waveoptics.renderers import sphere as render
from waveoptics.io import figures
from waveoptics.request import make_nano

fast = "--fast" in sys.argv
out = Path(next((a for a in sys.argv[1:] if not a.startswith("--")), "out/brdf_function"))
out.mkdir(parents=True, exist_ok=True)

nano = make_nano("abc:sigma=10nm,B=2um,C=2.6", [550.0])
f = wo.TwoScaleBRDF("Au", wo.brdf.Micro(alpha=0.1, ndf="ggx"), nano=nano)


def direction(theta_deg, phi_deg=0.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


wi = direction(30)
wo_dirs = np.array([direction(t, 180) for t in (20, 30, 40, 60)])
for lam in (450.0, 650.0):
    parts = f.eval_parts(wi, wo_dirs, lam)
    print(f"{lam:g} nm  f (1/sr) at θo = 20, 30, 40, 60°:", np.round(f.eval(wi, wo_dirs, lam), 4),
          " diffracted part:", np.round(parts["diffraction"], 4))

s = f.sample(wi, 550.0, np.random.default_rng(0).random((2000 if fast else 20000, 2)))
print(f"albedo at 550 nm: Monte Carlo {s.weight.mean():.4f} ± {s.weight.std() / np.sqrt(s.weight.size):.4f}, "
      f"quadrature {float(f.albedo(wi, 550.0)):.4f}")

w = np.array([450.0, 550.0, 650.0])
table = wo.TabulatedTwoScaleBRDF("Au", wo.brdf.Micro(alpha=0.1, ndf="ggx"), nano=nano, wavelengths_nm=tuple(w),
                                 resolution=32 if fast else 128)
img, mask = render.render_sphere(table, w, direction(30), size=48 if fast else 256)
figures.save_png(out / "sphere.png", render.tonemap(img))
print(f"sphere: {int(mask.sum())} lit pixels, mean luminance {float(colour.luminance(img[mask]).mean()):.4f}; "
      f"wrote {out / 'sphere.png'}")
