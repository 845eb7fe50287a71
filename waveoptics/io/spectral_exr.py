"""Spectral OpenEXR in the layout of Fichet, Pacanowski & Wilkie (2021): one channel per wavelength.

References
----------
.. [1] A. Fichet, R. Pacanowski, A. Wilkie, "An OpenEXR layout for spectral images", JCGT 10(3), 2021.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import WaveopticsError
from .files import NonFiniteOutputError, read_exr, write_exr

__all__ = ['SPECTRAL_LAYOUT_VERSION', 'spectral_channel_name', 'write_spectral_exr', 'read_spectral_exr']

# ----------------------------------------------------------------------------------------------------------------
# Spectral OpenEXR (Fichet, Pacanowski & Wilkie 2021)
# ----------------------------------------------------------------------------------------------------------------

#: value of the ``spectralLayoutVersion`` header attribute this writer follows
SPECTRAL_LAYOUT_VERSION = "1.0"


def spectral_channel_name(wavelength_nm: float, *, emissive: bool = False) -> str:
    """Channel name of one wavelength in the spectral OpenEXR layout: ``T.550,000000nm`` (reflective) or
    ``S0.550,000000nm`` (emissive, unpolarized Stokes component 0); the decimal separator is a comma.

    References
    ----------
    .. [1] A. Fichet, R. Pacanowski, A. Wilkie, "An OpenEXR Layout for Spectral Images", JCGT 10(3), 2021, §3
       (channel naming ``<component>.<value with comma decimal><unit>``, ``spectralLayoutVersion``).
    """
    w = float(wavelength_nm)
    if not np.isfinite(w) or w <= 0:
        raise WaveopticsError(f"wavelength {wavelength_nm!r} nm is not allowed in a spectral channel name; it must "
                              "be finite and > 0")
    return ("S0." if emissive else "T.") + f"{w:.6f}".replace(".", ",") + "nm"


def write_spectral_exr(path, layers: dict, header: dict | None = None, *, emissive: bool = False,
                       overwrite: bool = True) -> Path:
    """Write per-wavelength images as one spectral OpenEXR file (atomically).

    Parameters
    ----------
    layers : dict of float -> ndarray (H, W)
        Wavelength in nm to image; all images the same shape. Stored as float32 channels named by
        :func:`spectral_channel_name`.
    header : dict, optional
        Extra attributes (pass floats that need full precision as strings).
    emissive : bool
        ``S0.`` channels with ``emissiveUnits`` = W.m^-2.sr^-1 instead of reflective ``T.`` channels.

    References
    ----------
    .. [1] Fichet, Pacanowski & Wilkie, JCGT 10(3), 2021.
    """
    if not layers:
        raise WaveopticsError("a spectral image needs at least one wavelength layer")
    chans = {}
    for wl in sorted(layers, key=float):
        name = spectral_channel_name(wl, emissive=emissive)
        if name in chans:
            raise WaveopticsError(f"wavelength {wl!r} nm appears twice in the spectral layers")
        img = np.asarray(layers[wl], dtype=float)
        # a BRDF, a reflectance or a radiance is never negative nor infinite: such a value is a defect upstream,
        # refused here in one line rather than written (issue 34); the cause is fixed where it is computed
        if not np.all(np.isfinite(img)) or (img.size and img.min() < 0):
            bad = img[~np.isfinite(img)] if not np.all(np.isfinite(img)) else [img.min()]
            raise NonFiniteOutputError(f"the spectral layer {wl:g} nm of {Path(path).name} holds {bad[0]!r}: a "
                                       "BRDF or radiance is finite and >= 0")
        chans[name] = img
    hdr = {"spectralLayoutVersion": SPECTRAL_LAYOUT_VERSION}
    if emissive:
        hdr["emissiveUnits"] = "W.m^-2.sr^-1"
    hdr.update(header or {})
    return write_exr(path, chans, hdr, overwrite=overwrite)


def read_spectral_exr(path) -> tuple[dict, dict]:
    """Read the spectral channels of an OpenEXR file: ({wavelength_nm: image}, header).

    Channel names are parsed with colour-science's pattern for the Fichet et al. 2021 layout; reflective
    ``T.`` channels are returned, or emissive ``S0.`` channels when there are no reflective ones.
    """
    # deferred: colour-science takes most of a second to import and only this reader needs it (the core layer,
    # and so the command line's parsers, stay quick to load)
    from colour.io.fichet2021 import PATTERN_FICHET2021, match_groups_to_nm

    chans, header = read_exr(path)
    found = {"T": {}, "S0": {}}
    for name, img in chans.items():
        m = re.fullmatch(rf"(T|S0)\.{PATTERN_FICHET2021}", name)
        if m:
            found[m.group(1)][match_groups_to_nm(m.group(2), m.group(4) or "", m.group(5))] = img
    layers = found["T"] or found["S0"]
    if not layers:
        raise WaveopticsError(f"{str(path)!r} has no spectral channels (T.<wavelength>nm or S0.<wavelength>nm)")
    return dict(sorted(layers.items())), header
