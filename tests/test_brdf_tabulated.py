"""The two-scale BRDF from diffracted lobes tabulated over incidence (issue 14), and per-pixel sphere renders.

Oracles: direct grid evaluations at the same incidence (between table nodes too); grating orders, which sit at
fixed offsets from the mirror direction; a GGX/Beckmann sphere written here from Walter et al. 2007; χ² of the
sampler against its pdf.
"""
import warnings

import numpy as np
import pytest
from scipy import special

from waveoptics import brdf, colour
from waveoptics.renderers import sphere as render
from waveoptics.brdf import Micro, MicrofacetBRDF, TabulatedTwoScaleBRDF, chi2_test, reflected_samples
from waveoptics.request import make_nano
from waveoptics.scatter.grid import DirectionGrid


def _dir(theta_deg, phi_deg=0.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


NANO = make_nano("abc:sigma=20nm,B=2um,C=2.6", [550.0])
MICRO = Micro(alpha=0.05, ndf="beckmann")
GRID = DirectionGrid.hemisphere(128)


@pytest.fixture(scope="module")
def table():
    return TabulatedTwoScaleBRDF("gold", MICRO, nano=NANO, wavelengths_nm=(450.0, 550.0), resolution=128,
                                 thetas_deg=(10.0, 20.0, 30.0, 40.0, 50.0, 60.0))


def _direct(theta, phi=0.0, nano=NANO, micro=MICRO):
    wi = _dir(theta, phi)
    L = brdf.evaluate(wi, [550.0], "gold", micro, nano, GRID)
    return wi, L


def test_on_the_nodes_it_is_the_grid_model(table):
    """At a node the table returns the grid model's lobe (to the float32 rounding of the facet route's nano
    tables, whose sums depend on how many wavelengths are evaluated together: 4e-8 measured) up to θ_o 65°.
    Beyond, the read hands over to the rim tables (waveoptics.brdf.tabulated_rim: the same facet-frame sum at
    nodes 1.5° × 5° apart in (θ_o, φ_o), read bilinearly), which at the grid's cell centres differ from the sum
    there by their interpolation: measured max 0.32 % at 65-70°, 0.67 % at 70-80°, 0.56 % at 80-85°, 0.67 % at
    85-90° (the rim's last node is at 89.3°); 4.6 % at 85-90° before the facet tables held first-order lobes over
    cos²θ_o. Between the cell centres, at 40 random directions per band, the rim read is the closer one to the
    facet-frame sum: max / mean error 0.68 / 0.19 % at 70-80°, 0.45 / 0.18 % at 80-85°, 0.85 / 0.30 % at 85-89°,
    where the direction-cosine cells alone give 2.6 / 1.1 %, 36 / 5.2 %, 93 / 28 %."""
    wi, L = _direct(30.0)
    wo = GRID.directions()[GRID.inside]
    parts = table.eval_parts(wi, wo, 550.0)
    theta_o = np.degrees(np.arccos(wo[:, 2]))
    ref = L.diffraction[0][GRID.inside]
    for lo, hi, rtol in ((0, 65, 1e-6), (65, 80, 0.008), (80, 85, 0.008), (85, 90, 0.01)):
        s = (theta_o >= lo) & (theta_o < hi)
        np.testing.assert_allclose(parts["diffraction"][s], ref[s], rtol=rtol, atol=1e-15)
    c_ref = L.coherent[0][GRID.inside]
    assert np.max(np.abs(parts["coherent"] - c_ref)) < 1e-3 * c_ref.max()


@pytest.mark.parametrize("theta", [15.0, 32.5, 47.5, 55.0])
def test_between_nodes_the_lobe_follows_the_specular_direction(table, theta):
    """Issue 14's targets: peak within 1 %, energy within 2 % of a direct evaluation at that incidence, with 10°
    between nodes (the absolute-direction blend of two lobes at different places was 20 % off at the peak). The
    peak is taken over θ_o < 78°: the grid's last cells before the horizon hold the obliquity's 1/cos θ_o rise."""
    wi, L = _direct(theta)
    core = GRID.inside & (GRID.cos_theta > 0.2)
    wo = GRID.directions()[core]
    d = table.eval_parts(wi, wo, 550.0)["diffraction"]
    ref = L.diffraction[0][core]
    assert d.max() == pytest.approx(ref.max(), rel=0.01)
    wo_all = GRID.directions()[GRID.inside]
    assert table.eval_parts(wi, wo_all, 550.0)["diffraction"].sum() == pytest.approx(
        L.diffraction[0][GRID.inside].sum(), rel=0.02)
    # the naive blend for comparison: the two node lobes at the same absolute directions, by the lobes' L1 distance
    # to the direct lobe (measured 4.9, 4.1, 3.6, 2.4 times the table's at 15°, 32.5°, 47.5°, 55°). Not by the peak
    # height: at 55° the broad lobe's naive peak is within 0.20 % of the direct peak's height (the table's 0.16 %),
    # but a cell and a half off in place (θ_o 47.9° against 49.3°)
    k = int(theta // 10) - 1
    t = (theta % 10) / 10
    naive = ((1 - t) * table.table[0, k, 1] + t * table.table[0, k + 1, 1])[core]
    assert np.abs(naive - ref).sum() > 2 * np.abs(d - ref).sum()


def test_isotropic_tables_follow_the_light_azimuth(table):
    rng = np.random.default_rng(3)
    wo = rng.normal(size=(500, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = _dir(35.0)
    c, s = np.cos(1.1), np.sin(1.1)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    np.testing.assert_allclose(table.eval(wi @ R.T, wo @ R.T, 450.0), table.eval(wi, wo, 450.0), rtol=1e-9)


def test_a_grating_keeps_its_orientation_between_azimuth_nodes():
    """Grating orders sit at u_o + u_i = m λ/Λ along the grating vector, independent of the incidence: the
    azimuth-tabulated lobes keep them in place between nodes and conserve their energy."""
    warnings.simplefilter("ignore")
    nano = make_nano("sinusoid:amplitude=30nm,period=2um,orientation=30", [550.0])
    tab = TabulatedTwoScaleBRDF("gold", Micro(alpha=0.03, ndf="ggx"), nano=nano, wavelengths_nm=(550.0,), resolution=128,
                                thetas_deg=(20.0, 30.0, 40.0), n_phi=12)
    assert tab.table.shape[0] == 12
    wi, L = _direct(30.0, 45.0, nano=nano, micro=Micro(alpha=0.03, ndf="ggx"))
    wo = GRID.directions()[GRID.inside]
    d = tab.eval_parts(wi, wo, 550.0)["diffraction"]
    ref = L.diffraction[0][GRID.inside]
    assert np.argmax(d) == np.argmax(ref)
    assert d.sum() == pytest.approx(ref.sum(), rel=0.01)


def test_a_wavelength_outside_the_table_is_refused(table):
    with pytest.raises(Exception, match="wavelength 500 nm is not in this table"):
        table.eval(_dir(10), _dir(20, 180), 500.0)


@pytest.mark.parametrize("theta", [30.0, 70.0])
def test_sampling_passes_chi2(table, theta):
    wi = _dir(theta)

    sample = reflected_samples(table, wi, 550.0)
    r = chi2_test(sample, lambda d: table.pdf(wi, d, 550.0), sample_count=100_000, res=41, ires=12, test_count=2)
    assert r.passed, r.message
    assert r.pdf_integral == pytest.approx(r.valid_fraction, abs=1e-2)


# --- renders -----------------------------------------------------------------------------------------------

def _analytic_sphere(ndf, alpha, material, w, light, size):
    """A microfacet sphere written from Walter et al. 2007 in world space (isotropic D and Smith Λ of θ only)."""
    n, on = render.sphere_geometry(size)
    n = n[on]
    V = np.array([0.0, 0.0, 1.0])
    L = light / np.linalg.norm(light)
    ci, co = n @ L, n @ V
    h = (L + V) / np.linalg.norm(L + V)
    ch = n @ h
    t2 = (1 - ch ** 2) / ch ** 2
    if ndf == "ggx":
        D = alpha ** 2 / (np.pi * (ch ** 2 * (alpha ** 2 - 1) + 1) ** 2)

        def Lam(c):
            return (-1 + np.sqrt(1 + alpha ** 2 * (1 - c ** 2) / c ** 2)) / 2
    else:
        D = np.exp(-t2 / alpha ** 2) / (np.pi * alpha ** 2 * ch ** 4)

        def Lam(c):
            a = c / (alpha * np.sqrt(np.maximum(1 - c ** 2, 1e-300)))
            return (special.erf(a) - 1) / 2 + np.exp(-a * a) / (2 * a * np.sqrt(np.pi))
    lit = (ci > 0) & (co > 0)
    ci_, co_ = np.where(lit, ci, 1.0), np.where(lit, co, 1.0)
    G = 1 / (1 + Lam(ci_) + Lam(co_))
    mat = brdf.MicrofacetBRDF(material).material
    F = mat.F((L @ h) * np.ones((w.size, 1)), w[:, None])
    f = F * (G * D / (4 * ci_ * co_))[None]
    spec = np.where(lit[None], np.pi * f * ci_[None], 0.0).T
    rgb = np.zeros((size, size, 3))
    rgb[on] = colour.reflectance_to_rgb(spec, w, "D65")
    mask = np.zeros((size, size), bool)
    mask[on] = lit
    return rgb, mask


@pytest.mark.parametrize("ndf", ["ggx", "beckmann"])
def test_sphere_render_matches_an_analytic_per_pixel_render(ndf):
    w = np.array([450.0, 500.0, 550.0, 600.0, 650.0])
    light = _dir(30.0, 20.0)
    got, mask = render.render_sphere(MicrofacetBRDF("gold", Micro(alpha=0.05, ndf=ndf, shadowing="smith-correlated")),
                                     w, light, size=96)
    ref, mask_ref = _analytic_sphere(ndf, 0.05, "gold", w, light, 96)
    assert (mask == mask_ref).all()
    dE = colour.delta_e2000(np.maximum(got[mask], 1e-12), np.maximum(ref[mask], 1e-12))
    assert np.quantile(dE, 0.99) < 1.0


def test_anisotropic_highlights_keep_their_orientation():
    """A surface rougher along its x axis spreads the highlight along world x, and the swapped one along y."""
    w = np.array([550.0])

    def spread(ax, ay):
        img, _ = render.render_sphere(MicrofacetBRDF("gold", Micro(alpha=ax, alpha_y=ay, ndf="ggx")), w, [0, 0, 1.0], size=64)
        Y = colour.luminance(img)
        yy, xx = np.mgrid[0:64, 0:64]
        cx, cy = (xx * Y).sum() / Y.sum(), (yy * Y).sum() / Y.sum()
        return ((xx - cx) ** 2 * Y).sum() / Y.sum(), ((yy - cy) ** 2 * Y).sum() / Y.sum()
    sx, sy = spread(0.3, 0.05)
    tx, ty = spread(0.05, 0.3)
    assert sx > 2 * sy and ty > 2 * tx


# --- tables as functions ------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def table_file(tmp_path_factory):
    from waveoptics import distributed as D
    from waveoptics.request import SimulationRequest

    case = SimulationRequest("Au", nano="abc:sigma=15nm,B=2um,C=2.6", micro_alpha=0.1, ndf="ggx",
                             wavelengths_nm=(450.0, 550.0, 650.0), resolution=64)
    path = tmp_path_factory.mktemp("table") / "au.h5"
    D.run_table(D.TableSpec(case, thetas_deg=(0.0, 10.0, 20.0, 30.0, 40.0, 50.0), batch=3), path)
    return path, case


@pytest.mark.parametrize("theta", [20.0, 25.0, 32.5])
def test_open_table_evaluates_between_nodes_like_a_direct_evaluation(table_file, theta):
    """Issue 14: the mirror value and the energy at incidences between table nodes against a direct evaluation
    (grid model at that incidence): within 1 % and 2 % (measured: 0.07 % and 0.01 %)."""
    import waveoptics

    path, case = table_file
    T = waveoptics.open_table(path)
    grid = DirectionGrid.hemisphere(64)
    wi = _dir(theta)
    L = brdf.evaluate(wi, [550.0], case.material, case.micro(), T.nano, grid)
    i, j = np.unravel_index(np.argmax(L.total[0]), L.total[0].shape)
    assert float(T.eval(wi, grid.directions()[i, j], 550.0)) == pytest.approx(L.total[0, i, j], rel=0.01)
    assert float(T.albedo(wi, 550.0)) == pytest.approx(L.albedo()[0], rel=0.02)


def test_a_table_file_carries_the_rim_tables(table_file):
    """Format version 3: the file holds the rim tables (waveoptics.brdf.tabulated_rim), and the opened model reads
    them: beyond θ_o 69° at an incidence node its diffracted part is the facet-frame sum at that one direction
    (tests/facet_frame_helpers.py, a one-cell grid; float32 storage: measured 3e-8)."""
    import waveoptics
    from facet_frame_helpers import facet_frame_at
    from waveoptics import distributed as D
    from waveoptics.brdf.tabulated_rim import rim_directions
    from waveoptics.materials import get_material

    path, case = table_file
    assert D.read_table(path).attrs["format_version"] == 3
    T = waveoptics.open_table(path)
    assert T.rim_table is not None and T.rim_table.shape[:2] == (6, 3)
    wi = _dir(30.0)
    wo = rim_directions()[[2, 5, 8], [5, 40, 70]]   # θ_o 86°, 82°, 78°
    got = T.eval_parts(np.repeat(wi[None], 3, axis=0), wo, 550.0)["diffraction"]
    ref = [facet_frame_at(wi, c, 550.0, get_material(case.material), case.micro(), T.nano,
                          DirectionGrid.hemisphere(64)) for c in wo]
    np.testing.assert_allclose(got, ref, rtol=1e-6)


def test_cli_brdf_model_table(table_file, capsys):
    import json

    from waveoptics.cli import main as cli_main

    path, _ = table_file
    assert cli_main(["brdf", "--model", "table", "--table", str(path), "--incident", "25", "--outgoing", "25,180",
                     "--wavelengths", "450,650", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["values"]) == 2 and all(v["brdf"] > 0 for v in doc["values"])
    assert cli_main(["brdf", "--model", "table", "--table", str(path), "--incident", "25", "--outgoing", "25,180",
                     "--wavelengths", "500"]) == 2
    assert "500 nm is not in this table" in capsys.readouterr().err
