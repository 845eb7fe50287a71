"""Data of docs/validity.md (docs/data/validity.json; prose in docs/templates/validity.md): where the microfacet,
Kirchhoff, GHS and Rayleigh-Rice models agree with each other and with a rigorous solution (the Rayleigh-Fourier
method for sinusoidal gratings, waveoptics.scatter.rigorous), and what each loses beyond. Every number is computed
by this script."""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy import special

from waveoptics import brdf, scatter, surfaces
from waveoptics.materials import get_material
from waveoptics.materials.fresnel import F_facet_polarized
from waveoptics.scatter.grid import DirectionGrid
from waveoptics.scatter.rigorous import RAYLEIGH_HYPOTHESIS_KA, rayleigh_fourier

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
LAM = 550.0
AL = get_material("Al")
EPS = complex(AL.eta(LAM)) ** 2
TOL = 0.05

A_OVER_LAM = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2)
D_OVER_LAM = (1.6, 3.2, 6.4, 12.8, 25.6)   # off the Rayleigh anomalies of these incidences
THETAS = (0.0, 30.0, 60.0, 80.0)


def _dir(theta_deg, sign=1.0):
    t = math.radians(theta_deg)
    return np.array([sign * math.sin(t), 0.0, math.cos(t)])


def rigorous(a, d, theta, eps=EPS, pol="unpolarized"):
    """Reflected efficiencies {order: η} of the Rayleigh-Fourier solution for s, p or unpolarized light."""
    pols = ("s", "p") if pol == "unpolarized" else (pol,)
    sols = [rayleigh_fourier(LAM, d, a, theta, eps, q) for q in pols]
    eff = np.mean([r.reflected for r in sols], axis=0)
    return {int(m): float(x) for m, x in zip(sols[0].orders, eff) if x > 0}


def order_direction(m, d, theta):
    """(ω_i, ω_o) of order m in the convention of waveoptics (ω_i towards the light at +x, the mirror at −x)."""
    si = math.sin(math.radians(theta)) + m * LAM * 1e-9 / d
    if abs(si) >= 1:
        return None
    return _dir(theta), np.array([-si, 0.0, math.sqrt(1 - si * si)])


def facet_F(eps=EPS, pol="unpolarized"):
    """Reflectance of the facet that sends ω_i into ω_o (the half vector's), for s, p or unpolarized light."""
    eta = np.sqrt(complex(eps))
    return lambda wi, wo: float(F_facet_polarized(wi, wo, eta, pol))


def scalar(model, a, d, theta, F=None):
    """Efficiencies of a scalar model: F(θ_d) K λ² J_m²(v_z a) for the Kirchhoff-family *model* (the |U|² of a
    sinusoid is J_m² per order, docs/physics.md §5), with the factor K of waveoptics.scatter and the facet
    reflectance *F* (:func:`facet_F`; aluminium, unpolarized by default)."""
    F = F or facet_F()
    dm = scatter.get_model(model)
    k = 2 * math.pi / (LAM * 1e-9)
    out = {}
    for m in range(-60, 61):
        dirs = order_direction(m, d, theta)
        if dirs is None:
            continue
        wi, wo = dirs
        K = float(dm.K(wi, wo, LAM)) * (LAM * 1e-9) ** 2
        vz = k * float(dm.cos_sum(wi, wo))
        out[m] = F(wi, wo) * K * special.jv(m, vz * a) ** 2
    return out


def rayleigh_rice(a, d, theta, eps=EPS, pol="unpolarized"):
    """First-order (Rayleigh-Rice) efficiencies of a sinusoid: η_±1 = (2πa/λ)² cosθ_i cosθ_±1 Q (its PSD is
    (a²/4) δ(f ∓ 1/d) per side, and du dv = λ² df), the specular order the rest of R(θ_i)."""
    out = {}
    for m in (-1, 1):
        dirs = order_direction(m, d, theta)
        if dirs is not None:
            wi, wo = dirs
            out[m] = (2 * math.pi * a / (LAM * 1e-9)) ** 2 * wi[2] * wo[2] * float(scatter.Q(wi, wo, eps, pol))
    wi = _dir(theta)
    out[0] = facet_F(eps, pol)(wi, wi * np.array([-1.0, -1.0, 1.0])) - sum(out.values())
    return out


