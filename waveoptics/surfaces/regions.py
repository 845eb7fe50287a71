"""Per-region plane slopes stored with a height field on disk: a label map and a table of slopes, so that a field
read from a file (a metallic-paint flake field, any mosaic of planes meeting in steps) gives the patch NDF each
region's own plane instead of finite differences across its steps.

A field of planar regions (flakes) has a step where two regions meet. A central difference across a step is the
slope of a facet that is not on the surface (the step is a discontinuity, not a steep facet), and the patch NDF of
Yan et al. (2016) then shows normals no region has — the faint cross of geometric glints through a flake sphere's
highlight. The heights alone cannot tell a step from a steep facet; the regions can. They are stored as

* a **label map**: one integer per sample (same shape as the heights), the index of the sample's region;
* a **table**: (n_regions, 2) float64, the plane slopes (∂h/∂x, ∂h/∂y) of each region (dimensionless).

Each sample's slopes are then the table's row of its label, exact for planar regions. Layout on disk:

* a .npy height field ``NAME.npy``: ``NAME.regions.npy`` (the label map, memory-mapped; :func:`write_regions` makes
  it a sparse file and fills it by blocks) and ``NAME.region_slopes.npy`` (the table);
* a chunked HDF5 field: the datasets ``regions`` (chunked as the heights) and ``region_slopes`` in the same file.

:func:`waveoptics.surfaces.write_tiles` writes both from a :class:`waveoptics.surfaces.FlakeField` (each flake is one
region); :func:`write_regions` writes them from any labels and table (e.g. a segmentation of a measured field).

References
----------
.. [1] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, "Position-normal distributions for efficient rendering of
   specular microstructure", ACM TOG 35(4), 56, 2016 (the patch NDF of a footprint's normals; metallic flakes).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import FieldError

__all__ = ["REGION_DATASETS", "RegionPlanes", "npy_region_paths", "npy_regions", "hdf5_regions", "write_regions"]

#: HDF5 datasets of the label map and of the slopes table (next to the heights' dataset)
REGION_DATASETS = ("regions", "region_slopes")


def npy_region_paths(path) -> tuple[Path, Path]:
    """(label map, slopes table) companion paths of the .npy height field *path* (``NAME.regions.npy``,
    ``NAME.region_slopes.npy``)."""
    p = Path(path)
    stem = p.name[:-4] if p.name.lower().endswith(".npy") else p.name
    return p.with_name(stem + ".regions.npy"), p.with_name(stem + ".region_slopes.npy")


def _table(slopes, source) -> np.ndarray:
    t = np.asarray(slopes, dtype=np.float64)
    if t.ndim != 2 or t.shape[1] != 2 or len(t) == 0 or not np.all(np.isfinite(t)):
        raise FieldError(f"region slopes of {source} must be a finite (n_regions, 2) table of (dh/dx, dh/dy); got "
                         f"shape {t.shape}", "region_slopes")
    return t


class RegionPlanes:
    """The label map and slopes table of a field (module doc): ``slopes(i0, j0, i1, j1)`` → (∂h/∂x, ∂h/∂y) of the
    samples [j0:j1, i0:i1].

    Parameters
    ----------
    read_labels : callable
        ``read_labels(i0, j0, i1, j1)`` → the integer labels of those samples.
    table : array (n_regions, 2)
        Plane slopes of each region.
    source : str
        What the regions belong to (named in errors).
    """

    def __init__(self, read_labels, table, source: str):
        self.read_labels, self.table, self.source = read_labels, _table(table, source), source

    def slopes(self, i0: int, j0: int, i1: int, j1: int) -> tuple[np.ndarray, np.ndarray]:
        lab = np.asarray(self.read_labels(i0, j0, i1, j1))
        if lab.dtype.kind not in "iu":
            raise FieldError(f"the region labels of {self.source} are {lab.dtype}, not integers", "regions")
        if lab.size and (int(lab.min()) < 0 or int(lab.max()) >= len(self.table)):
            raise FieldError(f"region labels of {self.source} in samples [{j0}:{j1}, {i0}:{i1}] lie outside the "
                             f"table of {len(self.table)} regions", "regions")
        s = self.table[lab]
        return s[..., 0], s[..., 1]


def npy_regions(path, shape) -> RegionPlanes | None:
    """The regions stored next to the .npy height field *path* of *shape* (ny, nx), or None when it has none."""
    lab_path, tab_path = npy_region_paths(path)
    if not (lab_path.is_file() and tab_path.is_file()):
        return None
    labels = np.load(lab_path, mmap_mode="r")
    if tuple(labels.shape) != tuple(shape):
        raise FieldError(f"label map {lab_path.name!r} has shape {labels.shape}, the heights {tuple(shape)}",
                         "regions")
    return RegionPlanes(lambda i0, j0, i1, j1: labels[j0:j1, i0:i1], np.load(tab_path), str(lab_path))


def hdf5_regions(path, shape, dataset_handle) -> RegionPlanes | None:
    """The regions of the chunked HDF5 field *path* (datasets :data:`REGION_DATASETS`), or None when it has none;
    *dataset_handle* (name) → an open h5py dataset (the field's own lazily opened file)."""
    import h5py

    lab_name, tab_name = REGION_DATASETS
    with h5py.File(path, "r") as f:
        if lab_name not in f or tab_name not in f:
            return None
        if tuple(f[lab_name].shape) != tuple(shape):
            raise FieldError(f"dataset {lab_name!r} of {str(path)!r} has shape {f[lab_name].shape}, the heights "
                             f"{tuple(shape)}", "regions")
        table = f[tab_name][()]
    return RegionPlanes(lambda i0, j0, i1, j1: dataset_handle(lab_name)[j0:j1, i0:i1], table,
                        f"{path}:{lab_name}")


def write_regions(path, shape, labels, slopes, origin=(0, 0), *, chunk=None) -> None:
    """Store regions with the height field at *path* (.npy, or .h5 / .hdf5) of *shape* (ny, nx): the block of
    *labels* (integers) at sample *origin* (i0, j0) of the label map (created, all 0, when absent: a sparse file or
    chunks never written) and the whole table *slopes* (n_regions, 2), replaced (None: the stored table is kept).

    Parameters
    ----------
    chunk : int, optional
        HDF5 chunk width of a new label map (default: the heights' chunks).
    """
    import h5py

    p = Path(path)
    ny, nx = int(shape[0]), int(shape[1])
    lab = np.asarray(labels)
    given = slopes is not None
    h5 = p.suffix.lower() in (".h5", ".hdf5")
    lab_name, tab_name = REGION_DATASETS
    lab_path, tab_path = npy_region_paths(p)
    if slopes is None:
        if h5:
            with h5py.File(p, "r") as f:
                slopes = f[tab_name][()] if tab_name in f else None
        elif tab_path.is_file():
            slopes = np.load(tab_path)
        if slopes is None:
            raise FieldError(f"{str(p)!r} stores no region slopes yet; give the table", "region_slopes")
    table = _table(slopes, str(p))
    i0, j0 = int(origin[0]), int(origin[1])
    if lab.ndim != 2 or lab.dtype.kind not in "iu" or i0 < 0 or j0 < 0 or i0 + lab.shape[1] > nx \
            or j0 + lab.shape[0] > ny:
        raise FieldError(f"labels must be a 2-D integer block inside the field of {ny} x {nx} samples; got "
                         f"{lab.dtype} {lab.shape} at ({i0}, {j0})", "regions")
    if lab.size and (int(lab.min()) < 0 or int(lab.max()) >= len(table)):
        raise FieldError(f"labels must index the table of {len(table)} regions", "regions")
    sl = (slice(j0, j0 + lab.shape[0]), slice(i0, i0 + lab.shape[1]))
    if h5:
        with h5py.File(p, "r+") as f:
            if lab_name not in f:
                hc = next((f[k].chunks for k in f if f[k].ndim == 2 and f[k].chunks), None)
                ch = (min(chunk, ny), min(chunk, nx)) if chunk else (hc or (min(256, ny), min(256, nx)))
                f.create_dataset(lab_name, shape=(ny, nx), dtype=np.int32, chunks=ch, fillvalue=0)
            if tab_name in f and (f[tab_name].shape != table.shape or not np.array_equal(f[tab_name][()], table)):
                del f[tab_name]
            if tab_name not in f:
                f.create_dataset(tab_name, data=table)
            f[lab_name][sl] = lab
        return
    if not lab_path.is_file():
        np.lib.format.open_memmap(lab_path, mode="w+", dtype=np.int32, shape=(ny, nx))
    out = np.load(lab_path, mmap_mode="r+")
    if tuple(out.shape) != (ny, nx):
        raise FieldError(f"label map {lab_path.name!r} has shape {out.shape}, the heights {(ny, nx)}", "regions")
    out[sl] = lab
    out.flush()
    del out
    if given:
        np.save(tab_path, table)
