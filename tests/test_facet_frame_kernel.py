"""The facet-frame quadrature's OpenCL kernel (kernels/facet_frame.cl) against its NumPy twin.

Reference: the NumPy loop of :func:`facet_frame_diffraction` (``backend="numpy"``), a different implementation
(float64 arrays over all cells per node, the Sobol normals turned by rotation matrices, the facet tables read by
``np.interp`` and gathers) of the same sum, which tests/test_twoscale_facet_frame.py holds against the paper's
integral. The kernel runs in float32 around the same float32 tables: every cell above 1e-3 of the lobe's maximum
agrees to 1e-4 relative and the albedo (Σ f du dv) to 1e-5. Measured on these cases: cells ≤ 1.4e-6, except 4
cells of Kirchhoff p light on glass at 56° at 5.4e-5 (a node's discrete choice taken the other way in float32: the
float64 kernel agrees there to 2e-9); albedos ≤ 1.3e-7; the float64 kernel ≤ 2.2e-8.
"""
import numpy as np
import pytest

from waveoptics import surfaces
from waveoptics.brdf import Micro, Nano, facet_frame_diffraction
from waveoptics.brdf.facet_frame_cl import FACET_FRAME_BACKENDS, facet_frame_backend
from waveoptics.errors import FieldError
from waveoptics.materials import get_material
from waveoptics.runtime import get_runtime, opencl_available
from waveoptics.scatter.grid import DirectionGrid

pytestmark = pytest.mark.skipif(not opencl_available(), reason="no OpenCL device")

#: cells above CUT × the lobe's maximum agree to RTOL relative; the albedo to ALBEDO_RTOL
RTOL, CUT, ALBEDO_RTOL = 1e-4, 1e-3, 1e-5
LAMS = [450.0, 650.0]
GRID = DirectionGrid.hemisphere(32)
#: one Nano for all tests: its facet tables are cached on it per (grid, model, material, polarization)
NANO = Nano(model=surfaces.PSDModel("abc", 10e-9, B=2e-6, C=2.6))
AL, GLASS = get_material("aluminium"), get_material("1.5")