def error(model_eff, rig, specular: bool = True):
    """Σ |η_m − η_m^rig| / Σ_{m≠0} η_m^rig: the models' error relative to the diffracted light (over the diffracted
    orders only without *specular*)."""
    orders = (set(model_eff) | set(rig)) - (set() if specular else {0})
    diffracted = sum(v for m, v in rig.items() if m != 0)
    return sum(abs(model_eff.get(m, 0.0) - rig.get(m, 0.0)) for m in orders) / max(diffracted, 1e-300)


def _errors(a, d, theta):
    """Kirchhoff, GHS and Rayleigh-Rice errors against the rigorous solution (unpolarized, aluminium)."""
    rig = rigorous(a, d, theta)
    return [error(scalar("kirchhoff", a, d, theta), rig), error(scalar("ghs", a, d, theta), rig),
            error(rayleigh_rice(a, d, theta), rig)]


def grating_tables() -> list:
    """Per incidence, per a/λ: the three errors at each d/λ (None where K a is beyond the Rayleigh hypothesis)."""
    out = []
    for theta in THETAS:
        rows = []
        for a_l in A_OVER_LAM:
            cells = []
            for d_l in D_OVER_LAM:
                a, d = a_l * LAM * 1e-9, d_l * LAM * 1e-9
                cells.append(None if 2 * math.pi * a / d > RAYLEIGH_HYPOTHESIS_KA else _errors(a, d, theta))
            rows.append({"a_over_lam": a_l, "cells": cells})
        out.append({"theta_deg": theta, "rows": rows})
    return out


#: gratings of the polarization and dielectric maps: (a/λ, d/λ)
POL_GRATINGS = ((0.01, 3.2), (0.01, 12.8), (0.05, 3.2), (0.05, 12.8), (0.1, 12.8))
POL_THETAS = (0.0, 30.0, 60.0)
GLASS_EPS = 1.5 ** 2


def polarization_tables() -> dict:
    """Kirchhoff · Rayleigh-Rice errors against the rigorous solution for s and p light, on aluminium and on glass
    (n = 1.5), per grating and incidence; and the extremes the text quotes."""
    out = []
    quoted = {"rr_shallow": 0.0, "glass_p60": [], "glass_s60": []}
    for name, eps in (("aluminium", EPS), ("glass n = 1.5", GLASS_EPS)):
        rows = []
        for a_l, d_l in POL_GRATINGS:
            a, d = a_l * LAM * 1e-9, d_l * LAM * 1e-9
            cells = []
            for pol in ("s", "p"):
                for t in POL_THETAS:
                    rig = rigorous(a, d, t, eps, pol)
                    errs = [error(scalar("kirchhoff", a, d, t, facet_F(eps, pol)), rig, specular=False),
                            error(rayleigh_rice(a, d, t, eps, pol), rig, specular=False)]
                    cells.append(errs)
                    if a_l <= 0.01:
                        quoted["rr_shallow"] = max(quoted["rr_shallow"], errs[1])
                    if eps == GLASS_EPS and t == 60.0:
                        quoted[f"glass_{pol}60"].append(errs[0])
            rows.append({"a_over_lam": a_l, "d_over_lam": d_l, "cells": cells})
        out.append({"name": name, "rows": rows})
    return {"columns": [[pol, t] for pol in ("s", "p") for t in POL_THETAS], "tables": out,
            "rr_shallow_max": quoted["rr_shallow"],
            "glass_s60": [min(quoted["glass_s60"]), max(quoted["glass_s60"])],
            "glass_p60": [min(quoted["glass_p60"]), max(quoted["glass_p60"])]}


def issue_example() -> dict:
    """The grating the issue names: period 2 µm, amplitude 100 nm, at 550 nm."""
    a, d = 100e-9, 2e-6
    return {"d_over_lam": d / (LAM * 1e-9), "a_over_lam": a / (LAM * 1e-9), "Ka": 2 * math.pi * a / d,
            "errors": [{"theta_deg": theta, "errors": _errors(a, d, theta)} for theta in THETAS]}


def reference_checks():
    c = math.cos(math.radians(35.0))
    s = math.sin(math.radians(35.0))
    g = np.sqrt(EPS - s * s)
    rs = abs((c - g) / (c + g)) ** 2
    flat = abs(rayleigh_fourier(LAM, 2e-6, 0.0, 35.0, EPS, "s").order(0) / rs - 1)
    glass = rayleigh_fourier(633.0, 2e-6, 100e-9, 30.0, 2.25, "p")
    energy = abs(np.sum(glass.reflected) + np.sum(glass.transmitted) - 1)
    r = rayleigh_fourier(LAM, 2e-6, 80e-9, 20.0, EPS, "s")
    th = r.theta_deg[list(r.orders).index(-1)]
    back = rayleigh_fourier(LAM, 2e-6, 80e-9, abs(th), EPS, "s")
    recip = abs(back.order(1 if th >= 0 else -1) / r.order(-1) - 1)
    return {"flat_fresnel": flat, "energy": energy, "reciprocity": recip}


