"""Jobs out of the command line (issue 30): the render jobs and the BRDF models are library functions that take a
typed request (or keyword arguments), own their defaults, name fields in their errors, and write their outputs as a
set; the CLI only maps flags to them."""
import inspect
import json

import numpy as np
import pytest

from cli_helpers import run_cli
from waveoptics import brdf, vocabulary
from waveoptics.errors import FieldError
from waveoptics.renderers import requests

# ---------------------------------------------------------------------------------------------------------------
# the requests own the defaults


def _parsed(argv):
    from waveoptics.cli import build_parser

    return build_parser().parse_args(argv)


def _same_default(value, default) -> bool:
    """An option's default *value* is the request's *default*; a switch not given reads None (off), and the
    summaries echo it as given, so None stands for False."""
    return (value is None and default is False) or value == default


def test_render_options_show_the_request_defaults():
    """Every field of RenderRequest carried by a render option defaults to the field's default (the budget is
    given in seconds as text, the wavelength step as a length with unit)."""
    args = _parsed(["render", "-o", "x"])
    for f in requests.RenderRequest.__dataclass_fields__.values():
        if f.name == "budget_s":
            assert float(args.budget) == f.default
        elif f.name == "sphere_size":
            assert args.sphere_size == f.default == requests.GlintRequest.sphere_size
        else:
            assert _same_default(getattr(args, f.name), f.default), f.name
    assert requests.RenderRequest.wavelength_step == f"{vocabulary.RENDER_WAVELENGTH_STEP_NM:g}nm"


def test_renderer_brdf_takes_its_defaults_from_the_model_request():
    from waveoptics.renderers import renderer_brdf

    sig = inspect.signature(renderer_brdf).parameters
    for name in ("material", "alpha", "alpha_y", "ndf", "nano", "surface", "diffraction", "kd", "diffuse",
                 "resolution", "exact", "multiple_scattering"):
        assert sig[name].default == requests.field_default(requests.RendererModel, name), name
    assert sig["wavelength_step_nm"].default == vocabulary.RENDER_WAVELENGTH_STEP_NM


# ---------------------------------------------------------------------------------------------------------------
# the render jobs


def test_render_job_errors_name_fields_not_flags(tmp_path):
    pytest.importorskip("mitsuba")
    from waveoptics.renderers.jobs import render_job

    for request, fields in ((requests.RenderRequest(target_noise=0.0), ("target_noise",)),
                            (requests.RenderRequest(max_spp=8), ("max_spp", "spp")),
                            (requests.RenderRequest(variant="scalar_rgb", bsdf="measured"), ("bsdf", "variant")),
                            (requests.RenderRequest(bsdf="nope"), ("bsdf",)),
                            (requests.RenderRequest(nano="none", surface="x.npz"), ("nano", "surface")),
                            (requests.RenderRequest(spacing="5nm"), ("spacing", "surface"))):
        with pytest.raises(FieldError) as err:
            render_job(request, tmp_path / "o")
        assert err.value.fields[:len(fields)] == fields and "--" not in str(err.value), str(err.value)
    assert not list((tmp_path / "o").iterdir()) if (tmp_path / "o").exists() else True


def _procedural():
    return "procedural:brushed:0.2mm:0.5um:3"


def test_glints_job_writes_the_set_and_agrees_with_the_renderer(tmp_path):
    """The job renders what :func:`render_glints` renders for the same settings (its directions and wavelengths
    parsed from the request), writes the five files and a summary of them, and its ΔE2000 mean is the CIEDE2000 of
    the two images written (recomputed here with colour-science's own implementation, not the library's)."""
    from waveoptics import surfaces
    from waveoptics.renderers import glints
    from waveoptics.renderers.glint_job import GLINT_OUTPUTS, glints_job

    req = requests.GlintRequest(surface=_procedural(), sphere_size=10, wavelengths="500,600", incident="20,10")
    seen = []
    r = glints_job(req, tmp_path / "g", on_estimate=seen.append)
    assert sorted(p.name for p in (tmp_path / "g").iterdir()) == sorted(GLINT_OUTPUTS)
    summary = json.loads((tmp_path / "g" / "summary.json").read_text())
    assert summary["outputs"] == list(GLINT_OUTPUTS) and summary["light_deg"] == [20.0, 10.0]
    assert summary["view_deg"] == [30.0, 180.0] and summary["wavelengths_nm"] == [500.0, 600.0]
    assert len(seen) == 1 and summary["estimate"]["estimate_s"] == seen[0].estimate_s

    settings = glints.GlintSettings(size=10, light_deg=20.0, light_azimuth_deg=10.0, view_deg=30.0,
                                    view_azimuth_deg=180.0, wavelengths_nm=(500.0, 600.0))
    direct = glints.render_glints(surfaces.procedural("brushed", 0.2e-3, 0.5e-6, 3), "aluminium", settings)
    np.testing.assert_array_equal(r.summary["pixels_on_field"], int(direct.on_field.sum()))
    np.testing.assert_allclose(summary["footprint_sigma_m"], direct.footprint_sigma_m, rtol=0)

    colour = pytest.importorskip("colour")
    on = direct.on_field

    def lab(rgb):
        return colour.XYZ_to_Lab(colour.RGB_to_XYZ(rgb, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=False))

    de = colour.delta_E(lab(direct.wave), lab(direct.geometric), method="CIE 2000")
    assert summary["delta_e2000_mean"] == pytest.approx(float(de[on].mean()), rel=1e-6, abs=1e-9)


