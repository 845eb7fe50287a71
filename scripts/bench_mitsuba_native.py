"""Render time of one small scene with the three ways the two-scale BRDF enters Mitsuba 3, at equal spp:

* ``native``: the Dr.Jit plugin ``waveoptics_native`` (:mod:`waveoptics.renderers.mitsuba_native`);
* ``numpy``: the NumPy plugin ``waveoptics`` (:mod:`waveoptics.renderers.mitsuba`, wavefront mode);
* ``measured``: Mitsuba's ``measured`` BSDF reading the RGL export of the same model (spectral variants only).

Scene: a sphere under a constant sky and a directional sun, ``path`` integrator (max depth 3), SIZE² pixels. Each
BSDF renders once to compile its kernels, then is timed over a second render with another seed (Dr.Jit reuses the
compiled kernels); both times are printed. The NumPy plugin runs last, because registering it turns Dr.Jit's
symbolic loops and calls off for the process.

Usage: ``PYTHONPATH=. python scripts/bench_mitsuba_native.py [--variant llvm_ad_spectral] [--size 64] [--spp 16]
[--resolution 64] [--wavelength-step 47]``
(``--json`` prints the numbers as JSON).
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

PARAMS = dict(material="aluminium", alpha=0.1, nano="abc:sigma=10nm,B=2um,C=2.6", wavelength_step=47.0,
              resolution=64)


def _scene(mi, bsdf, size, spp):
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 3},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": size, "height": size, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.3, 0.3]}},
        "sun": {"type": "directional", "direction": [-0.5, -0.6, -0.6],
                "irradiance": {"type": "rgb", "value": [3, 3, 3]}},
    })


def _time(mi, bsdf, size, spp):
    import drjit as dr

    t0 = time.perf_counter()
    scene = _scene(mi, bsdf, size, spp)
    img = mi.render(scene, seed=0)
    dr.eval(img)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    img = mi.render(scene, seed=1)
    dr.eval(img)
    second = time.perf_counter() - t0
    return {"first_s": first, "timed_s": second, "image": np.array(img, dtype=float)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variant", default="llvm_ad_spectral")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--resolution", type=int, default=PARAMS["resolution"], help="direction-grid cells per axis")
    ap.add_argument("--wavelength-step", type=float, default=PARAMS["wavelength_step"], help="nm")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)

    from waveoptics.renderers.mitsuba import PLUGIN_NAME, register
    from waveoptics.renderers.mitsuba_native import NATIVE_PLUGIN_NAME, register_native
    from waveoptics.renderers.model import cached_renderer_brdf

    params = dict(PARAMS, resolution=args.resolution, wavelength_step=args.wavelength_step)
    t0 = time.perf_counter()
    kw = {("wavelength_step_nm" if k == "wavelength_step" else k): v for k, v in params.items()}
    model = cached_renderer_brdf(**dict(sorted(kw.items())))
    out = {"variant": args.variant, "size": args.size, "spp": args.spp, "model_s": time.perf_counter() - t0,
           "params": params}
    mi = register_native(args.variant)
    res = {"native": _time(mi, {"type": NATIVE_PLUGIN_NAME, **params}, args.size, args.spp)}
    if mi.is_spectral:
        from waveoptics.renderers.rgl import export_rgl

        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "model.bsdf"
            t0 = time.perf_counter()
            export_rgl(model, path)
            out["rgl_export_s"] = time.perf_counter() - t0
            res["measured"] = _time(mi, {"type": "measured", "filename": str(path)}, args.size, args.spp)
    register(args.variant)
    res["numpy"] = _time(mi, {"type": PLUGIN_NAME, **params}, args.size, args.spp)
    ref = res["numpy"]["image"]
    for name, r in res.items():
        img = r.pop("image")
        r["mean_rel_diff_to_numpy"] = float(np.abs(img - ref).mean() / max(ref.mean(), 1e-30))
        r["numpy_over_this"] = res["numpy"]["timed_s"] / r["timed_s"]
    out["renders"] = res
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        print(f"{args.variant}, {args.size}² px, {args.spp} spp (model built in {out['model_s']:.1f} s)")
        for name, r in res.items():
            print(f"  {name:9s} first {r['first_s']:7.2f} s  timed {r['timed_s']:7.2f} s  "
                  f"numpy/this {r['numpy_over_this']:6.1f}  mean |Δ|/mean vs numpy {r['mean_rel_diff_to_numpy']:.3f}")


if __name__ == "__main__":
    main()
