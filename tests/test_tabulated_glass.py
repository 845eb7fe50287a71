"""A rough glass's BSDF tabulated over the sphere (``waveoptics.brdf.tabulated_glass``, ``waveoptics table
--transmission``; issue 33: "tables" in transmission).

References that are not the code under test:

* the light of the cells, Σ f du dv over each exit hemisphere, against the model's own R and T by its quadrature
  over facet normals (``albedo_parts``: Walter's integral mapped from facet normals, not the eval on exit cells),
  and against energy conservation (a lossless glass with multiple scattering: R + T = 1);
* the cells against a Monte-Carlo estimate written here from the model's *sampler*: each sample's weight
  f |cos θ_o| / pdf deposited in the cell of its exit estimates ∫_cell f |cos θ_o| dω = ∫_cell f du dv (a different
  algorithm: importance sampling, not sub-cell sums of eval);
* the read between incidence nodes against the model's R and T at that incidence (its quadrature);
* the table's sampler against its pdf by Pearson's χ² (``waveoptics.brdf.chi2_test``).
"""
from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

from cli_helpers import run_cli
from waveoptics import brdf, distributed, surfaces
from waveoptics.brdf import tabulated_glass as tg
from waveoptics.scatter.grid import DirectionGrid

PSD = surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6)
LAM = 550.0


def _glass(alpha, **kw):
    return brdf.nano_rough_glass("BK7", brdf.Micro(alpha=alpha), PSD, **kw)


def _model_rt(model, side, theta):
    parts = model.albedo_parts(tg.incident_direction(side, theta), LAM)
    return [float(sum(v for k, v in parts.items() if k.endswith(h))) for h in tg.GLASS_HEMISPHERES]


@pytest.mark.parametrize("alpha", [0.01, 0.1, 0.5])
def test_cells_hold_the_model_light(alpha):
    """Σ cells du dv = the model's R and T (its facet-normal quadrature) within 3e-3 of the incident light, from
    the air (0-80°) and from inside (below and beyond the critical angle), however narrow the lobe; a midpoint
    per cell misses the narrow lobe's light by far more."""
    model, g = _glass(alpha), DirectionGrid.hemisphere(32)
    for side, theta in (("air", 0), ("air", 45), ("air", 80), ("dielectric", 20), ("dielectric", 60)):
        cells = tg.glass_cells(model, side, theta, [LAM], g, PSD)
        got = [tg.cells_light(cells[h][0], g) for h in tg.GLASS_HEMISPHERES]
        want = _model_rt(model, side, theta)
        assert np.allclose(got, want, rtol=0, atol=3e-3), (side, theta, got, want)
    if alpha == 0.01:   # the sub-cells matter: one midpoint per cell
        wi = tg.incident_direction("air", 0)
        coarse = tg.cell_averages(lambda wo: model.eval(wi, wo, LAM)[:, None], g, True, np.ones((32, 32), int), 1)
        assert abs(tg.cells_light(coarse[0], g) - _model_rt(model, "air", 0)[1]) > 0.05


@pytest.mark.parametrize("side,theta", [("air", 30.0), ("dielectric", 50.0)])
def test_cells_against_the_sampler(side, theta):
    """Each cell's light against a Monte-Carlo estimate from the model's sampler (weights binned by exit cell):
    within 4 standard errors (+ 1e-4) on every cell, light from the air and from inside beyond the critical
    angle."""
    model, g = _glass(0.1), DirectionGrid.hemisphere(16)
    wi = tg.incident_direction(side, theta)
    cells = tg.glass_cells(model, side, theta, [LAM], g, PSD)
    n = 400_000
    s = model.sample(wi, LAM, np.random.default_rng(7).random((n, 2)))
    ok = s.pdf > 0
    wo, w = s.wo[ok], s.weight[ok]
    iu = np.clip(((wo[:, 0] + 1) / g.du).astype(int), 0, g.n_u - 1)
    iv = np.clip(((wo[:, 1] + 1) / g.dv).astype(int), 0, g.n_v - 1)
    for h in tg.GLASS_HEMISPHERES:
        sel = (wo[:, 2] * wi[2] > 0) == (h == "reflection")
        flat = iv[sel] * g.n_u + iu[sel]
        mean = np.bincount(flat, weights=w[sel], minlength=g.n_u * g.n_v) / n
        second = np.bincount(flat, weights=w[sel] ** 2, minlength=g.n_u * g.n_v) / n
        se = np.sqrt(np.maximum(second - mean ** 2, 0.0) / n)
        table = (cells[h][0] * tg.disc_fraction(g)).ravel() * g.du * g.dv
        assert np.all(np.abs(table - mean) <= 4 * se + 1e-4), (h, np.max(np.abs(table - mean) - 4 * se))


