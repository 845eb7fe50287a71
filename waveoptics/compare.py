"""Where is geometric optics good enough? The two-scale model against the plain microfacet model over θ_i.

For each incidence angle :func:`compare` reports, for both models: the directional albedo (luminance Y under the
illuminant), the angular width (FWHM) of the lobe in the plane of incidence, the energy in the tail beyond a given
angle from the mirror direction, the ΔE2000 between the albedo colours, and the mean/max ΔE2000 between sphere
renders lit from that angle. Widths are measured on the continuous lobe (the BRDF functions of the simulation
evaluated along the plane of incidence, half-maximum crossings interpolated), not on grid cells, so they do not
step with the grid. Sphere renders evaluate the BRDF functions per pixel; the sweep costs one
:func:`waveoptics.simulate.simulate` plus one grid lobe (albedo, tail) per angle.
"""
from __future__ import annotations

import numpy as np

from . import colour
from .renderers import sphere as render
from .brdf import twoscale
from .errors import FieldError
from .io import figures
from .io.figures import save_figure
from .scatter.grid import integrate
from .units import direction_from_angles

__all__ = ['lobe_fwhm_deg', 'compare', 'plot', 'table_text', 'OUTPUTS', 'write_outputs']



def _angle_from_mirror(grid, wi):
    """Angle (deg) between each grid direction and the mirror direction of *wi*."""
    m = np.array([-wi[0], -wi[1], wi[2]])
    d = grid.directions()
    return np.degrees(np.arccos(np.clip(d @ m, -1.0, 1.0)))