def _wi(theta_deg, phi_deg=0.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def _both(theta, micro, material=AL, diffraction="kirchhoff", polarization="unpolarized", phi=0.0, **kw):
    def F(x, lam):
        return material.F(x, lam)

    return [facet_frame_diffraction(_wi(theta, phi), LAMS, material, micro, NANO, GRID, F, diffraction=diffraction,
                                    polarization=polarization, backend=b, **kw) for b in ("numpy", "opencl")]


def _assert_twins(numpy_result, cl_result, what):
    ref, got = numpy_result[0], cl_result[0]
    assert ref.max() > 0, what
    big = ref > CUT * ref.max(axis=(1, 2), keepdims=True)
    rel = np.abs(got - ref)[big] / ref[big]
    assert rel.max() <= RTOL, f"{what}: max relative difference {rel.max():.3g} on {big.sum()} cells"
    # the albedo Σ f du dv (the grid's measure cos θ dω = du dv), and the budget terms, which the kernel leaves
    alb_ref, alb = ref.sum(axis=(1, 2)), got.sum(axis=(1, 2))
    np.testing.assert_allclose(alb, alb_ref, rtol=ALBEDO_RTOL, err_msg=what)
    for a, b in zip(numpy_result[1:], cl_result[1:]):
        np.testing.assert_allclose(b, a, rtol=1e-12)
    # no cell of the NumPy sum that is 0 is lit by the kernel, nor the other way (the nodes' masks agree)
    assert np.array_equal(ref > 0, got > 0) or np.abs(got - ref).max() <= 1e-6 * ref.max(), what


@pytest.mark.parametrize("ndf, alpha", [("beckmann", 0.05), ("ggx", 0.3)])
@pytest.mark.parametrize("theta", [0.0, 30.0, 75.0, 88.0])
def test_kirchhoff_on_aluminium(ndf, alpha, theta):
    _assert_twins(*_both(theta, Micro(alpha=alpha, ndf=ndf)), f"{ndf} α {alpha} θ_i {theta}")


@pytest.mark.parametrize("ndf, alpha, theta", [("ggx", 0.05, 30.0), ("beckmann", 0.3, 75.0)])
def test_rayleigh_rice_on_aluminium(ndf, alpha, theta):
    _assert_twins(*_both(theta, Micro(alpha=alpha, ndf=ndf), diffraction="rayleigh-rice"),
                  f"rayleigh-rice {ndf} α {alpha} θ_i {theta}")


@pytest.mark.parametrize("diffraction, polarization, theta", [("rayleigh-rice", "p", 30.0),
                                                              ("rayleigh-rice", "s", 75.0),
                                                              ("kirchhoff", "p", 56.0)])
def test_polarized_light_on_glass(diffraction, polarization, theta):
    """Glass: the Rayleigh-Rice tables of the facet's own s and p light mixed by cos²η_i in the kernel."""
    _assert_twins(*_both(theta, Micro(alpha=0.3, ndf="beckmann"), GLASS, diffraction, polarization),
                  f"glass {diffraction} {polarization} θ_i {theta}")


def test_anisotropic_ndf_at_an_azimuth():
    """Anisotropic GGX: the NDF nodes stay in the surface's frame (WO_ISO 0); light at azimuth 40°."""
    _assert_twins(*_both(45.0, Micro(alpha=0.1, alpha_y=0.3, ndf="ggx"), phi=40.0), "anisotropic ggx")


@pytest.mark.parametrize("shadowing", ["smith", "cook-torrance", "implicit"])
def test_every_shadowing_form(shadowing):
    _assert_twins(*_both(60.0, Micro(alpha=0.3, ndf="beckmann", shadowing=shadowing)), shadowing)


@pytest.mark.parametrize("ndf", ["blinn-phong", "abc"])
def test_ndfs_with_a_radial_lambda(ndf):
    _assert_twins(*_both(40.0, Micro(alpha=0.2, ndf=ndf)), ndf)



def test_bridge_normals_in_a_lobes_tail():
    """Beckmann α 0.15 × 0.4 with a Gaussian nano lobe (σ 15 nm, T 1.5 µm), light at 60°, azimuth 30°: cells of
    the lobe's tail get the third node set about the bridge point (:func:`waveoptics.brdf.facet.bridge_point`; its
    Gaussian normals and their density in the kernel, their share β), the same sum in both."""
    from waveoptics.brdf import facet

    nano = Nano(model=surfaces.PSDModel("gaussian", 15e-9, T=1.5e-6))
    micro = Micro(alpha=0.15, alpha_y=0.4, ndf="beckmann")
    wi = _wi(60.0, 30.0)
    res = [facet_frame_diffraction(wi, LAMS, AL, micro, nano, GRID, lambda x, lam: AL.F(x, lam), backend=b)
           for b in ("numpy", "opencl")]
    wo = GRID.directions()[GRID.inside]
    h = (wi + wo) / np.linalg.norm(wi + wo, axis=-1, keepdims=True)
    rad = facet.NanoRadial(nano.model, facet.FACET_REFERENCE_NM, "kirchhoff", 256)
    beta = facet.bridge_point(h, h @ wi, rad, rad.level(h @ wi), (128, 256), ndf="beckmann", ax=0.15, ay=0.4,
                              c=None)[2]
    lobe = res[0][0][0][GRID.inside]
    assert np.sum((beta > 0) & (lobe > CUT * lobe.max())) >= 10   # the bridge is on in cells the twins compare
    _assert_twins(*res, "bridge normals")

def test_float64_device_arithmetic():
    if not get_runtime().fp64:
        pytest.skip("the device has no fp64")
    _assert_twins(*_both(75.0, Micro(alpha=0.3, ndf="ggx"), precision="float64"), "float64")


def test_backend_choice():
    """``auto`` takes the kernel for statistics and a kernel NDF, NumPy for an NDF without an OpenCL twin; asking
    the kernel for one is refused naming the field; an unknown backend is refused with the allowed ones."""
    assert FACET_FRAME_BACKENDS == ("auto", "opencl", "numpy")
    assert facet_frame_backend("auto", Micro(alpha=0.1, ndf="ggx"), NANO) == "opencl"
    epd = Micro(alpha=0.1, ndf="epd")
    assert facet_frame_backend("auto", epd, NANO) == "numpy"
    with pytest.raises(FieldError, match="backend 'opencl' .* NDF 'epd' has no OpenCL twin") as e:
        facet_frame_backend("opencl", epd, NANO)
    assert e.value.field == "backend"
    rng = np.random.default_rng(1)
    field = Nano(surface=surfaces.HeightField(1e-9 * rng.standard_normal((8, 8)), 1e-7, 1e-7))
    assert facet_frame_backend("auto", Micro(alpha=0.1), field) == "numpy"
    with pytest.raises(FieldError, match="height field"):
        facet_frame_backend("opencl", Micro(alpha=0.1), field)
    with pytest.raises(FieldError, match="unknown backend 'gpu'.*allowed: auto, numpy, opencl") as e:
        facet_frame_backend("gpu", Micro(alpha=0.1), NANO)
    assert e.value.field == "backend"


def test_wavelengths_in_passes(monkeypatch):
    """More wavelengths than one pass holds (``KERNEL_WAVELENGTHS``, here 1): each pass reads its own columns of
    the tables and writes its own of the result."""
    from waveoptics.brdf import facet_frame_cl

    monkeypatch.setattr(facet_frame_cl, "KERNEL_WAVELENGTHS", 1)
    _assert_twins(*_both(30.0, Micro(alpha=0.3, ndf="ggx")), "one wavelength per pass")


@pytest.mark.parametrize("diffraction,polarization", [("kirchhoff", "unpolarized"), ("rayleigh-rice", "s")])
def test_the_warm_up_launch_matches_the_kernels_arguments(monkeypatch, diffraction, polarization):
    """The warm-up thread launches the kernel over no cells with as many arguments as the kernel takes: a mismatch
    raised in the thread, where no test saw it and the warm-up was lost (found when the kernel gained an argument)."""
    import threading

    from waveoptics import scatter
    from waveoptics.brdf.facet_frame_cl import warm_facet_frame_kernel

    raised = []
    monkeypatch.setattr(threading, "excepthook", lambda args: raised.append(args.exc_value))
    thread = warm_facet_frame_kernel(Micro(alpha=0.1), NANO, scatter.get_model(diffraction, perturbative=True),
                                     polarization)
    assert thread is not None
    thread.join()
    assert not raised, raised
