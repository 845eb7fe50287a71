"""Glint renders on fields of real size (waveoptics.renderers.glints with waveoptics.surfaces.tiled): the per-pixel
BRDFs equal single footprint queries, a 10⁸-sample field renders with little memory, and the command line
reports its estimate, per-pixel cost and EXR layers."""
import json
import tracemalloc

import numpy as np
import pytest

from waveoptics.renderers import glints
from waveoptics.scatter import footprint_brdf
from waveoptics.surfaces import Footprint, tiled

from cli_helpers import run_cli


@pytest.fixture(scope="module")
def small_render():
    field = tiled.procedural("scratched", 0.2e-3, 0.1e-6, seed=2)
    s = glints.GlintSettings(size=32, shape="sphere", light_deg=40.0, light_azimuth_deg=150.0, view_deg=25.0,
                             view_azimuth_deg=200.0, wavelengths_nm=(450.0, 550.0, 650.0), precision="float64")
    return field, s, glints.render_glints(field, "Al", s)


def test_pixels_equal_the_footprint_query_at_20_random_pixels(small_render):
    """Each pixel's wave and geometric BRDF (batched per row task, regions shared between footprints) equals
    :func:`waveoptics.scatter.footprint_brdf` of its own footprint and directions, to 1e-6."""
    field, s, r = small_render
    lit = np.argwhere(r.on_field & (r.wave_brdf[..., 0] > 0))
    assert len(lit) > 300
    assert 1e-6 < r.footprint_sigma_m[1] <= r.footprint_sigma_m[0] < 4e-6      # footprints of a few µm
    rng = np.random.default_rng(5)
    for j, i in lit[rng.choice(len(lit), 20, replace=False)]:
        fp = Footprint(*(float(v) for v in r.footprints[j, i]))
        wi, wo = r.directions[j, i, :3], r.directions[j, i, 3:]
        fw, fg = footprint_brdf(field, fp, wi, wo, s.wavelengths_nm, "Al", slope_sigma=s.intrinsic_slope,
                                precision="float64")
        np.testing.assert_allclose(r.wave_brdf[j, i], fw, rtol=1e-6)
        np.testing.assert_allclose(r.geometric_brdf[j, i], fg, rtol=1e-6)
    # the radiance is the BRDF times the light's irradiance cos θ_i d²/|light − P|², the same in both panels
    both = r.on_field[..., None] & (r.wave_brdf > 0) & (r.geometric_brdf > 1e-30)
    assert both.sum() > 100
    np.testing.assert_allclose(r.wave_spectral[both] / r.wave_brdf[both],
                               r.geometric_spectral[both] / r.geometric_brdf[both], rtol=1e-12)


def test_wave_and_geometric_panels_differ_but_agree_in_brightness(small_render):
    """Both panels light the same pixels' neighbourhood; the wave panel is not a blur of everything (its
    brightest 1 % of pixels hold a large part of the light, as glints do)."""
    _, _, r = small_render
    w = r.wave_spectral[..., 1][r.on_field]
    g = r.geometric_spectral[..., 1][r.on_field]
    assert w.max() > 0 and g.max() > 0
    top = np.sort(w)[::-1][: max(1, w.size // 100)]
    assert top.sum() / w.sum() > 0.05
    assert not np.allclose(w, g, rtol=0.1)


def test_a_1mm_field_at_0p1um_renders_in_little_memory():
    """A 1 mm × 1 mm field at 0.1 µm (10⁸ samples, procedural) seen by a plane camera zoomed to a 60 µm view
    (footprints of ~1 µm): the render's peak traced memory stays far below 2 GB."""
    field = tiled.procedural("psd", 1e-3, 0.1e-6, seed=3)
    assert field.shape[0] * field.shape[1] == 10 ** 8
    s = glints.GlintSettings(size=24, fov_deg=1.5, wavelengths_nm=(550.0,), view_deg=20.0, light_deg=20.0)
    tracemalloc.start()
    try:
        r = glints.render_glints(field, "Al", s)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert r.on_field.sum() > 400 and np.all(np.isfinite(r.wave))
    assert peak < 200e6, peak


def test_cli_reports_its_estimate_cost_and_layers(tmp_path):
    out = tmp_path / "g"
    rc, stdout, err, _ = run_cli(["render", "--glints", "--surface", "procedural:flakes:0.15mm:0.1um:4", "--shape",
                                  "sphere", "--sphere-size", "16", "--wavelengths", "500,600", "-o", str(out)])
    assert rc == 0, err
    assert "estimate:" in err and "ms/pixel" in err
    assert "footprints/s" in stdout and "estimated" in stdout
    d = json.loads((out / "summary.json").read_text())
    assert d["estimate"]["estimate_s"] > 0 and d["timings_s"]["per_pixel"] > 0
    import OpenEXR

    names = set(OpenEXR.InputFile(str(out / "glints_layers.exr")).header()["channels"])
    assert {"footprint.sigma1", "footprint.x", "wave.500nm", "geometric.600nm"} <= names
