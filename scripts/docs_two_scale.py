"""Data of docs/two-scale.md (docs/data/two_scale.json; prose in docs/templates/two_scale.md): the model's limits
(measured), and figures made by running the main job."""
from __future__ import annotations

import shutil
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from waveoptics import brdf, scatter, surfaces
from waveoptics.scatter import tangent_blend
from waveoptics import compare, simulate
from waveoptics import materials
from waveoptics.brdf import twoscale
from waveoptics.scatter.grid import DirectionGrid
from waveoptics.units import direction_from_angles
from waveoptics import colour
from waveoptics.renderers import sphere as render

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"
sys.path.insert(0, str(ROOT / "scripts"))


def limits_table() -> dict:
    """σ_nano = 0 against the microfacet model, α_micro = 0 against the pure nano lobe, and the largest albedo
    excess over F on 20 random configurations."""
    grid = DirectionGrid.hemisphere(96)
    w = np.array([400.0, 550.0, 700.0])
    wi = direction_from_angles(30.0, 0.0)
    model = surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6)
    out = {}
    zero = twoscale.Nano(model=surfaces.PSDModel("abc", sigma=0.0, B=2e-6, C=2.6))
    L = twoscale.evaluate(wi, w, "Au", twoscale.Micro(alpha=0.2, ndf="ggx"), zero, grid)
    out["sigma0_max_abs"] = float(np.abs(L.total - L.microfacet).max())
    mat = materials.get_material("Al")
    L = twoscale.evaluate(wi, w, mat, twoscale.Micro(alpha=0.0, ndf="ggx"), twoscale.Nano(model=model), grid)
    wo = grid.directions()
    rho = brdf.albedo(wi, fresnel="one", alpha=brdf.ALPHA_MIN)
    nano = twoscale.Nano(model=model)

    def nano_lobe(lam):
        """The pure nano lobe the facets carry at α = 0: W F f_K + (1 − W) f_RR, W = w(θ_i) w(θ_o) of the hand-over
        to first order towards grazing angles (scatter.tangent_blend), F the unpolarized Fresnel factor."""
        cos_d = np.clip(np.linalg.norm(wi + wo, axis=-1) / 2, 0, 1)
        k = scatter.scattered_lobe(wi, wo, lam, model, F=mat.F(cos_d, lam))
        rr = scatter.rayleigh_rice_lobe(wi, wo, lam, model, mat, "unpolarized")
        W = tangent_blend.blend_weight(wi, wo)
        return np.where(grid.inside, W * k + (1 - W) * rr, 0) * rho

    err = max(np.abs(L.diffraction[i] - nano_lobe(lam)).max() / L.diffraction[i].max() for i, lam in enumerate(w))
    out["alpha0_max_rel"] = float(err)
    worst = -1.0
    rng = np.random.default_rng(0)
    for _ in range(20):
        th = rng.uniform(0, 80)
        m = surfaces.PSDModel("abc", sigma=rng.uniform(1, 60) * 1e-9, B=rng.uniform(0.5, 20) * 1e-6, C=rng.uniform(2.3, 4))
        name = rng.choice(["Au", "Ag", "Al", "Cu"])
        wi2 = direction_from_angles(th, 0.0)
        L = twoscale.evaluate(wi2, w, name, twoscale.Micro(alpha=rng.choice([0.0, 0.05, 0.2, 0.5]), ndf="ggx"),
                              twoscale.Nano(model=m), grid)
        worst = max(worst, float(np.max(L.albedo() - materials.get_material(name).F(wi2[2], w))))
    out["albedo_excess_max"] = worst
    return out


def guard_table() -> dict:
    """The coherent-loss guard's factor against incidence and micro roughness, on one height field and one PSD."""
    mat = materials.get_material("1+6j")
    grid = DirectionGrid.hemisphere(96)
    cases = (("height field, Gaussian σ = 24.6 nm, T = 1.65 µm",
              twoscale.Nano(surface=surfaces.gaussian(24.6e-9, 1.65e-6, 128 * 137.5e-9, 128, 0))),
             ("PSD, ABC σ = 40 nm, B = 3.7 µm, C = 2.2",
              twoscale.Nano(model=surfaces.PSDModel("abc", sigma=40e-9, B=3.7e-6, C=2.2))))
    thetas = (0.0, 40.0, 70.0, 80.0, 85.0)
    rows = []
    for label, nano in cases:
        for alpha in (0.0, 0.3):
            vals = []
            for t in thetas:
                L = twoscale.evaluate(direction_from_angles(t, 0.0), [550.0], mat, twoscale.Micro(alpha=alpha, ndf="ggx"), nano,
                                      grid, kd=0)
                vals.append(L.info["diffraction_energy_scale"][0])
            rows.append({"nano": label, "alpha": alpha, "factors": vals})
    return {"thetas": thetas, "rows": rows}


