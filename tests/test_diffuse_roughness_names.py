"""One name per quantity for the diffuse roughness (issue 30): ``diffuse_sigma`` is Oren-Nayar's σ (radians in the
library, an angle on the command line), ``diffuse_roughness`` is Burley's r; each model reads only its own.

References: M. Oren, S. K. Nayar, SIGGRAPH 1994 (qualitative model, A and B); B. Burley, "Physically-Based
Shading at Disney", SIGGRAPH 2012 course notes, §5.3 — both written out here, not taken from the library.
"""
import inspect
import json
import math
import re

import numpy as np
import pytest

from cli_helpers import run_cli
from waveoptics import brdf
from waveoptics.errors import FieldError


def _dir(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


PAIRS = [((30.0, 0.0), (50.0, 160.0)), ((70.0, 10.0), (20.0, 200.0)), ((45.0, 0.0), (60.0, 0.0))]


def _burley_ref(wi, wo, kd, r):
    h = (wi + wo) / np.linalg.norm(wi + wo)
    fd90 = 0.5 + 2 * r * float(wi @ h) ** 2
    return kd / math.pi * (1 + (fd90 - 1) * (1 - wi[2]) ** 5) * (1 + (fd90 - 1) * (1 - wo[2]) ** 5)


def _oren_nayar_ref(wi, wo, kd, sigma):
    ti, to = math.acos(wi[2]), math.acos(wo[2])
    dphi = math.atan2(wi[1], wi[0]) - math.atan2(wo[1], wo[0])
    A = 1 - 0.5 * sigma ** 2 / (sigma ** 2 + 0.33)
    B = 0.45 * sigma ** 2 / (sigma ** 2 + 0.09)
    alpha, beta = max(ti, to), min(ti, to)
    return kd / math.pi * (A + B * max(0.0, math.cos(dphi)) * math.sin(alpha) * math.tan(beta))


@pytest.mark.parametrize("wi_deg, wo_deg", PAIRS)
def test_each_diffuse_model_reads_its_own_roughness(wi_deg, wo_deg):
    """f(model) − f(none) with no trade-off is the paper's diffuse term at the model's own parameter; the other
    model's parameter changes nothing."""
    wi, wo = _dir(*wi_deg), _dir(*wo_deg)
    kw = dict(alpha=0.3, ndf="ggx", eta=1.5, kd=0.6, tradeoff=False)
    spec = brdf.brdf(wi, wo, diffuse="none", **kw)
    for r in (0.0, 0.7, 1.0):
        got = brdf.brdf(wi, wo, diffuse="burley", diffuse_roughness=r, diffuse_sigma=0.5, **kw) - spec
        assert got == pytest.approx(_burley_ref(wi, wo, 0.6, r), rel=1e-12)
    for sigma in (0.0, 0.4, 1.2):
        got = brdf.brdf(wi, wo, diffuse="oren-nayar", diffuse_sigma=sigma, diffuse_roughness=0.9, **kw) - spec
        assert got == pytest.approx(_oren_nayar_ref(wi, wo, 0.6, sigma), rel=1e-12)


def test_the_brdf_object_passes_burleys_r_and_refuses_sigma_for_burley():
    """MicrofacetBRDF: the diffuse part scales with Burley's formula in r (the trade-off weight cancels in the
    ratio); Oren-Nayar's σ given to Burley is refused, naming the field to use."""
    wi, wo = _dir(30.0, 0.0)[None], _dir(55.0, 150.0)[None]
    micro = brdf.Micro(alpha=0.3, ndf="ggx")
    none = brdf.MicrofacetBRDF("1.5", micro, kd=0.5, diffuse="none").eval(wi, wo, 550.0)
    part = {r: brdf.MicrofacetBRDF("1.5", micro, kd=0.5, diffuse="burley", diffuse_roughness=r).eval(wi, wo, 550.0)
            - none for r in (0.2, 0.9)}
    ref = _burley_ref(wi[0], wo[0], 0.5, 0.9) / _burley_ref(wi[0], wo[0], 0.5, 0.2)
    assert float(part[0.9][0] / part[0.2][0]) == pytest.approx(ref, rel=1e-12)
    with pytest.raises(FieldError, match="diffuse_sigma is Oren-Nayar's σ; Burley's roughness is diffuse_roughness"):
        brdf.MicrofacetBRDF("1.5", micro, kd=0.5, diffuse="burley", diffuse_sigma=0.3)
    with pytest.raises(FieldError, match=r"diffuse_roughness=1\.5 is not allowed"):
        brdf.MicrofacetBRDF("1.5", micro, kd=0.5, diffuse="burley", diffuse_roughness=1.5)
    with pytest.raises(TypeError, match="sigma"):   # the old keyword that held either is gone
        brdf.brdf(wi, wo, alpha=0.3, diffuse="oren-nayar", kd=0.5, sigma=0.3)


def test_cli_diffuse_sigma_is_an_angle():
    """--diffuse-sigma takes 20, 20deg or 0.349…rad alike; the JSON records diffuse_sigma_deg; the value matches
    Oren-Nayar at σ = 20° (no trade-off, minus the specular part)."""
    base = ["brdf", "--model", "microfacet", "--material", "1.5", "--alpha", "0.3", "--ndf", "ggx", "--kd", "0.5",
            "--no-tradeoff", "--incident", "30", "--outgoing", "50,160", "--wavelengths", "550", "--json"]
    vals = {}
    for text in ("20", "20deg", f"{math.radians(20):.17g}rad"):
        rc, out, err, _ = run_cli(base + ["--diffuse", "oren-nayar", "--diffuse-sigma", text])
        assert rc == 0, err
        doc = json.loads(out)
        assert doc["parameters"]["diffuse_sigma_deg"] == pytest.approx(20.0, rel=1e-12)
        vals[text] = float(np.ravel(doc["values"][0]["brdf"])[0])
    rc, out, err, _ = run_cli(base + ["--diffuse", "none"])
    spec = float(np.ravel(json.loads(out)["values"][0]["brdf"])[0])
    ref = _oren_nayar_ref(_dir(30.0, 0.0), _dir(50.0, 160.0), 0.5, math.radians(20))
    for v in vals.values():
        assert v - spec == pytest.approx(ref, rel=1e-9)
    rc, out, err, _ = run_cli(base + ["--diffuse", "oren-nayar", "--diffuse-sigma", "20 parsecs"])
    assert rc == 2 and "--diffuse-sigma" in err


@pytest.mark.parametrize("diffuse, new", [("oren-nayar", "diffuse_sigma="), ("burley", "diffuse_roughness="),
                                          ("lambert", "diffuse_sigma=.* or diffuse_roughness=")])
def test_the_removed_sigma_keyword_names_its_new_name(diffuse, new):
    """Python keywords are renamed outright (the CLI's old flags warn until 0.3): the old sigma= is refused, not taken,
    in one line that names the keyword of the call's diffuse model."""
    wi, wo = _dir(30.0, 0.0), _dir(50.0, 160.0)
    for fn in (brdf.brdf, brdf.brdf_cl):
        with pytest.raises(TypeError) as err:
            fn(wi, wo, alpha=0.3, eta=1.5, diffuse=diffuse, kd=0.5, sigma=0.3)
        msg = str(err.value)
        assert "\n" not in msg and msg.startswith(f"{fn.__name__}() got an unexpected keyword argument 'sigma': it "
                                                  "was renamed; use ")
        assert re.search(new, msg), msg
    # the new keywords keep the signature a reader (and inspect) sees
    assert "diffuse_sigma" in inspect.signature(brdf.brdf).parameters
