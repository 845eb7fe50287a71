"""The Dr.Jit-native two-scale BSDF (``waveoptics_native``) in Mitsuba 3's CUDA variants, against the NumPy model
and the LLVM variant (issue 31). A GPU check, never run by the test suite (CI has no GPU).

Two steps, because the GPU machine has no network and only a small carried tree:

``prepare DIR`` (here, with the project's virtual environment and an LLVM variant):
    builds the model of ``make demo``'s render (gold, GGX α 0.05, ABC σ 50 nm, B 1 µm, C 2.6) on a 64² table grid
    at 60 nm wavelength nodes, pickles it (gzip), draws seeded direction pairs, and writes the NumPy model's float64 eval × cos θ_o
    and pdf (RGB and spectral), the LLVM variant's plugin values and eval throughput, and an LLVM render of a test
    scene (a sphere of the model under a constant environment and a point light, 128², 64 spp) with its time.

``device DIR OUT`` (on the GPU machine, with Mitsuba and Dr.Jit carried as a site folder):
    the same pairs in ``cuda_ad_rgb`` and ``cuda_ad_spectral``: eval and pdf against the NumPy model (float32
    precision) and against the LLVM values; eval throughput; Mitsuba's own χ² test of sample/pdf at 30° and 80°
    (10⁶ samples; ires = 24: with Mitsuba's default-like ires = 8 the expected counts of the narrow grazing lobe,
    GGX α 0.05 at 80°, are integrated too coarsely and both this BSDF and the NumPy model are rejected; measured
    in LLVM here, the same test with ires = 24 accepts both at 70, 75 and 80°, p = 0.16, 0.70, 0.17);
    the same scene rendered (time, and the image against LLVM's with the same sampler seed). Writes OUT/cuda.json.

Modules the GPU machine lacks and the model's evaluation does not call (pyopencl, colour-science, the optical
constants' database) are stubbed there; a stub that is called raises, so a result cannot come from a stub.

References
----------
.. [1] W. Jakob, S. Speierer, N. Roussel, M. Nimier-David et al., *Mitsuba 3 renderer*, 2022,
   https://mitsuba-renderer.org (variants, ``mitsuba.chi2``).
"""
from __future__ import annotations

import gzip
import json
import os
import pickle
import sys
import time
import types
from pathlib import Path

import numpy as np

#: make demo's render model on a 64² table grid and 60 nm wavelength nodes (the carried tree is limited to 64 MiB)
DEMO = dict(material="gold", alpha=0.05, nano="abc:sigma=50nm,B=1um,C=2.6", resolution=64, wavelength_step_nm=60.0)
N_PAIRS = 4000
N_SPEED = 1 << 20
SCENE_RES, SCENE_SPP = 128, 64


def _pairs(n, seed):
    """n (ω_i, ω_o) pairs: θ_i uniform in cos θ up to 85°; ω_o uniform in cos θ up to 85° for half of them and within
    ±5° (θ and φ) of the mirror direction for the other half; 4 wavelengths each; float32-exact."""
    rng = np.random.default_rng(seed)
    cmin = np.cos(np.radians(85.0))
    ti, pi = np.arccos(rng.uniform(cmin, 1.0, n)), rng.uniform(-np.pi, np.pi, n)
    to, po = np.arccos(rng.uniform(cmin, 1.0, n)), rng.uniform(-np.pi, np.pi, n)
    near = np.arange(n) < n // 2
    jitter = np.radians(rng.uniform(-5.0, 5.0, (2, n)))
    to = np.where(near, np.clip(ti + jitter[0], 0.0, np.radians(85.0)), to)
    po = np.where(near, pi + np.pi + jitter[1], po)

    def unit(t, p):
        return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).astype(np.float32)

    lam = rng.uniform(400.0, 700.0, (n, 4)).astype(np.float32)
    return unit(ti, pi).astype(float), unit(to, po).astype(float), lam.astype(float)


