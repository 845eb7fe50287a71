"""The library's BRDF model registry (``waveoptics.brdf.BRDF_MODELS``, what ``waveoptics brdf`` calls): a factory
evaluates the closed form at normal incidence, and its errors name keyword arguments, never command-line flags."""
import numpy as np
import pytest

from waveoptics import brdf
from waveoptics.errors import FieldError


def test_microfacet_factory_matches_the_closed_form_at_normal_incidence():
    """GGX at ω_i = ω_o = n: D(n) = 1/(π α²), Λ(n) = 0 so G = 1, F(0) = ((n − 1)/(n + 1))² (Walter et al. 2007,
    eqs. 20 and 33), so f = F(0) / (4 π α²)."""
    alpha, n = 0.3, 1.5
    model = brdf.BRDF_MODELS["microfacet"](wavelengths_nm=np.array([450.0, 650.0]), alpha=alpha, ior=str(n), kd=0.0)
    z = np.array([[0.0, 0.0, 1.0]])
    f = model.evaluate(z, z)
    want = ((n - 1) / (n + 1)) ** 2 / (4 * np.pi * alpha ** 2)
    assert f.shape == (2, 1, 1)
    np.testing.assert_allclose(f, want, rtol=1e-12)


@pytest.mark.parametrize("name, kwargs, field", [
    ("microfacet", dict(alpha=0.1, roughness=0.3, ior="1.5"), "alpha"),
    ("microfacet", dict(alpha=0.1), "material"),
    ("microfacet", dict(alpha=0.1, material="Au", ior="1.5"), "material"),
    ("microfacet", dict(alpha=0.1, ior="1.5", diffuse_sigma_deg=120.0), "diffuse_sigma_deg"),
    ("rayleigh-rice", dict(psd=None), "material"),
    ("twoscale", dict(alpha=0.1, ior="1.5"), "nano"),
    ("kirchhoff", dict(surface=None), "surface"),
])
def test_factory_errors_name_fields(name, kwargs, field):
    with pytest.raises(FieldError) as err:
        brdf.BRDF_MODELS[name](wavelengths_nm=np.array([550.0]), **kwargs)
    assert err.value.field == field and "--" not in str(err.value)
