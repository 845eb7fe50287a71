"""Where is geometric optics good enough? The two-scale model against the plain microfacet model over θ_i.

For each incidence angle :func:`compare` reports, for both models: the directional albedo (luminance Y under the
illuminant), the angular width (FWHM) of the lobe in the plane of incidence, the energy in the tail beyond a given
angle from the mirror direction, the ΔE2000 between the albedo colours, and the mean/max ΔE2000 between sphere
renders lit from that angle. Sphere renders reuse one lobe table over θ_i, so the sweep costs one
:func:`waveoptics.simulate.simulate` plus one lobe evaluation per angle.
"""
from __future__ import annotations

import math

import numpy as np

from . import colour, render
from .brdf import twoscale
from .io import figures
from .io.figures import save_figure
from .scatter.grid import integrate
from .units import direction_from_angles

__all__ = ['lobe_fwhm_deg', 'compare', 'plot', 'table_text']



def _angle_from_mirror(grid, wi):
    """Angle (deg) between each grid direction and the mirror direction of *wi*."""
    m = np.array([-wi[0], -wi[1], wi[2]])
    d = grid.directions()
    return np.degrees(np.arccos(np.clip(d @ m, -1.0, 1.0)))


def lobe_fwhm_deg(f_lum, grid, wi) -> float:
    """Full width at half maximum (deg) of a luminance lobe, measured as the angular extent of the cells above half
    the peak around the mirror direction (2 × the largest angle from the mirror among them), ≥ the cell size."""
    if not np.any(f_lum > 0):
        return 0.0
    ang = _angle_from_mirror(grid, wi)
    half = f_lum >= 0.5 * f_lum.max()
    cell = math.degrees(grid.du)
    return float(max(2 * ang[half & grid.inside].max(), cell)) if np.any(half & grid.inside) else cell


def compare(sim, angles_deg, *, tail_deg=10.0, sphere_size=128):
    """Compare both models of a :class:`waveoptics.simulate.Simulation` over incidence angles (degrees).

    Returns
    -------
    list of dict
        One row per angle with keys ``theta_i_deg``, ``albedo_Y_wave``, ``albedo_Y_microfacet``,
        ``fwhm_deg_wave``, ``fwhm_deg_microfacet``, ``tail_fraction_wave``, ``tail_fraction_microfacet``
        (share of the albedo farther than *tail_deg* from the mirror direction), ``delta_e2000_albedo``,
        ``delta_e2000_sphere_mean``, ``delta_e2000_sphere_max``.
    """

    grid = sim.grid
    w = sim.wavelengths_nm
    rows = []
    thetas = np.radians(sim.table_thetas_deg)
    for th in angles_deg:
        wi = direction_from_angles(th, 0.0)
        i = int(np.argmin(np.abs(sim.table_thetas_deg - th)))
        if abs(sim.table_thetas_deg[i] - th) < 1e-9:
            tot, mf = sim.table_total[i], sim.table_microfacet[i]
        else:
            L = _lobes_at(sim, wi)
            tot, mf = L.total, L.microfacet
        out = {"theta_i_deg": float(th)}
        ang = _angle_from_mirror(grid, wi)
        rgbs = {}
        for name, f in (("wave", tot), ("microfacet", mf)):
            rgb_lobe = colour.reflectance_to_rgb(np.moveaxis(f, 0, -1), w, sim.illuminant)
            lum = colour.luminance(rgb_lobe)
            alb = colour.reflectance_to_rgb(integrate(f, grid), w, sim.illuminant)
            rgbs[name] = alb
            total = float(np.sum(np.where(grid.inside, lum, 0))) * grid.du * grid.dv
            tail = float(np.sum(np.where(grid.inside & (ang > tail_deg), lum, 0))) * grid.du * grid.dv
            out[f"albedo_Y_{name}"] = float(colour.luminance(alb))
            out[f"fwhm_deg_{name}"] = lobe_fwhm_deg(lum, grid, wi)
            out[f"tail_fraction_{name}"] = tail / total if total > 0 else 0.0
        out["delta_e2000_albedo"] = float(colour.delta_e2000(rgbs["wave"], rgbs["microfacet"]))
        light = direction_from_angles(th, 0.0)
        wave, m1 = render.render_sphere(sim.table_total, thetas, grid, w, light, size=sphere_size,
                                        illuminant=sim.illuminant)
        mfr, _ = render.render_sphere(sim.table_microfacet, thetas, grid, w, light, size=sphere_size,
                                      illuminant=sim.illuminant)
        dE = colour.delta_e2000(wave[m1], mfr[m1]) if m1.any() else np.zeros(1)
        out["delta_e2000_sphere_mean"] = float(np.mean(dE))
        out["delta_e2000_sphere_max"] = float(np.max(dE))
        rows.append(out)
    return rows


