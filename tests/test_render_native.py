"""``render --bsdf native`` (issue 31): the Dr.Jit plugin (:mod:`waveoptics.renderers.mitsuba_native`) in the sphere
render job, chosen by ``auto`` where it runs compiled and takes the model.

The independent reference is the NumPy plugin (:mod:`waveoptics.renderers.mitsuba`, the model evaluated by NumPy in
wavefront mode, a different implementation): a tiny sphere rendered through each must give the same image within
the Monte Carlo noise floor the job measures (two renders of one model with different seeds), the colour
difference recomputed here with colour-science's CIEDE2000, not the library's."""
import json
import os

import numpy as np
import pytest

pytest.importorskip("mitsuba")

from waveoptics.errors import FieldError  # noqa: E402
from waveoptics.renderers import mitsuba as wm  # noqa: E402
from waveoptics.renderers.requests import RenderRequest, field_default  # noqa: E402

HAVE_LLVM = (wm.llvm_library()[1] or 0) >= wm.LLVM_MIN or bool(os.environ.get("DRJIT_LIBLLVM_PATH"))
needs_llvm = pytest.mark.skipif(not HAVE_LLVM, reason="no libLLVM >= 17 for Mitsuba's JIT")

#: a small rough-nano model (2 wavelength nodes, a 24² lobe grid) on a 16² sphere: the diffracted lobes take part
TINY = dict(material="copper", alpha=0.3, nano="abc:sigma=20nm,B=2um,C=2.6", wavelength_step="470nm",
            resolution=24, sphere_size=16, spp=16, environment="studio", ground=False)


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("WAVEOPTICS_CACHE_DIR", str(tmp_path / "cache"))


def _rgb(path):
    from waveoptics.io.files import read_exr

    ch, _ = read_exr(path)
    return ch["RGB"] if "RGB" in ch else np.stack([ch["R"], ch["G"], ch["B"]], -1)


def _delta_e2000(a, b):
    colour = pytest.importorskip("colour")

    def lab(rgb):
        return colour.XYZ_to_Lab(colour.RGB_to_XYZ(rgb, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=False))

    return colour.delta_E(lab(a), lab(b), method="CIE 2000")


@needs_llvm
def test_native_and_numpy_plugins_render_the_same_sphere_within_the_noise_floor(tmp_path, cache_dir):
    from waveoptics.renderers.jobs import render_job
    from waveoptics.renderers.scene import sphere_mask

    runs = {b: render_job(RenderRequest(bsdf=b, **TINY), tmp_path / b) for b in ("native", "plugin")}
    on = sphere_mask(TINY["sphere_size"])
    images = {b: _rgb(tmp_path / b / "wave.exr") for b in runs}
    for b, r in runs.items():
        s = json.loads((tmp_path / b / "summary.json").read_text())
        assert s["bsdf"] == b and s["bsdf_requested"] == b and s["bsdf_reason"] == "given"
        assert np.all(np.isfinite(images[b])) and images[b].min() >= 0 and images[b][on].max() > 0
    floor = min(r.summary["noise_floor_delta_e2000"]["mean"] for r in runs.values())
    de = _delta_e2000(images["native"], images["plugin"])[on].mean()
    assert floor > 0.5, floor                      # the floor is a real one at 16 spp ...
    assert de < 0.25 * floor, (de, floor)          # ... and the two plugins differ by far less (same seeds)


def _small_model(**kw):
    from waveoptics.renderers.model import renderer_brdf

    return renderer_brdf(**dict(dict(material="gold", alpha=0.2, nano="none", wavelength_step_nm=235.0), **kw))


@pytest.mark.parametrize("variant,expected", [("llvm_ad_spectral", "native"), ("cuda_ad_rgb", "native"),
                                              ("scalar_spectral", "measured"), ("scalar_rgb", "plugin"),
                                              ("llvm_ad_mono_polarized", "plugin")])
def test_auto_chooses_by_variant_and_says_why(variant, expected):
    from waveoptics.renderers.jobs import choose_bsdf

    assert field_default(RenderRequest, "bsdf") == "auto"
    how, why = choose_bsdf(RenderRequest(variant=variant), _small_model())
    assert how == expected and why.startswith("auto: ") and variant in why, (how, why)


def test_auto_falls_back_where_the_native_plugin_lacks_the_model():
    from waveoptics.renderers.jobs import choose_bsdf

    blinn = _small_model(ndf="blinn-phong")
    assert choose_bsdf(RenderRequest(variant="llvm_ad_spectral"), blinn)[0] == "measured"
    how, why = choose_bsdf(RenderRequest(variant="llvm_ad_rgb"), blinn)
    assert how == "plugin" and "blinn-phong" in why
    with pytest.raises(FieldError) as err:
        choose_bsdf(RenderRequest(variant="llvm_ad_rgb", bsdf="native"), blinn)
    assert err.value.fields[:2] == ("bsdf", "ndf") and "--" not in str(err.value)
    schlick = _small_model(material="f0:0.9")
    assert choose_bsdf(RenderRequest(variant="llvm_ad_spectral_polarized"), schlick)[0] == "measured"
    assert choose_bsdf(RenderRequest(variant="llvm_ad_spectral"), schlick)[0] == "native"