def _in_plane_luminance(brdf_fn, wi, t_deg, wavelengths_nm, illuminant):
    """Luminance Y (1/sr) of the BRDF spectrum along ω_o = (−sin t, 0, cos t), t in degrees: the plane of incidence
    of a light at azimuth 0."""
    t = np.radians(np.asarray(t_deg, dtype=float))
    wo = np.stack([-np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    w = np.asarray(wavelengths_nm, dtype=float)
    f = brdf_fn.eval(wi, wo[:, None, :], w[None, :])
    return colour.luminance(colour.reflectance_to_rgb(f, w, illuminant))


def _half_crossing(t, y, i_peak, half, step):
    """Angle where y falls to *half* walking from the peak index by *step* (±1), interpolated; the end if never."""
    i = i_peak
    while 0 <= i + step < t.size and y[i + step] >= half:
        i += step
    j = i + step
    if not 0 <= j < t.size:
        return float(t[i])
    return float(t[i] + (t[j] - t[i]) * (y[i] - half) / (y[i] - y[j]))


def lobe_fwhm_deg(brdf_fn, wi, wavelengths_nm, illuminant, *, n=2001) -> float:
    """Full width at half maximum (deg) of the BRDF's luminance lobe in the plane of incidence of *wi* (azimuth 0),
    measured on the continuous function: a coarse pass over θ_o ∈ (−89.9°, 89.9°), then *n* points on the peak's
    neighbourhood, half-maximum crossings interpolated linearly."""
    t = np.linspace(-89.9, 89.9, n)
    y = _in_plane_luminance(brdf_fn, wi, t, wavelengths_nm, illuminant)
    if not np.any(y > 0):
        return 0.0
    k = int(np.argmax(y))
    lo = _half_crossing(t, y, k, 0.5 * y[k], -1)
    hi = _half_crossing(t, y, k, 0.5 * y[k], +1)
    pad = 2 * (t[1] - t[0])
    t2 = np.linspace(max(lo - pad, -89.9), min(hi + pad, 89.9), n)   # refine: lobes narrower than the coarse step
    y2 = _in_plane_luminance(brdf_fn, wi, t2, wavelengths_nm, illuminant)
    k2 = int(np.argmax(y2))
    return _half_crossing(t2, y2, k2, 0.5 * y2[k2], +1) - _half_crossing(t2, y2, k2, 0.5 * y2[k2], -1)


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
    if sim.brdf_wave is None:
        raise FieldError("compare needs a simulation run with its BRDF functions (sphere=True)", "sphere")
    for th in angles_deg:
        wi = direction_from_angles(th, 0.0)
        L = _lobes_at(sim, wi)
        tot, mf = L.total, L.microfacet
        out = {"theta_i_deg": float(th)}
        ang = _angle_from_mirror(grid, wi)
        rgbs = {}
        for name, f, fn in (("wave", tot, sim.brdf_wave), ("microfacet", mf, sim.brdf_microfacet)):
            rgb_lobe = colour.reflectance_to_rgb(np.moveaxis(f, 0, -1), w, sim.illuminant)
            lum = colour.luminance(rgb_lobe)
            alb = colour.reflectance_to_rgb(integrate(f, grid), w, sim.illuminant)
            rgbs[name] = alb
            total = float(np.sum(np.where(grid.inside, lum, 0))) * grid.du * grid.dv
            tail = float(np.sum(np.where(grid.inside & (ang > tail_deg), lum, 0))) * grid.du * grid.dv
            out[f"albedo_Y_{name}"] = float(colour.luminance(alb))
            out[f"fwhm_deg_{name}"] = lobe_fwhm_deg(fn, wi, w, sim.illuminant)
            out[f"tail_fraction_{name}"] = tail / total if total > 0 else 0.0
        out["delta_e2000_albedo"] = float(colour.delta_e2000(rgbs["wave"], rgbs["microfacet"]))
        light = direction_from_angles(th, 0.0)
        wave, m1 = render.render_sphere(sim.brdf_wave, w, light, size=sphere_size, illuminant=sim.illuminant)
        mfr, _ = render.render_sphere(sim.brdf_microfacet, w, light, size=sphere_size, illuminant=sim.illuminant)
        dE = colour.delta_e2000(wave[m1], mfr[m1]) if m1.any() else np.zeros(1)
        out["delta_e2000_sphere_mean"] = float(np.mean(dE))
        out["delta_e2000_sphere_max"] = float(np.max(dE))
        rows.append(out)
    return rows


def _lobes_at(sim, wi):
    """The simulation's lobes at another incidence: the same micro roughness object the simulation used (its NDF
    shape, a measured slope table or the α a split measured), material, nano roughness and options."""
    p = sim.params
    mf = sim.brdf_microfacet
    solver = p["solver"] if p["solver"] != "none" else "auto"
    return twoscale.evaluate(wi, sim.wavelengths_nm, mf.material, mf.micro, sim.nano, sim.grid, solver=solver,
                             kd=p["kd"], precision=p["precision"], diffraction=p.get("diffraction", "kirchhoff"),
                             polarization=p.get("polarization", "unpolarized"),
                             multiple_scattering=p.get("multiple_scattering", False))


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


#: files of ``compare -o DIR`` (compare.json, the manifest, last)
OUTPUTS = ("compare.csv", "compare.png", "compare.json")


def write_outputs(rows, data: dict, directory, *, tail_deg=10.0, title="") -> None:
    """Write the rows of :func:`compare` as compare.csv, their :func:`plot` as compare.png and *data* as
    compare.json into *directory*, as a set: the three files appear together, compare.json last
    (:func:`waveoptics.io.staged_outputs`)."""
    import csv
    import io as _io
    from pathlib import Path

    from . import io

    buf = _io.StringIO()
    wr = csv.DictWriter(buf, fieldnames=list(rows[0]))
    wr.writeheader()
    wr.writerows(rows)
    with io.staged_outputs(Path(directory), OUTPUTS, last="compare.json") as out:
        with io.atomic_path(out / "compare.csv") as tmp:
            tmp.write_text(buf.getvalue())
        plot(rows, out / "compare.png", tail_deg=tail_deg, title=title)
        io.write_json(out / "compare.json", data)