def band_table() -> list:
    """Per surface and λ at θ_i = 30°: σ, σ_rel, the share of σ² beyond the band, the light the full-σ exp(−g) would
    withhold from both halves, the share of the reflected light the band-limited lobe scatters (E), the share of it
    the multiple-order terms returned to the band, and the two-scale albedo over F (micro α = 0)."""
    cases = (("Al default", "Al", surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6)),
             ("Au, heavy tail", "Au", surfaces.PSDModel("abc", sigma=39e-9, B=3.7e-6, C=2.34)),
             ("Au, Gaussian", "Au", surfaces.PSDModel("gaussian", sigma=10e-9, T=1e-6)))
    rows = []
    s, c = 0.5, np.sqrt(0.75)
    grid = DirectionGrid.hemisphere(128)
    wi = direction_from_angles(30.0, 0.0)
    for name, mat_name, m in cases:
        mat = materials.get_material(mat_name)
        for lam in (380.0, 550.0, 700.0):
            rel = scatter.relevant_variance(m, lam, s)
            k2 = (4 * np.pi * c / (lam * 1e-9)) ** 2
            F = float(np.ravel(mat.F(np.array([c]), lam))[0])
            lost = F * (np.exp(-k2 * rel) - np.exp(-k2 * m.sigma ** 2))
            bs = scatter.band_series(m, lam)
            L = twoscale.evaluate(wi, [lam], mat, twoscale.Micro(alpha=0.0, ndf="ggx"), twoscale.Nano(model=m), grid, kd=0)
            rows.append({"surface": name, "kind": m.kind, "sigma_nm": m.sigma * 1e9, "wavelength_nm": lam,
                         "sigma_rel_nm": np.sqrt(rel) * 1e9, "beyond": scatter.beyond_band_fraction(m.sigma ** 2, rel),
                         "withheld": lost, "E": float(bs.scattered_albedo(30.0, material=mat)),
                         "returned": bs.redistributed_share(s, 2 * c), "albedo_over_F": L.albedo()[0] / F})
    return rows


#: the nano height fields of the energy tables: 128² samples over 17.6 µm, σ = 40 nm (λ/10 at 400 nm)
FIELDS = (("Gaussian T = 1.5 µm", lambda: surfaces.gaussian(40e-9, 1.5e-6, 128 * 137.5e-9, 128, 0)),
          ("exponential T = 1.5 µm", lambda: surfaces.exponential(40e-9, 1.5e-6, 128 * 137.5e-9, 128, 0)),
          ("ABC B = 3.7 µm, C = 2.2", lambda: surfaces.abc(3.7e-6, 2.2, 128 * 137.5e-9, 128, 0, sigma=40e-9)),
          ("ABC B = 3.7 µm, C = 4", lambda: surfaces.abc(3.7e-6, 4.0, 128 * 137.5e-9, 128, 0, sigma=40e-9)))


def field_table() -> list:
    """Per height field and λ at θ_i = 30°, micro α = 0: the share of σ² the grid holds (the generator keeps the PSD
    there and does not rescale), the field's rms height, σ² beyond the band, the share 1 − |χ̂|² the whole variance
    would take from the specular light, E_field (what the lobe scatters), and the albedo over F."""
    mat = materials.get_material("1+6j")
    grid = DirectionGrid.hemisphere(128)
    wi = direction_from_angles(30.0, 0.0)
    rows = []
    for name, make in FIELDS:
        hf = make()
        smp = scatter.samples(hf)
        for lam in (400.0, 550.0):
            var = float(np.var(hf.heights))
            rel = scatter.relevant_variance_of_field(hf, lam, 0.5)
            chi2 = abs(scatter.coherent_amplitude(smp, wi, lam)) ** 2
            nano = twoscale.Nano(surface=hf)
            E = 1 - nano.coherent_fraction(wi[2], lam, material=mat)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", scatter.DiffractionWarning)
                L = twoscale.evaluate(wi, [lam], mat, twoscale.Micro(alpha=0.0, ndf="ggx"), nano, grid, kd=0)
            F = float(mat.F(wi[2], lam))
            old = (L.albedo("diffraction")[0] + F * chi2) / F
            rows.append({"field": name, "wavelength_nm": lam, "resolved": hf.meta["psd_variance_fraction"],
                         "sigma_nm": np.sqrt(var) * 1e9, "beyond": scatter.beyond_band_fraction(var, rel),
                         "incoherent_chi": 1 - chi2, "E": E, "albedo_over_F": L.albedo()[0] / F, "before": old})
    return rows