def test_read_between_nodes_keeps_the_light():
    """Between refined nodes the read's R and T (integrated on a fine grid) are those of the model at that
    incidence within 5e-3 of the incident light, from inside across the critical angle where R(θ) bends sharply
    (the nodes 5° apart that the refinement started from read R 0.015 off there); ``albedo`` is that integral."""
    model, g = _glass(0.1), DirectionGrid.hemisphere(32)
    fine = DirectionGrid.hemisphere(256)
    d = fine.directions().reshape(-1, 3)
    d = d[d[:, 2] > 0]

    def light(table, theta):
        wi = tg.incident_direction("dielectric", theta)
        return [table.eval(wi, d * [1, 1, -1 if h == "reflection" else 1], LAM).sum() * fine.du * fine.dv
                for h in tg.GLASS_HEMISPHERES]

    coarse = tg.tabulate_glass(model, (30.0, 35.0), [LAM], g, PSD)
    assert abs(light(coarse, 32.5)[0] - _model_rt(model, "dielectric", 32.5)[0]) > 0.015
    nodes = tg.refined_incidence_nodes(model, (30.0, 35.0), [LAM], g, PSD)
    assert len(nodes) > 2
    table = tg.tabulate_glass(model, nodes, [LAM], g, PSD)
    for a, b in zip(nodes[:-1], nodes[1:]):
        m = 0.5 * (a + b)
        want = _model_rt(model, "dielectric", m)
        assert np.allclose(light(table, m), want, rtol=0, atol=5e-3), m
        got = table.albedo_parts(tg.incident_direction("dielectric", m), LAM)
        assert np.allclose([got[h] for h in tg.GLASS_HEMISPHERES], light(table, m), rtol=0, atol=2e-3), m