def _eval_pdf(mi, plugin, wi, wo, lam):
    """(f cos θ_o (n, channels), pdf (n,)) of a loaded BSDF in a JIT variant."""
    import drjit as dr

    n = wi.shape[0]
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T.astype(np.float32)))
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(np.ascontiguousarray(lam.T.astype(np.float32)))
    w = mi.Vector3f(np.ascontiguousarray(wo.T.astype(np.float32)))
    ctx = mi.BSDFContext()
    got = np.array(plugin.eval(ctx, si, w), dtype=float).reshape(-1, n).T
    return got, np.array(plugin.pdf(ctx, si, w), dtype=float).ravel()


def _throughput(mi, plugin, seed=5):
    """Evaluations per second of eval on N_SPEED pairs (the second of two timed runs; the first compiles)."""
    import drjit as dr

    wi, wo, lam = _pairs(N_SPEED, seed)
    rates = []
    for _ in range(2):
        t0 = time.perf_counter()
        got, _ = _eval_pdf(mi, plugin, wi, wo, lam)
        dr.sync_thread()
        rates.append(N_SPEED / (time.perf_counter() - t0))
    return rates[-1]


def _scene(mi, name):
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 4},
        "sensor": {"type": "perspective", "fov": 30.0,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, -4.0, 1.2], target=[0, 0, 0], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": SCENE_RES, "height": SCENE_RES, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": SCENE_SPP, "seed": 3}},
        "sphere": {"type": "sphere", "bsdf": {"type": name}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.05}},
        "light": {"type": "point", "position": [2.0, -3.0, 3.0], "intensity": {"type": "rgb", "value": 40.0}},
    })


def _render(mi, name):
    import drjit as dr

    scene = _scene(mi, name)
    times, img = [], None
    for _ in range(2):                         # the first render compiles the kernels
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, spp=SCENE_SPP, seed=3), dtype=float)
        dr.sync_thread()
        times.append(time.perf_counter() - t0)
    return img, times


def _rel(got, want):
    """Largest error relative to max(|want|, 1e-3 of its largest)."""
    scale = np.maximum(np.abs(want), 1e-3 * np.abs(want).max())
    return float((np.abs(got - want) / scale).max())


def prepare(d: Path) -> None:
    from waveoptics.renderers.mitsuba_native import register_native
    from waveoptics.renderers.model import renderer_brdf

    d.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    model = renderer_brdf(**DEMO)
    build_s = time.perf_counter() - t0
    wi, wo, lam = _pairs(N_PAIRS, 11)
    ref = dict(wi=wi, wo=wo, lam=lam, rgb=model.eval_rgb(wi, wo) * wo[:, 2:3], pdf_rgb=model.pdf_rgb(wi, wo),
               spectral=model.eval(wi[:, None, :], wo[:, None, :], lam) * wo[:, 2:3],
               pdf_spectral=model.pdf(wi, wo, lam[:, 0]))
    import cloudpickle   # the material's n, k interpolant is a closure

    model.rgb_matrix     # computed here (colour-science): the GPU machine has no colour-science
    (d / "model.pkl.gz").write_bytes(gzip.compress(cloudpickle.dumps(model), 6))
    info = {"model_build_s": build_s}
    for variant in ("llvm_ad_rgb", "llvm_ad_spectral"):
        mi = register_native(variant, model=model, name="wo_gpu_check")
        plugin = mi.load_dict({"type": "wo_gpu_check"})
        got, pdf = _eval_pdf(mi, plugin, wi, wo, lam)
        ref[f"{variant}_eval"], ref[f"{variant}_pdf"] = got, pdf
        info[variant] = {"eval_vs_numpy": _rel(got, ref["rgb" if "rgb" in variant else "spectral"]),
                         "pdf_vs_numpy": _rel(pdf, ref["pdf_rgb" if "rgb" in variant else "pdf_spectral"]),
                         "evals_per_s": _throughput(mi, plugin)}
        if variant == "llvm_ad_rgb":
            img, times = _render(mi, "wo_gpu_check")
            ref["llvm_image"] = img
            info[variant]["render_s"] = times
    np.savez_compressed(d / "ref.npz", **ref)
    (d / "prepare.json").write_text(json.dumps(info, indent=1))
    print(json.dumps(info, indent=1))