def random_surface_table() -> dict:
    """E (share of F scattered) of the band-limited Kirchhoff lobe and of Rayleigh-Rice, Gaussian PSDs on Al."""
    sig = (0.005, 0.01, 0.02, 0.05, 0.1)
    Ts = (1.0, 2.0, 5.0, 10.0)
    thetas = (0.0, 30.0, 60.0, 80.0, 85.0)
    rows = []
    for s_l in sig:
        for T_l in Ts:
            model = surfaces.PSDModel("gaussian", sigma=s_l * LAM * 1e-9, T=T_l * LAM * 1e-9)
            series = scatter.band_series(model, LAM)
            rows.append({"sigma_over_lam": s_l, "T_over_lam": T_l, "cells": [
                [float(series.scattered_albedo(t, "kirchhoff", AL)),
                 float(scatter.rayleigh_rice_albedo(t, LAM, model, AL))] for t in thetas]})
    ratio = {t: [r["cells"][i][0] / r["cells"][i][1] for r in rows] for i, t in enumerate(thetas)}
    tis_over = [[s_l, max(r["cells"][0][1] / r["cells"][0][0] for r in rows if r["sigma_over_lam"] == s_l)]
                for s_l in (0.05, 0.1)]
    return {"thetas": list(thetas), "rows": rows, "rr_over_kirchhoff_at_0": tis_over,
            "kirchhoff_over_rr_at_80": [min(ratio[80.0]), max(ratio[80.0])],
            "kirchhoff_over_rr_at_85_max": max(ratio[85.0])}


def microfacet_table():
    """Relative L1 distance between the Kirchhoff lobe of a Gaussian surface (coherent part in the mirror cell +
    the classical series, F = 1) and the Beckmann microfacet lobe of α = 2σ/T (F = 1), θ_i = 30°, 128² cells."""
    grid = DirectionGrid.hemisphere(128)
    wo = grid.directions()
    wi = _dir(30.0)
    cell = np.unravel_index(np.argmin(np.sum((wo - np.array([-wi[0], 0, wi[2]])) ** 2, axis=-1)), wo.shape[:2])
    sig = (0.02, 0.05, 0.1, 0.2, 0.4)
    Ts = (2.0, 5.0, 10.0, 20.0)
    rows = []
    for s_l in sig:
        cells = []
        for T_l in Ts:
            sigma, T = s_l * LAM * 1e-9, T_l * LAM * 1e-9
            model = surfaces.PSDModel("gaussian", sigma=sigma, T=T)
            try:
                kl = scatter.scattered_lobe(wi[None, None, :], wo, LAM, model, 1.0, band_limited=False)
            except Exception as exc:          # the series refuses g beyond its range
                cells.append(type(exc).__name__)
                continue
            kl = np.where(grid.inside, kl, 0.0)
            g = (4 * math.pi * sigma * wi[2] / (LAM * 1e-9)) ** 2
            kl[cell] += math.exp(-g) / (grid.du * grid.dv)
            mf = np.where(grid.inside, brdf.specular(wi[None, None, :], wo, alpha=2 * sigma / T, ndf="beckmann",
                                                     shadowing="smith-correlated", fresnel="one"), 0.0)
            d = float(np.sum(np.abs(kl - mf))) / float(np.sum(kl))
            cells.append(d)
        rows.append({"sigma_over_lam": s_l, "cells": cells})
    return {"T_over_lam": list(Ts), "rows": rows}


def compute() -> dict:
    """Every number of docs/validity.md."""
    t0 = time.perf_counter()
    out = {"tolerance": TOL, "wavelength_nm": LAM, "rayleigh_hypothesis_Ka": RAYLEIGH_HYPOTHESIS_KA,
           "checks": reference_checks(), "d_over_lam": list(D_OVER_LAM), "gratings": grating_tables(),
           "example": issue_example(), "random": random_surface_table(), "microfacet": microfacet_table(),
           "polarization": polarization_tables()}
    out["seconds"] = time.perf_counter() - t0
    return out


def main() -> None:
    import make_docs

    make_docs.main(["validity"])


if __name__ == "__main__":
    main()
