"""Metamers: laser-line spectra with the same XYZ as a continuous illuminant (colour vision is a 3-D
projection of the spectrum; CIE 015:2018 §7).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import WaveopticsError
from ..io.files import atomic_path
from ..units import check_wavelengths
from .colorimetry import DEFAULT_OBSERVER, XYZ_to_rgb, cmf_at, cmfs, observer_name, spd_to_XYZ
from .illuminants import SPD, SPD_FACTORIES, as_spd, laser

__all__ = ['metamer_laser_weights', 'metamer_summary', 'plot_metamers', 'RGB_LASER_NM', 'rgb_laser_projector']

# ------------------------------------------------------------------------------------------- metamers

def metamer_laser_weights(target_spd, lines_nm, observer=DEFAULT_OBSERVER) -> np.ndarray:
    """Powers of three laser lines whose mix has the same XYZ as *target_spd*.

    Solves Σ_l P_l x̄ȳz̄(λ_l) = ∫ S x̄ȳz̄ dλ (a 3×3 linear system).

    Parameters
    ----------
    target_spd : str or SPD
        The light to match (e.g. ``"D65"``).
    lines_nm : sequence of 3 float, nm
        Laser wavelengths.

    Returns
    -------
    numpy.ndarray (3,)
        Line powers, in the target's units × nm (so the mix has the target's absolute XYZ).

    Raises
    ------
    WaveopticsError
        Not three distinct visible lines, or a match needs negative power (the target lies outside the
        lines' chromaticity triangle).
    """
    target = as_spd(target_spd)
    lines = check_wavelengths(lines_nm, name="laser line")
    if lines.size != 3 or np.unique(lines).size != 3:
        raise WaveopticsError(f"metamer needs exactly 3 distinct laser lines, got {lines.tolist()} nm")
    M = cmf_at(lines, observer).T  # columns: XYZ of a unit-power line
    if np.linalg.cond(M) > 1e8:
        raise WaveopticsError(f"laser lines {lines.tolist()} nm are (nearly) colour-collinear or invisible; "
                              "choose a blue, a green and a red line")
    P = np.linalg.solve(M, spd_to_XYZ(target, observer))
    if np.any(P < 0):
        bad = int(np.argmin(P))
        raise WaveopticsError(f"{target.name} cannot be matched by lines {lines.tolist()} nm: line "
                              f"{lines[bad]:g} nm would need negative power; choose lines around its "
                              "chromaticity (blue, green, red)")
    return P


def metamer_summary(target_spd, lines_nm, observer=DEFAULT_OBSERVER) -> dict:
    """The laser metamer of a light as plain data (for the CLI and docs).

    Returns
    -------
    dict
        ``target``, ``observer``, ``lines_nm``, ``powers`` (target units × nm, see
        :func:`metamer_laser_weights`), ``power_fractions`` (sum 1), ``XYZ_target`` and ``XYZ_mix`` (scaled so the
        target's Y = 1) and ``xy`` (chromaticity of the target).
    """

    target = as_spd(target_spd)
    lines = check_wavelengths(lines_nm, name="laser line")
    P = metamer_laser_weights(target, lines, observer)
    XYZ_t = spd_to_XYZ(target, observer)
    XYZ_m = spd_to_XYZ(laser(lines, P), observer)
    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)

    return {"target": target.name, "observer": observer_name(observer), "lines_nm": lines.tolist(),
            "powers": P.tolist(), "power_fractions": (P / P.sum()).tolist(),
            "XYZ_target": (XYZ_t / XYZ_t[1]).tolist(), "XYZ_mix": (XYZ_m / XYZ_t[1]).tolist(),
            "xy": colour.XYZ_to_xy(XYZ_t).tolist()}


def plot_metamers(target_spd, lines_nm, powers, path, *, observer=DEFAULT_OBSERVER,
                  overwrite: bool = False) -> Path:
    """PNG plot of a continuous SPD and its laser-line metamer (stems), with both chromaticities.

    Parameters
    ----------
    target_spd : str or SPD
    lines_nm, powers : sequences of float
        Laser wavelengths (nm) and powers (target units × nm), e.g. from :func:`metamer_laser_weights`.
    path : str or Path
        PNG file (written atomically; refused if it exists unless *overwrite*).
    """
    import colour   # colour-science and matplotlib, imported where used (about 2 s)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    target = as_spd(target_spd)
    mix = laser(lines_nm, powers)
    xy_t = colour.XYZ_to_xy(spd_to_XYZ(target, observer))
    xy_m = colour.XYZ_to_xy(spd_to_XYZ(mix, observer))
    w_cmf, c = cmfs(observer)
    fig = Figure(figsize=(7.5, 4.2), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    if target.lines:
        ax.stem(target.wavelengths_nm, target.values, linefmt="k-", markerfmt="ko", basefmt=" ",
                label=target.name)
    else:
        wt = w_cmf[(w_cmf >= 360) & (w_cmf <= 780)]
        ax.plot(wt, target(wt), "k-", lw=1.5, label=f"{target.name} (per nm)")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("relative spectral power per nm")
    ax.set_xlim(360, 780)
    ax.set_ylim(bottom=0)
    ax2 = ax.twinx()
    for lam, p, col in zip(mix.wavelengths_nm, mix.values, _line_colours(mix.wavelengths_nm, observer)):
        ax2.vlines(lam, 0, p, color=col, lw=3)
        ax2.annotate(f"{lam:g} nm", (lam, p), textcoords="offset points", xytext=(0, 4), ha="center", fontsize=8)
    ax2.set_ylabel("laser line power (× 1 nm)")
    ax2.set_ylim(0, 1.15 * mix.values.max())
    for i in range(3):
        ax.plot(w_cmf, c[:, i] / c.max() * ax.get_ylim()[1] * 0.5, ":", lw=0.8, color="grey",
                label="CMFs (scaled)" if i == 0 else None)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"Metamers: {target.name} xy=({xy_t[0]:.4f}, {xy_t[1]:.4f}) vs lasers "
                 f"xy=({xy_m[0]:.4f}, {xy_m[1]:.4f})", fontsize=9)
    fig.tight_layout()
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format="png")
    return Path(path)


def _line_colours(lines_nm, observer):
    """Display sRGB (0-1) of monochromatic lines, scaled into gamut (for plotting only)."""
    rgb = XYZ_to_rgb(cmf_at(lines_nm, observer), "sRGB")
    rgb = np.clip(rgb, 0.0, None)
    rgb = rgb / np.maximum(rgb.max(axis=-1, keepdims=True), 1e-12)
    return [tuple(r) for r in np.clip(rgb, 0.0, 1.0)]


#: BT.2020 monochromatic primaries (nm): wavelengths of the "rgb-laser" projector [7]_
RGB_LASER_NM = (467.0, 532.0, 630.0)


def rgb_laser_projector(lines_nm=RGB_LASER_NM, white="D65", observer=DEFAULT_OBSERVER) -> SPD:
    """A three-laser RGB projector whose full-white mix is a metamer of *white* (same XYZ).

    Parameters
    ----------
    lines_nm : sequence of 3 float, nm
        Laser wavelengths; default the BT.2020 primaries 467, 532, 630 nm [1]_.
    white : str or SPD
        The white the projector is calibrated to.

    References
    ----------
    .. [1] ITU-R BT.2020-2 (2015), Table 3 (primaries on the spectral locus, D65 white).
    """
    target = as_spd(white)
    powers = metamer_laser_weights(target, lines_nm, observer=observer)
    label = ",".join(f"{x:g}" for x in np.asarray(lines_nm, dtype=float))
    return laser(lines_nm, powers, name=f"rgb-laser {label} nm ({target.name} white)")


SPD_FACTORIES["rgb-laser"] = rgb_laser_projector
