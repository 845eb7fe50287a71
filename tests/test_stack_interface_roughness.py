"""A film's top interface with its own rms roughness (``FILM:THICKNESS:roughness=R``, issue 33): interface j's PSD is
r_j² times the nano-roughness model's. Held to Elson's rough-stack BRDF given one PSD per interface explicitly (each a
PSDModel whose σ is r_j σ: S ∝ σ², a different route than the stack's r_j), to the additivity of uncorrelated
interfaces (f = f_substrate + r² f_top), to the quadratic law of correlated ones, and through the product (the
Rayleigh-Rice model by name and the command line)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from waveoptics import scatter
from waveoptics.brdf import build_brdf_model
from waveoptics.cli import main as cli_main
from waveoptics.errors import FieldError
from waveoptics.materials import get_material
from waveoptics.surfaces import PSDModel

LAM = np.array([450.0, 550.0, 650.0])
SIGMA = 2e-9
PSD = PSDModel("abc", sigma=SIGMA, B=2e-6, C=2.6)


def _dirs(theta_deg, phi_deg):
    t, p = np.radians(np.asarray(theta_deg, float)), np.radians(np.asarray(phi_deg, float))
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


WI = _dirs([0.0, 30.0, 60.0], [0.0, 0.0, 0.0])[None, :, None, :]
WO = _dirs([0.0, 20.0, 45.0, 70.0, 35.0], [0.0, 180.0, 90.0, 200.0, 10.0])[None, None]
L = LAM[:, None, None]


def _scaled(r):
    return None if r == 0 else PSDModel("abc", sigma=r * SIGMA, B=2e-6, C=2.6)


def test_the_grammar_reads_each_films_roughness_and_names_it():
    st = get_material("Si|SiO2:100nm:roughness=0.5|TiO2:50nm")
    assert st.interface_roughness == (1.0, 0.5, 1.0) and st.roughness_scales == (1.0, 0.5, 1.0)
    assert get_material(st.name).interface_roughness == st.interface_roughness      # the name reads back
    plain = get_material("Si|SiO2:100nm|TiO2:50nm")
    assert plain.interface_roughness == () and plain.roughness_scales == (1.0, 1.0, 1.0)
    assert st.cache_name != plain.cache_name                                         # caches tell them apart
    assert np.array_equal(st.F(0.7, LAM), plain.F(0.7, LAM))                        # the flat stack is the same


@pytest.mark.parametrize("spec, words", [("Al|Al2O3:120nm:roughness=-1", "'-1', which is not a number >= 0"),
                                         ("Al|Al2O3:120nm:roughness=nan", "'nan', which is not a number >= 0"),
                                         ("Al|Al2O3:120nm:roughness=", "'', which is not a number >= 0"),
                                         ("Al|Al2O3:roughness=0.5", "needs a thickness")])
def test_a_bad_roughness_is_refused_in_one_line_naming_the_material(spec, words):
    with pytest.raises(FieldError) as e:
        get_material(spec)
    msg = str(e.value)
    assert msg.startswith("material") and words in msg and "\n" not in msg


@pytest.mark.parametrize("corr", ["correlated", "uncorrelated", 0.4])
@pytest.mark.parametrize("r", [0.0, 0.5, 1.7])
def test_the_stacks_roughness_equals_a_psd_of_that_sigma_on_its_interface(r, corr):
    st = get_material(f"Al|Al2O3:120nm:roughness={r:g}")
    plain = get_material("Al|Al2O3:120nm")
    got = scatter.rough_stack_brdf(WI, WO, L, st, PSD, corr)
    want = scatter.rough_stack_brdf(WI, WO, L, plain, [PSD, _scaled(r)], corr)
    assert np.all(want > 0)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)


def test_uncorrelated_interfaces_add_and_correlated_ones_follow_the_square_of_their_sum():
    """Uncorrelated: f(r) = f(substrate alone) + r² f(top alone). Correlated: f(r) is a quadratic in r whose value
    at r = 0 is the substrate alone and whose r² coefficient is the top alone (fit through r = 0, 1, 2, checked at
    r = 0.5)."""
    plain = get_material("Al|Al2O3:120nm")
    sub = scatter.rough_stack_brdf(WI, WO, L, plain, [PSD, None], "uncorrelated")
    top = scatter.rough_stack_brdf(WI, WO, L, plain, [None, PSD], "uncorrelated")

    def f(r, corr):
        return scatter.rough_stack_brdf(WI, WO, L, get_material(f"Al|Al2O3:120nm:roughness={r:g}"), PSD, corr)
    np.testing.assert_allclose(f(0.5, "uncorrelated"), sub + 0.25 * top, rtol=1e-12)
    f0, f1, f2 = (f(r, "correlated") for r in (0.0, 1.0, 2.0))
    a, c = f0, 0.5 * (f2 - 2 * f1 + f0)
    b = f1 - a - c
    np.testing.assert_allclose(f0, sub, rtol=1e-12)
    np.testing.assert_allclose(c, top, rtol=1e-9)
    np.testing.assert_allclose(f(0.5, "correlated"), a + 0.5 * b + 0.25 * c, rtol=1e-9)


def test_the_rayleigh_rice_model_and_the_command_line_carry_it(capsys):
    spec = "Al|Al2O3:120nm:roughness=0.3"
    m = build_brdf_model("rayleigh-rice", LAM, psd=PSD, material=spec, roughness_correlation="uncorrelated")
    want = scatter.rough_stack_brdf(WI, WO, L, get_material("Al|Al2O3:120nm"), [PSD, _scaled(0.3)], "uncorrelated")
    np.testing.assert_allclose(m.evaluate(WI[0, :, 0], WO[0, 0]), want, rtol=1e-12)
    args = ["brdf", "--model", "rayleigh-rice", "--material", spec, "--nano", "abc:sigma=2nm,B=2um,C=2.6",
            "--incident", "30", "--outgoing", "20,180", "--wavelengths", "550", "--roughness-correlation",
            "uncorrelated", "--json"]
    assert cli_main(args) == 0
    got = json.loads(capsys.readouterr().out)["values"][0]["brdf"]
    ref = scatter.rough_stack_brdf(_dirs(30.0, 0.0), _dirs(20.0, 180.0), 550.0, get_material("Al|Al2O3:120nm"),
                                   [PSD, _scaled(0.3)], "uncorrelated")
    assert got == pytest.approx(float(ref), rel=1e-12)
    assert cli_main(args[:4] + ["Al|Al2O3:120nm:roughness=-2"] + args[5:]) == 2
    err = capsys.readouterr().err
    assert "roughness '-2'" in err and len(err.strip().splitlines()) == 1