def _stub_missing() -> None:
    """Stub the modules the GPU machine lacks and the evaluation of a built model never calls."""
    import importlib.util

    class _Missing(types.ModuleType):
        def __getattr__(self, attr):
            if attr.startswith("__"):
                raise AttributeError(attr)
            if f"{self.__name__}.{attr}" in sys.modules:        # a stubbed submodule
                return sys.modules[f"{self.__name__}.{attr}"]
            raise RuntimeError(f"stubbed module {self.__name__} was used ({attr})")

    for name in ("pyopencl", "pyopencl.array", "pyopencl.clmath", "pyopencl.elementwise", "pyopencl.reduction",
                 "colour", "SurfaceTopography", "OpenEXR", "Imath"):
        top = name.split(".")[0]
        if os.environ.get("WAVEOPTICS_GPU_CHECK_STUB") or (top not in sys.modules
                                                            and importlib.util.find_spec(top) is None):
            sys.modules[name] = _Missing(name)


def device(d: Path, out: Path) -> None:
    _stub_missing()
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    from waveoptics.renderers.mitsuba_native import register_native

    out.mkdir(parents=True, exist_ok=True)
    model = pickle.loads(gzip.decompress((d / "model.pkl.gz").read_bytes()))
    ref = dict(np.load(d / "ref.npz"))
    wi, wo, lam = ref["wi"], ref["wo"], ref["lam"]
    res = {}
    # WAVEOPTICS_GPU_CHECK_VARIANTS: a dry run of this step in other variants (e.g. LLVM, here)
    for variant in os.environ.get("WAVEOPTICS_GPU_CHECK_VARIANTS", "cuda_ad_rgb,cuda_ad_spectral").split(","):
        rgb = "rgb" in variant
        mi = register_native(variant, model=model, name="wo_gpu_check")
        plugin = mi.load_dict({"type": "wo_gpu_check"})
        got, pdf = _eval_pdf(mi, plugin, wi, wo, lam)
        llvm = "llvm_ad_rgb" if rgb else "llvm_ad_spectral"
        r = {"eval_vs_numpy": _rel(got, ref["rgb" if rgb else "spectral"]),
             "pdf_vs_numpy": _rel(pdf, ref["pdf_rgb" if rgb else "pdf_spectral"]),
             "eval_vs_llvm": _rel(got, ref[f"{llvm}_eval"]), "pdf_vs_llvm": _rel(pdf, ref[f"{llvm}_pdf"]),
             "evals_per_s": _throughput(mi, plugin)}
        if rgb:
            chi = {}
            for th in (30.0, 80.0):
                t = np.radians(th)
                w = mi.Vector3f(float(np.sin(t) * np.cos(0.4)), float(np.sin(t) * np.sin(0.4)), float(np.cos(t)))
                sf, pf = BSDFAdapter("wo_gpu_check", {"type": "wo_gpu_check"}, wi=w)
                test = ChiSquareTest(domain=SphericalDomain(), sample_func=sf, pdf_func=pf, sample_dim=3,
                                     sample_count=1_000_000, res=101, ires=24, seed=7)
                chi[f"{th:g}"] = {"passed": bool(test.run()), "p_value": float(getattr(test, "p_value", np.nan))}
            r["chi2"] = chi
            img, times = _render(mi, "wo_gpu_check")
            li = ref["llvm_image"]
            r["render_s"] = times
            r["image_mean_rel_vs_llvm"] = float(np.mean(np.abs(img - li)) / np.mean(np.abs(li)))
            r["image_max_abs_vs_llvm"] = float(np.abs(img - li).max())
            np.save(out / "cuda_image.npy", img.astype(np.float32))
        res[variant] = r
        print(variant, json.dumps(r), flush=True)
    (out / "cuda.json").write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "prepare":
        prepare(Path(sys.argv[2]))
    elif len(sys.argv) >= 4 and sys.argv[1] == "device":
        device(Path(sys.argv[2]), Path(sys.argv[3]))
    else:
        sys.exit("usage: gpu_native_check.py prepare DIR | device DIR OUT")