def test_glints_job_writes_nothing_when_it_fails(tmp_path, monkeypatch):
    """Whole or not at all: a failure while the files are written leaves the directory as it was."""
    from waveoptics.io import files
    from waveoptics.renderers.glint_job import glints_job

    def broken(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(files, "write_exr", broken)
    with pytest.raises(OSError, match="disk full"):
        glints_job(requests.GlintRequest(surface=_procedural(), sphere_size=6, wavelengths="550"), tmp_path / "g")
    assert list((tmp_path / "g").iterdir()) == []


def test_glint_request_errors_name_fields(tmp_path):
    from waveoptics.renderers.glint_job import glints_job

    for request, field in ((requests.GlintRequest(), "surface"),
                           (requests.GlintRequest(surface="procedural:brushed"), "surface"),
                           (requests.GlintRequest(surface=_procedural(), incident="95"), "incident"),
                           (requests.GlintRequest(surface=_procedural(), coherence="-1um"), "coherence")):
        with pytest.raises(FieldError) as err:
            glints_job(request, tmp_path / "g")
        assert err.value.field == field and "--" not in str(err.value), str(err.value)


# ---------------------------------------------------------------------------------------------------------------
# the BRDF model registry


@pytest.mark.parametrize("name", list(brdf.BRDF_MODELS))
def test_the_registry_is_each_factorys_signature(name):
    """Each model's parameters (name, default, order) are its factory's keyword arguments, read by inspect."""
    sig = [(n, p.default if p.default is not inspect.Parameter.empty else vocabulary.REQUIRED)
           for n, p in inspect.signature(brdf.BRDF_MODELS[name]).parameters.items() if n != "wavelengths_nm"]
    assert sig == [(p.name, p.default) for p in brdf.BRDF_MODEL_PARAMETERS[name]]
    assert all(p.meaning for p in brdf.BRDF_MODEL_PARAMETERS[name])
    assert tuple(brdf.BRDF_MODELS) == tuple(brdf.BRDF_MODEL_HELP) == tuple(vocabulary.BRDF_MODEL_PARAMETERS)


@pytest.mark.parametrize("name, kw", [("microfacet", dict(ior="1.5", kd=0.0)), ("rough-dielectric", dict(ior="1.5"))])
def test_a_model_built_by_name_is_the_closed_form_at_normal_incidence(name, kw):
    """GGX at ω_i = ω_o = n: D = 1/(π α²), G = 1, F(0) = ((n − 1)/(n + 1))² (Walter et al. 2007, eqs. 20, 33):
    f = F(0) / (4 π α²), the reflection of a conductor-style microfacet BRDF and of the rough dielectric alike."""
    alpha, n = 0.25, 1.5
    m = brdf.build_brdf_model(name, np.array([550.0]), alpha=alpha, **kw)
    z = np.array([[0.0, 0.0, 1.0]])
    np.testing.assert_allclose(m.evaluate(z, z), ((n - 1) / (n + 1)) ** 2 / (4 * np.pi * alpha ** 2), rtol=1e-9)


def test_build_by_name_refuses_another_models_parameter():
    with pytest.raises(FieldError) as err:
        brdf.build_brdf_model("rough-dielectric", np.array([550.0]), alpha=0.2, ior="1.5", kd=0.3)
    assert err.value.field == "kd" and "microfacet, twoscale" in str(err.value)
    with pytest.raises(FieldError) as err:
        brdf.build_brdf_model("nosuch", np.array([550.0]))
    assert err.value.field == "model"


def test_brdf_options_show_the_registry_defaults():
    """The brdf command's options default to the registry's defaults, and each model reads the options of its
    registry parameters."""
    from waveoptics.cli.brdf import DEST, INPUTS, MODELS

    args = _parsed(["brdf", "--incident", "30"])
    for name, params in vocabulary.BRDF_MODEL_PARAMETERS.items():
        for p in params:
            if p.name in INPUTS or p.name in ("tradeoff", "device"):
                continue
            assert _same_default(getattr(args, DEST.get(p.name, p.name)), p.default), (name, p.name)
            assert DEST.get(p.name, p.name) in MODELS[name].uses
    assert args.no_tradeoff is (not vocabulary.BRDF_MODEL_PARAMETERS["microfacet"][14].default)


def test_the_brdf_command_sets_models_up_through_the_registry(monkeypatch):
    """``brdf --model NAME`` calls :func:`waveoptics.brdf.build_brdf_model` with the model's parameters."""
    calls = []
    real = brdf.build_brdf_model

    def spy(name, wavelengths_nm, **params):
        calls.append((name, params))
        return real(name, wavelengths_nm, **params)

    monkeypatch.setattr(brdf, "build_brdf_model", spy)
    rc, out, err, _ = run_cli(["brdf", "--model", "rough-dielectric", "--alpha", "0.25", "--ior", "1.5",
                               "--incident", "0", "--outgoing", "0,0", "--json"])
    assert rc == 0, err
    assert calls == [("rough-dielectric", dict(alpha=0.25, roughness=None, alpha_y=None, ndf="beckmann", ndf_shape=None,
                                               shadowing="smith-correlated", material=None, ior="1.5",
                                               fresnel="exact", multiple_scattering=None, nano_frame="macro"))]
    f = json.loads(out)["values"][0]["brdf"]
    assert f == pytest.approx(0.04 / (4 * np.pi * 0.25 ** 2), rel=1e-9)


def test_export_job_errors_name_fields(tmp_path):
    from waveoptics.renderers.jobs import export_job

    with pytest.raises(FieldError) as err:
        export_job(requests.RendererModel(), tmp_path / "m.txt")
    assert err.value.fields == ("output", "format") and "--" not in str(err.value)
    (tmp_path / "m.bsdf").write_bytes(b"")
    with pytest.raises(FieldError) as err:
        export_job(requests.RendererModel(), tmp_path / "m.bsdf")
    assert err.value.field == "output" and "overwrite=True" in str(err.value)
