"""Figures of a height field (map, profile, radial PSD with fits).
"""
from __future__ import annotations

import numpy as np

from ..io import figures
from ..io.files import atomic_path
from .heightfield import HeightField
from .psd import PSD_MODELS
from .statistics import psd_radial

__all__ = ['plot']

def plot(hf: HeightField, path, *, fits=(), overwrite: bool = False):
    """PNG with the height map (nm) and the radial PSD with fitted models, written atomically.

    Parameters
    ----------
    hf : HeightField
    path : str or Path
        Output .png.
    fits : iterable of dict
        Results of :func:`fit_psd` to overlay.
    overwrite : bool
        Replace an existing file.
    """
    plt = figures.pyplot()


    f, S = psd_radial(hf)
    profile = 1 in hf.shape
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5))
    x, y = hf.coords()
    h_nm = np.where(hf.valid, hf.heights, np.nan) * 1e9
    if profile:
        ax0.plot((x if hf.shape[0] == 1 else y) * 1e6, h_nm.ravel(), lw=0.8)
        ax0.set(xlabel="position (µm)", ylabel="height (nm)")
    else:
        im = ax0.imshow(h_nm, origin="lower", cmap="viridis",
                        extent=[x[0] * 1e6, x[-1] * 1e6, y[0] * 1e6, y[-1] * 1e6])
        fig.colorbar(im, ax=ax0, label="height (nm)")
        ax0.set(xlabel="x (µm)", ylabel="y (µm)")
    ax0.set_title(str(hf.meta.get("model", hf.meta.get("source", "height field"))))
    ax1.loglog(f * 1e-6, S, ".", ms=3, label="radial periodogram")
    for fit in fits:
        family = PSD_MODELS[fit["model"]]
        fn = family.S1 if profile else family.S
        args = ((fit["sigma_m"], fit["B_m"], fit["C"]) if fit["model"] == "abc"
                else (fit["sigma_m"], fit["corr_length_m"]))
        ax1.loglog(f * 1e-6, fn(f, *args), lw=1.2, label=f"{fit['model']} fit")
    ax1.set(xlabel="spatial frequency |f| (1/µm)", ylabel="PSD (m³)" if profile else "PSD (m⁴)",
            ylim=(max(S.min(), S.max() * 1e-12), S.max() * 10))
    ax1.legend()
    fig.tight_layout()
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