def test_eval_reciprocal():
    """``eval_reciprocal``: f(ω_i, ω_o)/η_o² = f(ω_o, ω_i)/η_i² to rounding, on and between nodes, reflected and
    transmitted, light from either side (``eval``, the read, is not: its cells lie at different nodes)."""
    model, g = _glass(0.3), DirectionGrid.hemisphere(16)
    table = tg.tabulate_glass(model, (0.0, 20.0, 40.0, 60.0, 80.0), [LAM], g, PSD)
    rng = np.random.default_rng(11)
    d = rng.normal(size=(2, 2000, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    wi, wo = d
    eta = table.eta[0]
    n_i, n_o = np.where(wi[:, 2] > 0, 1.0, eta), np.where(wo[:, 2] > 0, 1.0, eta)
    a, b = table.eval_reciprocal(wi, wo, LAM) / n_o ** 2, table.eval_reciprocal(wo, wi, LAM) / n_i ** 2
    assert np.count_nonzero(a) > 500
    assert np.allclose(a, b, rtol=1e-12, atol=0)
    ra, rb = table.eval(wi, wo, LAM) / n_o ** 2, table.eval(wo, wi, LAM) / n_i ** 2
    assert not np.allclose(ra, rb, rtol=1e-2, atol=0)


@pytest.mark.parametrize("side,theta", [("air", 37.5), ("dielectric", 42.0), ("dielectric", 60.0)])
def test_sampler_chi2(side, theta):
    """The table's sampler against its pdf (between nodes; across the critical angle from inside)."""
    model, g = _glass(0.3), DirectionGrid.hemisphere(32)
    table = tg.tabulate_glass(model, (35.0, 40.0, 45.0, 55.0, 65.0), [LAM], g, PSD)
    wi = tg.incident_direction(side, theta)
    res = brdf.chi2_test(lambda u: table.sample(wi, LAM, u).wo, lambda x: table.pdf(wi, x, LAM),
                         sample_count=100_000, res=31, ires=16)
    assert res.passed, res.message
    w = table.sample(wi, LAM, np.random.default_rng(3).random((20_000, 2))).weight
    assert abs(w.mean() - table.albedo(wi, LAM)) < 0.02


def test_white_furnace_of_the_cells():
    """A lossless rough glass with its multiple scattering (α 1, GGX): the cells' R + T within 1e-2 of 1 from
    both sides (energy conservation)."""
    model = brdf.RoughDielectricBSDF("1.5", brdf.Micro(alpha=1.0, ndf="ggx"), multiple_scattering=True)
    g = DirectionGrid.hemisphere(32)
    for side, theta in (("air", 0), ("air", 60), ("dielectric", 30), ("dielectric", 70)):
        cells = tg.glass_cells(model, side, theta, [LAM], g)
        total = sum(tg.cells_light(cells[h][0], g) for h in tg.GLASS_HEMISPHERES)
        assert abs(total - 1.0) < 1e-2, (side, theta, total)


def test_cli_table_transmission(tmp_path):
    """``table --transmission`` writes both sides and hemispheres; ``open_table`` reads them back as a BSDF whose
    read on a node is the file's cell; the cells' light beside the model's; refusals name the option."""
    out = tmp_path / "glass.h5"
    code, text, err, _ = run_cli(["table", "--transmission", "--exact-angles", "--material", "BK7", "--nano",
                                  "abc:sigma=10nm,B=2um,C=2.6", "--micro-alpha", "0.3", "--wavelengths", "550",
                                  "--resolution", "16", "--incident-angles", "0,40,80", "-o", str(out)])
    assert code == 0, err
    with h5py.File(out) as f:
        assert f["reflection"].shape == (2, 3, 1, 16, 16)
        assert np.allclose(f["albedo_reflection"][()] + f["albedo_transmission"][()],
                           f["model_albedo_reflection"][()] + f["model_albedo_transmission"][()], atol=5e-3)
        cell = f["transmission"][1, 1, 0]
    table = distributed.open_table(out)
    assert isinstance(table, brdf.TabulatedGlassBSDF)
    g = table.grid
    iv, iu = np.unravel_index(np.argmax(cell), cell.shape)
    u, v = g.u[iu], g.v[iv]
    wo = np.array([u, v, math.sqrt(1 - u * u - v * v)])   # light from inside at 40°: transmitted upwards
    assert table.eval(tg.incident_direction("dielectric", 40.0), wo, LAM) == pytest.approx(cell[iv, iu], rel=1e-6)
    code, text, err, _ = run_cli(["brdf", "--model", "table", "--table", str(out), "--incident", "140",
                                  "--wavelengths", "550", "--albedo"])     # light from inside at the node 40°
    assert code == 0, err
    want = table.albedo_parts(tg.incident_direction("dielectric", 40.0), LAM)
    r, t = (float(x.split("=")[1]) for x in text.split()[-2:])
    assert (r, t) == pytest.approx((float(want["reflection"]), float(want["transmission"])), abs=2e-6)
    with h5py.File(out) as f:   # on a node the read's light is the cells'
        assert (r, t) == pytest.approx((f["albedo_reflection"][1, 1, 0], f["albedo_transmission"][1, 1, 0]), abs=2e-3)
    for argv, flag in ((["--material", "Al", "--transmission"], "material"), (["--exact-angles"], "--transmission"),
                       (["--multiple-scattering"], "--transmission")):
        code, _, err, _ = run_cli(["table", "--nano", "abc:sigma=10nm,B=2um,C=2.6", "--wavelengths", "550",
                                   "--resolution", "16", "-o", str(tmp_path / "x.h5"), *argv])
        assert code == 2 and flag in err and "Traceback" not in err


def test_a_lobe_between_sub_points_is_refused():
    """A micro lobe narrower than two of the finest sub-cells (α 0.001 on 32² cells: the transmitted lobe 2.4e-4
    wide would fall between sub-points and its light, 96 % of the incident light, be lost) is refused naming
    micro_alpha and resolution; α 0.002 on 128² holds R + T = 1 within 1e-4 (lossless, the model's own quadrature
    says 1 too)."""
    from waveoptics.errors import FieldError

    psd = surfaces.PSDModel("gaussian", sigma=5e-9, T=1e-6)
    with pytest.raises(FieldError) as e:
        tg.glass_cells(brdf.nano_rough_glass("BK7", brdf.Micro(alpha=0.001), psd), "air", 0.0, [LAM],
                       DirectionGrid.hemisphere(32), psd)
    assert {"micro_alpha", "resolution"} <= set(e.value.fields)
    g = DirectionGrid.hemisphere(128)
    cells = tg.glass_cells(brdf.nano_rough_glass("BK7", brdf.Micro(alpha=0.002), psd), "air", 0.0, [LAM], g, psd)
    assert sum(tg.cells_light(cells[h][0], g) for h in tg.GLASS_HEMISPHERES) == pytest.approx(1.0, abs=1e-4)