def horizon_table() -> list:
    """Two-scale albedo against the microfacet albedo with micro roughness, and the light the facets' lobes lose to
    masking on the way out and below the horizon (θ_i = 0° and 40°, 450 nm, Beckmann micro NDF)."""
    mat = materials.get_material("1+6j")
    grid = DirectionGrid.hemisphere(128)
    cases = [("PSD ABC σ = 40 nm, B = 3.7 µm, C = 2.2",
              lambda: twoscale.Nano(model=surfaces.PSDModel("abc", sigma=40e-9, B=3.7e-6, C=2.2))),
             ("PSD Gaussian σ = 20 nm, T = 1.5 µm",
              lambda: twoscale.Nano(model=surfaces.PSDModel("gaussian", sigma=20e-9, T=1.5e-6)))]
    cases += [(f"field {name}", lambda make=make: twoscale.Nano(surface=make())) for name, make in FIELDS[::2]]
    rows = []
    for name, make in cases:
        nano = make()
        for alpha in (0.1, 0.3):
            for theta in (0.0, 40.0):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", scatter.DiffractionWarning)
                    L = twoscale.evaluate(direction_from_angles(theta, 0.0), [450.0], mat,
                                          twoscale.Micro(alpha=alpha, ndf="beckmann"), nano, grid, kd=0)
                mf = L.albedo("microfacet")[0]
                rows.append({"nano": name, "alpha": alpha, "theta_deg": theta, "excess": L.albedo()[0] / mf - 1,
                             "beyond_horizon": L.info["diffraction_beyond_horizon"][0] / mf})
    return rows


def default_case() -> dict:
    """``waveoptics simulate``'s default run: its parameters, time, albedos and sphere ΔE2000; the figures."""
    IMG.mkdir(parents=True, exist_ok=True)
    t = time.perf_counter()
    sim = simulate.simulate()
    t_sim = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as tmp:
        summary = simulate.write_outputs(sim, tmp, overwrite=True, sphere_size=256)
        for name in ("lobes.png", "brdf.png", "sphere_diff.png"):
            shutil.copy(Path(tmp) / name, IMG / f"two_scale_{name}")
    wave, mf, dE, mask = simulate.render_spheres(sim, 256)
    pos = colour.luminance(wave)[mask]
    exposure = min(0.18 / float(np.exp(np.mean(np.log(pos[pos > 1e-8])))), 4.0)
    render.plot_spheres([render.tonemap(wave, exposure), render.tonemap(mf, exposure)],
                        ["two-scale (diffraction)", "microfacet only"], IMG / "two_scale_spheres.png",
                        diff=np.where(mask, dE, np.nan), diff_title="ΔE2000",
                        light_deg=sim.params["incident_deg"], exposure=exposure)
    rows = compare.compare(sim, [0, 20, 40, 60, 80])
    compare.plot(rows, IMG / "two_scale_compare.png", title="Al, nano ABC σ=10 nm: two-scale vs microfacet")
    p = sim.params
    return {**{k: p[k] for k in ("material", "material_source", "nano", "ndf", "micro_alpha", "illuminant",
                                 "resolution")},
            "incident_deg": p["incident_deg"][0], "wavelengths": len(sim.wavelengths_nm),
            "wavelength_range_nm": [sim.wavelengths_nm[0], sim.wavelengths_nm[-1]], "seconds": t_sim,
            "rgb_albedo": np.round(summary["rgb_albedo"], 4), "microfacet_rgb_albedo":
            np.round(summary["microfacet_rgb_albedo"], 4),
            "delta_e2000": {k: summary["delta_e2000"][k] for k in ("mean", "max")}}


def compute() -> dict:
    """Every number of docs/two-scale.md (minutes). The facet-frame sweeps' rows are written by
    ``scripts/facet_frame_sweep.py [--narrow] --write`` (slow) and kept here from the committed data."""
    import docs_render

    old = docs_render.load_data("two_scale") if docs_render.data_path("two_scale").exists() else {}
    return {"limits": limits_table(), "guard": guard_table(), "band": band_table(), "field": field_table(),
            "horizon": horizon_table(), "default": default_case(),
            "facet_frame_sweep": old.get("facet_frame_sweep", []), "narrow_lobe_sweep": old.get("narrow_lobe_sweep", [])}


def main():
    import make_docs

    make_docs.main(["two_scale"])


if __name__ == "__main__":
    main()
