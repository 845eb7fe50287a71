"""The files of ``waveoptics scatter``: spectral EXR of the lobes, summary.json and a figure of the lobes.
"""
from __future__ import annotations

import math

import numpy as np

from ..io import figures
from ..io.files import atomic_path, prepare_outdir, staged_outputs, write_json
from ..io.spectral_exr import write_spectral_exr
from .solvers import ScatterResult

__all__ = ['plot_scatter', 'SCATTER_FILES', 'write_scatter', 'brdf_exr_header']


def brdf_exr_header(grid, incident_deg, material: str, **extra) -> dict:
    """The string attributes of every two-scale BRDF image (simulate's and a scene run's spectral and RGB BRDF
    EXR): the direction grid's parametrization, the light's (θ, φ) in degrees, the material, the quantity and its
    unit, plus *extra* attributes (``waveoptics_`` is prefixed to their names)."""
    hdr = {k: str(v) for k, v in grid.header().items()}
    hdr.update({"waveoptics_incident_deg": " ".join(f"{float(a):g}" for a in incident_deg),
                "waveoptics_material": str(material), "waveoptics_quantity": "BRDF f (1/sr), not x cos",
                "waveoptics_unit": "1/sr (a BRDF, not multiplied by cos theta_o: values exceed 1 near sharp lobes)"})
    hdr.update({f"waveoptics_{k}": str(v) for k, v in extra.items()})
    return hdr

def plot_scatter(result: ScatterResult, path, *, overwrite: bool = True, max_lobes: int = 4):
    """PNG: the lobes at a few wavelengths (log scale, direction-cosine plane) and the fractions vs wavelength."""
    plt = figures.pyplot()


    wl = result.wavelengths_nm
    idx = np.unique(np.linspace(0, wl.size - 1, min(max_lobes, wl.size)).round().astype(int))
    fig, axes = plt.subplots(1, idx.size + 1, figsize=(3.2 * (idx.size + 1) + 1.2, 3.4), layout="constrained")
    g = result.grid
    ext = (*g.u_range, *g.v_range)
    top = float(result.brdf.max()) if result.brdf.max() > 0 else 1.0
    im = None
    for ax, i in zip(axes[:-1], idx):
        f = np.where(g.inside, result.brdf[i], np.nan)
        im = ax.imshow(np.log10(np.maximum(f, top * 1e-8)), origin="lower", extent=ext, vmin=np.log10(top) - 8,
                       vmax=np.log10(top), cmap="magma")
        ax.set_title(f"{wl[i]:g} nm")
        ax.set_xlabel("u = sinθ cosφ")
        ax.set_ylabel("v = sinθ sinφ")
    if im is not None:
        fig.colorbar(im, ax=axes[idx.size - 1], label="log10 BRDF (1/sr)", shrink=0.8)
    ax = axes[-1]
    ax.plot(wl, result.albedo, "k-", label="albedo")
    ax.plot(wl, result.coherent_specular_fraction * result.flat_albedo, "b--", label="coherent")
    ax.plot(wl, result.scattered_fraction, "r:", label="scattered")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    plt.close(fig)


#: files written by :func:`write_scatter`
SCATTER_FILES = ("lobes.exr", "summary.json", "lobes.png")


def write_scatter(result: ScatterResult, outdir, *, overwrite: bool = False, header: dict | None = None,
                  surface_info: dict | None = None) -> dict:
    """Write ``lobes.exr`` (spectral OpenEXR, one ``T.<λ>nm`` layer per wavelength, BRDF in 1/sr on the
    direction-cosine grid), ``summary.json`` and ``lobes.png`` into *outdir*. Returns {name: path}.

    *header* (strings) goes into the EXR header and the summary; *surface_info* (the height field's
    :meth:`~waveoptics.surfaces.HeightField.provenance`: grid, file, instrument) into the summary only."""

    final = prepare_outdir(outdir, overwrite=overwrite, expected=SCATTER_FILES)
    # the set is staged and moved into place whole (summary.json last): a failure leaves an earlier set intact
    with staged_outputs(final, SCATTER_FILES, last="summary.json") as out:
        _write_scatter(result, out, header, surface_info)
    return {name: final / name for name in SCATTER_FILES}


def _write_scatter(result: ScatterResult, out, header, surface_info=None) -> None:
    th = math.degrees(math.acos(min(1.0, float(result.incident[2]))))
    ph = math.degrees(math.atan2(result.incident[1], result.incident[0]))
    hdr = {**result.grid.header(), "quantity": "BRDF f (1/sr), Kirchhoff model, ensemble mean",
           "incident_theta_deg": f"{th:.17g}", "incident_phi_deg": f"{ph:.17g}", "solver": result.solver,
           "realizations": str(result.realizations), **(header or {})}
    hdr["waveoptics_unit"] = "1/sr (a BRDF, not multiplied by cos theta_o)"
    layers = {float(w): result.grid.to_image(result.brdf[i]) for i, w in enumerate(result.wavelengths_nm)}
    write_spectral_exr(out / "lobes.exr", layers, hdr)
    plot_scatter(result, out / "lobes.png")
    extra = {} if surface_info is None else {"surface_info": surface_info}
    write_json(out / "summary.json", {**result.summary(), **(header or {}), **extra})