def _lobes_at(sim, wi):
    p = sim.params
    micro = twoscale.Micro(alpha=p["micro_alpha"], ndf=p["ndf"], shadowing=p["shadowing"])
    solver = p["solver"] if p["solver"] != "none" else "auto"
    return twoscale.evaluate(wi, sim.wavelengths_nm, p["material"], micro, sim.nano, sim.grid, solver=solver,
                             kd=p["kd"], precision=p["precision"], diffraction=p.get("diffraction", "kirchhoff"),
                             polarization=p.get("polarization", "unpolarized"))


def plot(rows, path, *, title="", tail_deg=10.0):
    """Four panels against θ_i: albedo, FWHM, tail fraction and ΔE2000, both models."""
    plt = figures.pyplot()


    th = [r["theta_i_deg"] for r in rows]
    fig, ax = plt.subplots(2, 2, figsize=(9, 6.5), constrained_layout=True)
    for key, a, lab in (("albedo_Y", ax[0, 0], "albedo (luminance Y)"), ("fwhm_deg", ax[0, 1], "lobe FWHM (deg)"),
                        ("tail_fraction", ax[1, 0], f"energy beyond {tail_deg:g}° of mirror (fraction)")):
        a.plot(th, [r[f"{key}_wave"] for r in rows], "o-", label="two-scale (wave optics)")
        a.plot(th, [r[f"{key}_microfacet"] for r in rows], "s--", label="microfacet")
        a.set_xlabel("θi (deg)")
        a.set_ylabel(lab)
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    ax[1, 0].set_yscale("log")
    a = ax[1, 1]
    a.plot(th, [r["delta_e2000_sphere_mean"] for r in rows], "o-", label="sphere mean")
    a.plot(th, [r["delta_e2000_sphere_max"] for r in rows], "^-", label="sphere max")
    a.plot(th, [r["delta_e2000_albedo"] for r in rows], "s-", label="albedo colour")
    a.axhline(1.0, color="k", lw=0.8, ls=":", label="ΔE = 1 (just noticeable)")
    a.set_xlabel("θi (deg)")
    a.set_ylabel("ΔE2000 two-scale vs microfacet")
    a.grid(alpha=0.3)
    a.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    save_figure(fig, path)


def table_text(rows, tail_deg=10.0) -> str:
    """Fixed-width text table of :func:`compare` rows."""
    head = (f"{'θi':>5} {'albedo wave':>11} {'albedo mf':>9} {'FWHM wave':>9} {'FWHM mf':>7} "
            f"{'tail>' + format(tail_deg, 'g') + '° wave':>14} {'tail mf':>9} {'ΔE albedo':>9} {'ΔE sphere':>15}")
    lines = [head]
    for r in rows:
        lines.append(f"{r['theta_i_deg']:5.1f} {r['albedo_Y_wave']:11.4f} {r['albedo_Y_microfacet']:9.4f} "
                     f"{r['fwhm_deg_wave']:9.2f} {r['fwhm_deg_microfacet']:7.2f} {r['tail_fraction_wave']:14.4f} "
                     f"{r['tail_fraction_microfacet']:9.4f} {r['delta_e2000_albedo']:9.2f} "
                     f"{r['delta_e2000_sphere_mean']:6.2f} / {r['delta_e2000_sphere_max']:6.2f}")
    return "\n".join(lines)
