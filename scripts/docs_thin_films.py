"""Data of docs/thin-films.md (docs/data/thin_films.json; prose, grammar and method in docs/templates/thin_films.md):
tables of R against angle and wavelength for oxide films on aluminium computed from the code, the closed-form
checks, and the colour error of the wavelength grids against 1 nm sampling (the planner's nodes per fringe). Runs
in a few seconds."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

ANGLES = (0.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0)
LAMBDAS = (400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0)
AL_FILMS = ("Al", "Al|Al2O3:5nm", "Al|Al2O3:20nm", "Al|Al2O3:120nm", "Al|Al2O3:300nm", "Al|Al2O3:500nm")
ALIAS_FILMS = ("Al|Al2O3:120nm", "Al|Al2O3:500nm", "Si|SiO2:120nm", "Si|SiO2:500nm", "Ti|TiO2:120nm",
               "Ti|TiO2:500nm", "BK7|TiO2:500nm", "Si|SiO2:1um", "Si|SiO2:2um")
STEPS = (20.0, 10.0, 5.0, 2.0)


def r_vs_angle(get_material) -> dict:
    """F(θ) at 550 nm per stack (rows: spec, values at ANGLES) and R_s, R_p at every second angle."""
    c = np.cos(np.radians(ANGLES))
    F, sp = [], []
    for spec in AL_FILMS:
        m = get_material(spec)
        F.append({"spec": spec, "F": np.asarray(m.F(c, 550.0))})
        Rs, Rp = m.F_sp(c[1::2], 550.0)
        sp.append({"spec": spec, "Rs": Rs, "Rp": Rp})
    return {"angles": ANGLES, "sp_angles": ANGLES[1::2], "F": F, "sp": sp}


def r_vs_wavelength(get_material) -> dict:
    w = np.array(LAMBDAS)
    return {"wavelengths": LAMBDAS,
            "rows": [{"spec": spec, "F0": np.asarray(get_material(spec).F0(w))} for spec in AL_FILMS]}


def checks() -> dict:
    """The closed-form checks: quarter-wave AR coating, Bragg mirrors, R + T of a lossless stack."""
    from waveoptics.materials import stack

    n_s, lam0 = 1.52, 550.0
    n_f = math.sqrt(n_s)
    out = {"ar": float(stack.R(1.0, lam0, n_s, [n_f], [lam0 / (4 * n_f)])), "bragg": []}
    n0, nL, nH, lam0 = 1.0, 1.38, 2.35, 600.0
    for N in (1, 2, 4, 8):
        films = [nL, nH] * N
        R = float(stack.R(1.0, lam0, n_s, films, [lam0 / (4 * n) for n in films]))
        a, b = n0 * nL ** (2 * N), n_s * nH ** (2 * N)
        out["bragg"].append({"N": N, "closed": ((a - b) / (a + b)) ** 2, "computed": R})
    lam = np.linspace(380, 780, 41)[:, None]
    c = np.cos(np.radians(np.linspace(0, 89, 90)))
    films, d = [2.3, 1.38, 2.3], [60.0, 400.0, 75.0]
    out["energy"] = max(float(np.max(np.abs(stack.R(c, lam, 1.52, films, d, p) + stack.T(c, lam, 1.52, films, d, p)
                                            - 1))) for p in ("s", "p"))
    return out


def _dE(material, grid, ref_XYZ, xy):
    import colour as cs
    from waveoptics import colour

    XYZ = colour.reflectance_to_XYZ(material.F0(grid), grid, "D65")
    return float(cs.delta_E(cs.XYZ_to_Lab(XYZ, xy), cs.XYZ_to_Lab(ref_XYZ, xy), method="CIE 2000"))


def aliasing(get_material) -> dict:
    """Fringe spacing, the planner's step and ΔE2000 of F0's colour at each step against 1 nm sampling."""
    import colour as cs
    from waveoptics import colour
    from waveoptics.planning import FILM_NODES_PER_FRINGE
    from waveoptics.planning.effects import film_step

    cmfs, d65 = cs.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"], cs.SDS_ILLUMINANTS["D65"]
    w1 = np.arange(360.0, 831.0)
    white = cs.sd_to_XYZ(cs.SpectralDistribution(dict(zip(w1, np.ones_like(w1)))), cmfs, d65, method="Integration")
    xy = cs.XYZ_to_xy(white / 100)
    grids = {s: colour.spectral_grid("D65", s) for s in STEPS}
    rows = []
    for spec in ALIAS_FILMS:
        m = get_material(spec)
        ref = cs.sd_to_XYZ(cs.SpectralDistribution(dict(zip(w1, m.F0(w1)))), cmfs, d65, method="Integration") / 100
        film = film_step(SimpleNamespace(mat=m, w_colour=grids[20.0]))
        step = 20.0 if film is None or film[0] is None else film[0]
        grid = grids[step] if step in grids else colour.spectral_grid("D65", step)
        rows.append({"spec": spec, "fringe_nm": float(np.min(m.fringe_spacing_nm(np.array([380.0])))), "step_nm": step,
                     "dE_planner": _dE(m, grid, ref, xy), "dE": [_dE(m, grids[s], ref, xy) for s in STEPS]})
    return {"nodes_per_fringe": FILM_NODES_PER_FRINGE, "steps": STEPS, "rows": rows}


def compute() -> dict:
    """Every number of docs/thin-films.md."""
    from waveoptics.materials import get_material

    return {"angle": r_vs_angle(get_material), "wavelength": r_vs_wavelength(get_material), "checks": checks(),
            "aliasing": aliasing(get_material)}


def main():
    import make_docs

    make_docs.main(["thin_films"])


if __name__ == "__main__":
    main()
