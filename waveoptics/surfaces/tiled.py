"""Height fields of real surfaces (millimetres at 50–100 nm spacing: 10⁸–10¹⁰ samples) that are never held in
memory: a footprint anywhere reads, or generates, only its own patch.

Every field here is a :class:`TiledField`: a grid ``shape`` = (ny, nx) of spacing ``dx``, ``dy`` (m) whose
``patch(i0, j0, nx, ny)`` returns the samples [j0:j0+ny, i0:i0+nx] (rows y, columns x) as a
:class:`~waveoptics.surfaces.HeightField` in metres; ``region(i0, j0, i1, j1)`` is the same by corners (what
:func:`~waveoptics.surfaces.footprint_patch` calls). Implementations:

* :class:`NpyField` — a .npy file memory-mapped (``np.load(mmap_mode='r')``); :func:`create_npy` makes one of any
  size with :func:`numpy.lib.format.open_memmap` (a sparse file: tiles never written read as 0 and cost no disk);
* :class:`HDF5Field` — a chunked HDF5 dataset (``h5py``): a read touches only the chunks it overlaps;
  :func:`create_hdf5` makes one (chunks never written read as the fill value 0);
* procedural fields, evaluated on demand and deterministic in (seed, tile or cell index):
  :class:`PSDField` (a Gaussian random field of a given PSD), :class:`ScratchField` (scratches; ``brushed`` and
  ``scratched`` are its presets), :class:`FlakeField` (metallic-paint flakes).

Continuity across tiles (procedural fields)
-------------------------------------------
Each procedural field is *one* global function of the integer sample index; a patch evaluates that function on its
own samples, so two patches that overlap agree exactly on the overlap, whatever tiles they cross (tested to
round-off in ``tests/test_tiled.py``).

* :class:`PSDField` is the moving-average (convolution) form of a stationary Gaussian field [1]_: white noise
  ξ[m] ~ N(0, 1) on the global grid convolved with a kernel k whose discrete spectrum is √(S(f)/(Δx Δy)), so that
  h has PSD S (k = IDFT of √(S/(ΔxΔy)) on an M² grid; Σ k² = Σ S Δf² ≈ ∫ S d²f = σ²). ξ on tile (t_x, t_y) of
  ``tile``² samples is drawn from ``default_rng([seed, t_x, t_y])``, so ξ at any global index is fixed by the
  seed alone, and a patch convolves the noise of the tiles within the kernel's radius of it. The kernel is cut to
  the smallest square that keeps all but 10⁻⁶ of its energy (``kernel_energy_kept`` records what is kept; no
  renormalization).
* :class:`ScratchField` and :class:`FlakeField` are sparse primitives owned by cells of a global lattice: cell
  (c_x, c_y) draws its scratches (or its flake) from ``default_rng([seed, salt, c_x, c_y])``; a patch evaluates
  the primitives of every cell whose primitives can reach it (a scratch reaches half its length plus three
  widths from its cell's box; a flake's Voronoi cell, the nearest centre, is found among the 5 × 5 cells around).

A field may also give exact slopes (``gives_slopes`` True), ``region_slopes(i0, j0, i1, j1)`` → (heights,
∂h/∂x, ∂h/∂y): :class:`FlakeField` does (each sample takes its flake's plane), and so do :class:`NpyField` and
:class:`HDF5Field` when a label map and a table of plane slopes are stored with them
(:mod:`waveoptics.surfaces.regions`; :func:`write_tiles` stores a flake field's), so that the patch NDF of
:func:`waveoptics.scatter.pixel_brdf` does not take the steps between flakes for facets.

References
----------
.. [1] J. A. Ogilvy, *Theory of Wave Scattering from Random Rough Surfaces*, Adam Hilger, 1991, §4.2 (spectral
   synthesis and the moving-average form of a Gaussian random surface).
.. [2] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 75, 2018 (millimetre fields at sub-µm spacing).
.. [3] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, ACM TOG 35(4), 56, 2016 (scratches, brushed metal and
   metallic flakes).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..errors import FieldError, WaveopticsError
from .heightfield import HeightField
from .psd import S_abc, S_exponential, S_gaussian
from .regions import hdf5_regions, npy_regions, write_regions
from .tiled_base import TiledBase, TiledField, shape_spacing

__all__ = ["TiledField", "NpyField", "HDF5Field", "create_npy", "create_hdf5", "write_tiles", "PSDField",
           "ScratchField", "FlakeField", "PROCEDURAL", "procedural"]


# ----------------------------------------------------------------------------------------------------------------
# On disk: memory-mapped .npy and chunked HDF5
# ----------------------------------------------------------------------------------------------------------------

class NpyField(TiledBase):
    """A .npy height field (heights in metres × ``scale``) memory-mapped: a patch reads only its own pages.

    Parameters
    ----------
    path : str or Path
        The .npy file; its sidecar ``FILE.npy.json`` (``{"dx": m, "dy": m, "units": "m"}``) gives the spacing
        unless *dx* is given.
    dx, dy : float, m, optional
    """

    def __init__(self, path, dx=None, dy=None):
        self.path = Path(path)
        if not self.path.is_file():
            raise WaveopticsError(f"file {str(self.path)!r} does not exist")
        side = self.path.with_name(self.path.name + ".json")
        info = json.loads(side.read_text()) if side.is_file() else {}
        if dx is None and "dx" not in info:
            raise FieldError(f"{str(self.path)!r} does not state its grid spacing; give dx", "spacing")
        units = {"m": 1.0, "um": 1e-6, "nm": 1e-9}
        self.scale = units.get(info.get("units", "m"))
        if self.scale is None:
            raise FieldError(f"units {info.get('units')!r} in {side.name!r} are not allowed; m, um or nm", "units")
        dxs = float(dx) if dx is not None else float(info["dx"]) * self.scale
        dys = float(dy) if dy is not None else (float(info.get("dy", info["dx"])) * self.scale if dx is None
                                                else dxs)
        self.array = np.load(self.path, mmap_mode="r")
        if self.array.ndim != 2:
            raise WaveopticsError(f"{str(self.path)!r} holds an array of shape {self.array.shape}; heights must be "
                                  "2-D")
        ny, nx, self.dx, self.dy = shape_spacing(*self.array.shape, dxs, dys)
        self.shape = (ny, nx)
        self._args = (str(self.path), dx, dy)
        self.reload_regions()

    def reload_regions(self) -> None:
        """Read the regions stored with the file again (after :func:`write_tiles` or
        :func:`waveoptics.surfaces.regions.write_regions`)."""
        self.planes = npy_regions(self.path, self.shape)

    def __reduce__(self):     # pickled as its path: a worker maps the file itself
        return (type(self), self._args)

    def _read(self, i0, j0, nx, ny):
        return np.asarray(self.array[j0:j0 + ny, i0:i0 + nx], dtype=np.float64) * self.scale

    def describe(self) -> str:
        return str(self.path)


def create_npy(path, ny: int, nx: int, dx: float, dy: float | None = None, dtype=np.float32) -> NpyField:
    """An empty (all-zero, sparse on disk) .npy height field of ny × nx samples in metres with its sidecar; fill
    it with :func:`write_tiles`."""
    ny, nx, dx, dy = shape_spacing(ny, nx, dx, dy)
    p = Path(path)
    a = np.lib.format.open_memmap(p, mode="w+", dtype=dtype, shape=(ny, nx))
    del a
    p.with_name(p.name + ".json").write_text(json.dumps({"dx": dx, "dy": dy, "units": "m"}))
    return NpyField(p)


class HDF5Field(TiledBase):
    """A chunked HDF5 height field (dataset *dataset*, heights in m, attributes ``dx``, ``dy`` in m): a patch reads
    only the chunks it overlaps."""

    def __init__(self, path, dataset: str = "heights"):
        import h5py

        self.path, self.dataset = Path(path), dataset
        if not self.path.is_file():
            raise WaveopticsError(f"file {str(self.path)!r} does not exist")
        with h5py.File(self.path, "r") as f:
            if dataset not in f:
                raise FieldError(f"{str(self.path)!r} has no dataset {dataset!r}", "dataset")
            ds = f[dataset]
            if ds.ndim != 2:
                raise WaveopticsError(f"dataset {dataset!r} has shape {ds.shape}; heights must be 2-D")
            a = dict(ds.attrs)
            shape, self.chunks = ds.shape, ds.chunks
        if "dx" not in a:
            raise FieldError(f"dataset {dataset!r} of {str(self.path)!r} has no dx attribute", "spacing")
        ny, nx, self.dx, self.dy = shape_spacing(*shape, a["dx"], a.get("dy", a["dx"]))
        self.shape = (ny, nx)
        self._file = None        # opened for reading on the first patch (write_tiles closes it)
        self.reload_regions()

    def reload_regions(self) -> None:
        """Read the regions stored with the file again (after :func:`write_tiles` or
        :func:`waveoptics.surfaces.regions.write_regions`)."""
        self.close()
        self.planes = hdf5_regions(self.path, self.shape, self._data)

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def __reduce__(self):
        return (type(self), (str(self.path), self.dataset))

    def _data(self, name):
        """Dataset *name* of the file, opened for reading once."""
        if self._file is None:
            import h5py

            self._file = h5py.File(self.path, "r")
        return self._file[name]

    def _read(self, i0, j0, nx, ny):
        return self._data(self.dataset)[j0:j0 + ny, i0:i0 + nx]

    def describe(self) -> str:
        return f"{self.path}:{self.dataset}"


def create_hdf5(path, ny: int, nx: int, dx: float, dy: float | None = None, chunk: int = 256,
                dtype=np.float32, dataset: str = "heights") -> HDF5Field:
    """An empty chunked HDF5 height field (chunks of *chunk*² samples; unwritten chunks read 0 and take no disk)."""
    import h5py

    ny, nx, dx, dy = shape_spacing(ny, nx, dx, dy)
    with h5py.File(path, "w") as f:
        ds = f.create_dataset(dataset, shape=(ny, nx), dtype=dtype, chunks=(min(chunk, ny), min(chunk, nx)),
                              fillvalue=0.0)
        ds.attrs["dx"], ds.attrs["dy"], ds.attrs["units"] = dx, dy, "m"
    return HDF5Field(path, dataset)


def write_tiles(target, source: TiledField, tiles=None, tile: int = 1024) -> int:
    """Write the samples of *source* into *target* (an :class:`NpyField` or :class:`HDF5Field` path of the same
    shape) tile by tile: all tiles, or only *tiles* (an iterable of (t_x, t_y)). Returns the tiles written. A source
    made of planar regions (:class:`FlakeField`: ``region_labels`` and ``plane_table``) also stores its label map
    and slopes table with the target (:mod:`waveoptics.surfaces.regions`), so the file gives each flake's plane."""
    import h5py

    ny, nx = source.shape
    if tiles is None:
        tiles = [(tx, ty) for ty in range(-(-ny // tile)) for tx in range(-(-nx // tile))]
    if hasattr(source, "plane_table"):
        if isinstance(target, HDF5Field):
            target.close()
        table = source.plane_table()
        for k, (tx, ty) in enumerate(tiles):
            i0, j0 = tx * tile, ty * tile
            write_regions(target.path, (ny, nx), source.region_labels(i0, j0, min(nx, i0 + tile), min(ny, j0 + tile)),
                          table if k == 0 else None, (i0, j0))
    n = 0
    if isinstance(target, HDF5Field):
        target.close()
        f = h5py.File(target.path, "r+")
        out = f[target.dataset]
    else:
        f, out = None, np.load(target.path, mmap_mode="r+")
    try:
        if tuple(out.shape) != (ny, nx):
            raise FieldError(f"target shape {tuple(out.shape)} is not the source's {(ny, nx)}", "shape")
        for tx, ty in tiles:
            i0, j0 = tx * tile, ty * tile
            w, h = min(tile, nx - i0), min(tile, ny - j0)
            out[j0:j0 + h, i0:i0 + w] = source.patch(i0, j0, w, h).heights
            n += 1
    finally:
        if f is not None:
            f.close()
        else:
            out.flush()
    if hasattr(source, "plane_table"):
        target.reload_regions()
    return n


# ----------------------------------------------------------------------------------------------------------------
# Procedural fields
# ----------------------------------------------------------------------------------------------------------------

def _cell_rng(seed: int, *index) -> np.random.Generator:
    """The generator of one tile or cell: a SeedSequence of (seed, index...) (indices shifted to be >= 0)."""
    return np.random.default_rng(np.random.SeedSequence([int(seed)] + [int(i) + 2 ** 40 for i in index]))


_PSD = {"gaussian": S_gaussian, "exponential": S_exponential}


class PSDField(TiledBase):
    """A stationary Gaussian random field of an isotropic PSD, evaluated per patch (moving-average form; module
    doc).

    Parameters
    ----------
    model : {'gaussian', 'exponential', 'abc'}
        PSD of :mod:`waveoptics.surfaces.psd` (σ, T; abc: σ, B = *T*, C = *C*).
    sigma, T : float, m
        rms height and correlation length (abc: the B parameter).
    shape : (ny, nx)
    dx, dy : float, m
    seed : int
    tile : int
        Noise tile width (samples).
    C : float
        abc exponent (> 2).
    stretch : (sx, sy)
        Anisotropy: the PSD is S(f_x sx, f_y sy) sx sy (correlation lengths T sx along x, T sy along y; brushed
        finishes are long along the brushing direction).
    """

    def __init__(self, model, sigma, T, shape, dx, dy=None, seed=0, tile=256, C=3.0, stretch=(1.0, 1.0)):
        ny, nx, self.dx, self.dy = shape_spacing(shape[0], shape[1], dx, dy)
        self.shape = (ny, nx)
        if model not in ("gaussian", "exponential", "abc"):
            raise FieldError(f"PSD model {model!r} is not allowed; gaussian, exponential or abc", "model")
        if not (sigma >= 0 and T > 0):
            raise FieldError(f"sigma={sigma!r} m and T={T!r} m are not allowed (sigma >= 0, T > 0)", "sigma")
        self.model, self.sigma, self.T, self.C, self.seed = model, float(sigma), float(T), float(C), int(seed)
        self.tile, self.stretch = int(tile), (float(stretch[0]), float(stretch[1]))
        self.kernel, self.kernel_energy_kept = self._kernel()
        self.radius = (self.kernel.shape[1] // 2, self.kernel.shape[0] // 2)

    def __reduce__(self):
        return (type(self), (self.model, self.sigma, self.T, self.shape, self.dx, self.dy, self.seed, self.tile,
                             self.C, self.stretch))

    def _S(self, fx, fy):
        sx, sy = self.stretch
        f = np.hypot(fx * sx, fy * sy)
        if self.model == "abc":
            return S_abc(f, self.sigma, self.T, self.C) * sx * sy
        return _PSD[self.model](f, self.sigma, self.T) * sx * sy

    def _kernel(self):
        """k on the smallest centred odd square keeping all but 1e-6 of Σ k² (module doc)."""
        sx, sy = self.stretch
        Mx = int(2 ** math.ceil(math.log2(max(64, 16 * self.T * sx / self.dx))))
        My = int(2 ** math.ceil(math.log2(max(64, 16 * self.T * sy / self.dy))))
        if Mx * My > 2 ** 24:
            raise FieldError(f"correlation length {self.T:g} m on spacing {self.dx:g} m needs a kernel of {My} x "
                             f"{Mx} samples; at most 2^24", "T")
        fx = np.fft.fftfreq(Mx, self.dx)[None, :]
        fy = np.fft.fftfreq(My, self.dy)[:, None]
        k = np.fft.fftshift(np.fft.ifft2(np.sqrt(self._S(fx, fy) / (self.dx * self.dy))).real)
        total = float(np.sum(k * k))
        cy, cx = My // 2, Mx // 2
        e2 = k * k
        for r in range(1, max(cx, cy) + 1):
            ry, rx = min(r * My // Mx if My < Mx else r, cy - 1), min(r * Mx // My if Mx < My else r, cx - 1)
            kept = float(np.sum(e2[cy - ry:cy + ry + 1, cx - rx:cx + rx + 1]))
            if kept >= (1 - 1e-6) * total or (ry == cy - 1 and rx == cx - 1):
                return k[cy - ry:cy + ry + 1, cx - rx:cx + rx + 1].copy(), kept / max(total, 1e-300)
        raise AssertionError("unreachable")

    def noise(self, i0, j0, nx, ny) -> np.ndarray:
        """The global white noise ξ on samples [j0:j0+ny, i0:i0+nx] (any integers, also outside the field)."""
        T = self.tile
        out = np.empty((ny, nx))
        for ty in range(j0 // T, (j0 + ny - 1) // T + 1):
            for tx in range(i0 // T, (i0 + nx - 1) // T + 1):
                xi = _cell_rng(self.seed, tx, ty).standard_normal((T, T))
                a0, a1 = max(i0, tx * T), min(i0 + nx, (tx + 1) * T)
                b0, b1 = max(j0, ty * T), min(j0 + ny, (ty + 1) * T)
                out[b0 - j0:b1 - j0, a0 - i0:a1 - i0] = xi[b0 - ty * T:b1 - ty * T, a0 - tx * T:a1 - tx * T]
        return out

    def _read(self, i0, j0, nx, ny):
        from scipy.signal import fftconvolve

        rx, ry = self.radius
        xi = self.noise(i0 - rx, j0 - ry, nx + 2 * rx, ny + 2 * ry)
        return fftconvolve(xi, self.kernel, mode="valid")

    def describe(self) -> str:
        return f"PSDField({self.model}, sigma={self.sigma:g} m, T={self.T:g} m, seed={self.seed})"


class ScratchField(TiledBase):
    """Straight scratches (grooves of Gaussian cross-section −d exp(−4 ln2 s²/w²), w the full width at half depth;
    where grooves overlap the deeper wins) as sparse primitives of a cell lattice (module doc).

    Parameters
    ----------
    shape, dx, dy, seed
        As :class:`PSDField`.
    width, depth, length : float, m
        Groove width w, depth d and length (rounded ends).
    density : float, 1/m²
        Mean number of scratches per unit area (Poisson per cell).
    orientation_deg, spread_deg : float, degrees
        Directions uniform in [orientation − spread, orientation + spread].
    variation : float
        Relative spread of each width and depth, uniform in [1 − v, 1 + v].
    cell : float, m, optional
        Cell width (default: the length).
    """

    def __init__(self, shape, dx, dy=None, *, width, depth, length, density, orientation_deg=0.0, spread_deg=0.0,
                 variation=0.0, seed=0, cell=None):
        ny, nx, self.dx, self.dy = shape_spacing(shape[0], shape[1], dx, dy)
        self.shape = (ny, nx)
        if not (width > 0 and depth >= 0 and length > 0 and density >= 0 and 0 <= variation < 1):
            raise FieldError("width, length > 0, depth, density >= 0 and 0 <= variation < 1 are required", "width")
        self.width, self.depth, self.length, self.density = float(width), float(depth), float(length), float(density)
        self.orientation_deg, self.spread_deg, self.variation = float(orientation_deg), float(spread_deg), variation
        self.seed, self.cell = int(seed), float(cell or length)
        if self.density * self.cell ** 2 > 1e5:
            raise FieldError(f"{self.density * self.cell ** 2:.3g} scratches per cell; at most 1e5 (a smaller cell)",
                             "density")
        self._args = dict(width=width, depth=depth, length=length, density=density, orientation_deg=orientation_deg,
                          spread_deg=spread_deg, variation=variation, seed=seed, cell=cell)

    def __reduce__(self):
        import functools

        return (functools.partial(type(self), **self._args), (self.shape, self.dx, self.dy))

    def scratches(self, cx: int, cy: int) -> np.ndarray:
        """The scratches of cell (cx, cy): rows (px, py, θ, w, d), centres in m from the first sample."""
        rng = _cell_rng(self.seed, 1, cx, cy)
        n = rng.poisson(self.density * self.cell ** 2)
        px = (cx + rng.random(n)) * self.cell
        py = (cy + rng.random(n)) * self.cell
        th = np.radians(self.orientation_deg + rng.uniform(-self.spread_deg, self.spread_deg, n))
        v = self.variation
        return np.column_stack([px, py, th, self.width * rng.uniform(1 - v, 1 + v, n),
                                self.depth * rng.uniform(1 - v, 1 + v, n)])

    def _read(self, i0, j0, nx, ny):
        x = (i0 + np.arange(nx)) * self.dx
        y = (j0 + np.arange(ny)) * self.dy
        reach = self.length / 2 + 3 * self.width * (1 + self.variation)
        c = self.cell
        h = np.zeros((ny, nx))
        for cy in range(int(math.floor((y[0] - reach) / c)), int(math.floor((y[-1] + reach) / c)) + 1):
            for cx in range(int(math.floor((x[0] - reach) / c)), int(math.floor((x[-1] + reach) / c)) + 1):
                for px, py, th, w, d in self.scratches(cx, cy):
                    _groove(h, x, y, px, py, th, w, d, self.length)
        return h

    def describe(self) -> str:
        return f"ScratchField(w={self.width:g} m, d={self.depth:g} m, L={self.length:g} m, seed={self.seed})"


def _groove(h, x, y, px, py, th, w, d, length):
    """h = min(h, groove) on the samples within 3 w of the groove (in place)."""
    r = 3 * w
    c, s = math.cos(th), math.sin(th)
    hx, hy = abs(c) * length / 2 + r, abs(s) * length / 2 + r
    ia, ib = np.searchsorted(x, px - hx), np.searchsorted(x, px + hx)
    ja, jb = np.searchsorted(y, py - hy), np.searchsorted(y, py + hy)
    if ia >= ib or ja >= jb:
        return
    X, Y = x[None, ia:ib] - px, y[ja:jb, None] - py
    t = X * c + Y * s                                     # along the groove
    n = -X * s + Y * c                                    # across it
    over = np.maximum(np.abs(t) - length / 2, 0.0)        # beyond an end: distance to the end point
    g = -d * np.exp(-4 * math.log(2) * (n * n + over * over) / (w * w))
    np.minimum(h[ja:jb, ia:ib], g, out=h[ja:jb, ia:ib])


class FlakeField(TiledBase):
    """Metallic-paint flakes: a Voronoi mosaic of flat facets (as :func:`waveoptics.surfaces.flakes`), one flake
    centre uniform in each cell of width *size_flake* (so the mean flake area is size_flake²), slopes Gaussian of
    rms tan(*tilt_deg*) per axis; a sample lies on the plane of its nearest centre."""

    def __init__(self, shape, dx, dy=None, *, size_flake, tilt_deg, seed=0):
        ny, nx, self.dx, self.dy = shape_spacing(shape[0], shape[1], dx, dy)
        self.shape = (ny, nx)
        if not (size_flake > 0 and 0 <= tilt_deg < 60):
            raise FieldError("size_flake > 0 and 0 <= tilt_deg < 60 are required", "size_flake")
        self.size_flake, self.tilt_deg, self.seed = float(size_flake), float(tilt_deg), int(seed)

    def __reduce__(self):
        import functools

        return (functools.partial(type(self), size_flake=self.size_flake, tilt_deg=self.tilt_deg, seed=self.seed),
                (self.shape, self.dx, self.dy))

    def flake(self, cx: int, cy: int) -> tuple[float, float, float, float]:
        """(centre x, centre y, slope x, slope y) of the flake of cell (cx, cy)."""
        rng = _cell_rng(self.seed, 2, cx, cy)
        u = rng.random(2)
        s = rng.normal(0.0, math.tan(math.radians(self.tilt_deg)), 2)
        return (cx + u[0]) * self.size_flake, (cy + u[1]) * self.size_flake, s[0], s[1]

    def _nearest(self, i0, j0, nx, ny):
        """(flakes (m, 4) as :meth:`flake`, index (ny, nx) of each sample's flake, X, Y in m, the flakes' cells
        (m, 2)) of a patch."""
        from scipy.spatial import cKDTree

        c = self.size_flake
        x = (i0 + np.arange(nx)) * self.dx
        y = (j0 + np.arange(ny)) * self.dy
        # a point's nearest centre lies within 2 cells of its own (any centre of its own cell is closer than √2 c)
        cells = [(cx, cy) for cy in range(int(y[0] // c) - 2, int(y[-1] // c) + 3)
                 for cx in range(int(x[0] // c) - 2, int(x[-1] // c) + 3)]
        F = np.array([self.flake(cx, cy) for cx, cy in cells])
        X, Y = np.meshgrid(x, y)
        _, idx = cKDTree(F[:, :2]).query(np.column_stack([X.ravel(), Y.ravel()]))
        return F, idx.reshape(X.shape), X, Y, np.array(cells)

    def _read(self, i0, j0, nx, ny):
        F, idx, X, Y, _ = self._nearest(i0, j0, nx, ny)
        return F[idx, 2] * (X - F[idx, 0]) + F[idx, 3] * (Y - F[idx, 1])

    def region_slopes(self, i0: int, j0: int, i1: int, j1: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(heights, ∂h/∂x, ∂h/∂y) of samples [j0:j1, i0:i1]: each sample's slopes are those of its flake's plane
        (exact; a finite difference across a flake border would see the step between two flakes as a steep facet
        that is not on the surface — the patch NDF of Yan et al. 2016 then shows facets no flake has).

        References
        ----------
        .. [1] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, "Position-normal distributions for efficient
           rendering of specular microstructure", ACM TOG 35(4), 56, 2016 (the patch NDF of a footprint's normals).
        """
        i0, j0, nx, ny = self._check(i0, j0, int(i1) - int(i0), int(j1) - int(j0))
        F, idx, X, Y, _ = self._nearest(i0, j0, nx, ny)
        h = F[idx, 2] * (X - F[idx, 0]) + F[idx, 3] * (Y - F[idx, 1])
        return h, F[idx, 2], F[idx, 3]

    #: the flakes' own plane slopes (:meth:`region_slopes`)
    gives_slopes = True

    def _lattice(self) -> tuple[int, int]:
        """(cells per row, rows) of every cell whose flake can own a sample: cells −2 … ⌊x_max / size⌋ + 2."""
        c = self.size_flake
        return int(((self.shape[1] - 1) * self.dx) // c) + 5, int(((self.shape[0] - 1) * self.dy) // c) + 5

    def plane_table(self) -> np.ndarray:
        """(n_regions, 2) slopes of every flake that can own a sample, row (c_y + 2) n_x + (c_x + 2) for cell
        (c_x, c_y) (the rows :meth:`region_labels` gives)."""
        ncx, ncy = self._lattice()
        return np.array([self.flake(cx - 2, cy - 2)[2:] for cy in range(ncy) for cx in range(ncx)])

    def region_labels(self, i0: int, j0: int, i1: int, j1: int) -> np.ndarray:
        """The row of :meth:`plane_table` (int32) of each sample's flake, samples [j0:j1, i0:i1]."""
        i0, j0, nx, ny = self._check(i0, j0, int(i1) - int(i0), int(j1) - int(j0))
        _, idx, _, _, cells = self._nearest(i0, j0, nx, ny)
        cells = cells[idx]
        return ((cells[..., 1] + 2) * self._lattice()[0] + cells[..., 0] + 2).astype(np.int32)

    def describe(self) -> str:
        return f"FlakeField(size={self.size_flake:g} m, tilt={self.tilt_deg:g} deg, seed={self.seed})"


def brushed(shape, dx, dy=None, seed=0) -> ScratchField:
    """Brushed metal: long grooves (200 µm) within ±2° of the x axis, 0.5 µm wide, 30 nm deep, one every
    ~2 µm across."""
    return ScratchField(shape, dx, dy, width=0.5e-6, depth=30e-9, length=200e-6, density=1 / (2e-6 * 200e-6),
                        orientation_deg=0.0, spread_deg=2.0, variation=0.3, seed=seed, cell=50e-6)


def scratched(shape, dx, dy=None, seed=0) -> ScratchField:
    """Isotropically scratched metal: grooves 30 µm long in every direction, 0.8 µm wide, 60 nm deep, one per
    (10 µm)²."""
    return ScratchField(shape, dx, dy, width=0.8e-6, depth=60e-9, length=30e-6, density=1 / (10e-6) ** 2,
                        orientation_deg=0.0, spread_deg=90.0, variation=0.5, seed=seed, cell=30e-6)


def _flakes(shape, dx, dy=None, seed=0) -> FlakeField:
    return FlakeField(shape, dx, dy, size_flake=5e-6, tilt_deg=8.0, seed=seed)


def _psd(shape, dx, dy=None, seed=0) -> PSDField:
    return PSDField("gaussian", 20e-9, 1e-6, shape, dx, dy, seed=seed)


#: procedural fields by name: factory(shape, dx, dy=None, seed=0)
PROCEDURAL = {"brushed": brushed, "scratched": scratched, "flakes": _flakes, "psd": _psd}


def procedural(name: str, size_m: float, dx: float, seed: int = 0) -> TiledBase:
    """The procedural field *name* (:data:`PROCEDURAL`) of *size_m* × *size_m* at spacing *dx* (m)."""
    if name not in PROCEDURAL:
        raise FieldError(f"procedural field {name!r} is not known; one of {', '.join(PROCEDURAL)}", "surface")
    n = int(round(size_m / dx))
    return PROCEDURAL[name]((n, n), dx, None, seed)
