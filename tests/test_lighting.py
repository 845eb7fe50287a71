"""Environment lighting and sphere renders by multiple importance sampling (issue 14).

Oracles: χ² of the map's sampler against its pdf; the white furnace (a white Lambertian sphere in a constant
map of radiance 1 is 1 everywhere); a microfacet sphere in a constant map shows each pixel's directional albedo
(reciprocity: the radiance towards the view is the albedo of the view direction).
"""
import numpy as np
import pytest

from waveoptics.renderers import lighting, sphere as render
from waveoptics.brdf import BRDF, Micro, MicrofacetBRDF, chi2_test
from waveoptics.brdf.protocol import pdf_cosine, sample_cosine
from waveoptics.cli import main as cli_main


class Lambert(BRDF):
    """f = 1/π, cosine-sampled: written here, independent of the library's diffuse terms."""

    def _eval1(self, wi, wo, lam):
        return np.where((wi[:, 2] > 0) & (wo[:, 2] > 0), 1 / np.pi, 0.0)

    def _pdf1(self, wi, wo, lam):
        return pdf_cosine(wo)

    def _sample1(self, wi, u, lam):
        return sample_cosine(u)


@pytest.mark.parametrize("kind", ["sky", "studio"])
def test_environment_sampling_passes_chi2(kind):
    env = lighting.procedural_environment(kind, height=32)
    r = chi2_test(env.sample, env.pdf, sample_count=200_000, res=31, ires=16, pole=(0, 0, 1), test_count=2)
    assert r.passed, r.message
    assert r.pdf_integral == pytest.approx(1.0, abs=1e-2)


def test_white_furnace():
    env = lighting.procedural_environment("constant", height=16)
    img, on = render.render_sphere_environment(Lambert(), [450.0, 550.0, 650.0], env, size=32, spp=16, seed=1)
    vals = img[on]
    assert vals.mean() == pytest.approx(1.0, abs=4 * vals.std() / np.sqrt(vals.size))
    np.testing.assert_allclose(vals.mean(axis=0), vals.mean(), rtol=1e-3)   # white stays white


def test_constant_map_shows_the_directional_albedo():
    env = lighting.procedural_environment("constant", height=16)
    b = MicrofacetBRDF("gold", Micro(alpha=0.3, ndf="ggx"), fresnel="one")
    img, on = render.render_sphere_environment(b, [550.0], env, size=24, spp=32, seed=2)
    n, _ = render.sphere_geometry(24)
    cz = n[on][:, 2]
    E = b.albedo(np.stack([np.sqrt(1 - cz ** 2), np.zeros_like(cz), cz], axis=-1), 550.0)
    diff = img[on][:, 1] - E
    assert abs(diff.mean()) < 4 * diff.std() / np.sqrt(diff.size)
    assert np.all(img[on] <= 1.5)


def test_cli_environment_errors_are_one_line(tmp_path, capsys):
    for bad in ("nowhere.exr", "sunset"):
        rc = cli_main(["simulate", "--environment", bad, "-o", str(tmp_path / "o"), "--resolution", "16"])
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1 and "environment" in err
    assert not (tmp_path / "o").exists()


def test_simulate_writes_the_environment_renders(tmp_path, capsys):
    from waveoptics import io, simulate

    out = tmp_path / "o"
    assert cli_main(["simulate", "-o", str(out), "--resolution", "32", "--sphere-size", "32", "--wavelengths",
                     "450,550,650", "--environment", "constant", "--spp", "2"]) == 0
    for name in simulate.output_files(True):
        assert (out / name).is_file(), name
    _, hdr = io.read_exr(out / "sphere_env_wave.exr")
    assert "environment" in str(hdr.get("waveoptics_light_deg"))
    # a render is itself readable as a map (R, G, B channels): the file route of --environment
    env = lighting.load_environment(out / "sphere_env_wave.exr")
    assert env.shape == (32, 32)
