"""Requests as Dask tasks: a request from a scene file, its nano roughness per realization (generated once per
worker), and the tokens that identify a run."""
from __future__ import annotations

import functools
import hashlib
import inspect

import numpy as np

from .. import io, surfaces
from ..brdf import twoscale
from ..errors import WaveopticsError
from ..planning.scene import request_of
from ..request import SimulationRequest, make_nano

__all__ = ['case_from_scene', 'surface_digest']

def case_from_scene(sc, *, material: str | None = None, light: str | None = None, **overrides):
    """A :class:`~waveoptics.request.SimulationRequest` (and its nano height field, if any) from a scene of :mod:`waveoptics.planning.scene`.

    Parameters
    ----------
    sc : waveoptics.planning.scene.Scene
        A validated scene (``scene.load(path)``).
    material, light : str, optional
        Names of the scene material and light to use; default the first of each. The light gives the
        illuminant and the incident direction (its first one); the scene's ``accuracy.delta_e``,
        ``output.resolution`` and ``seed`` are used too.
    **overrides
        Request fields that replace the scene's values (e.g. ``resolution=32``); None values are ignored.

    Returns
    -------
    (SimulationRequest, HeightField or None)
        The height field of a nano ``file`` or ``generator`` (loaded or generated here, in the client, with the
        scene's seed); statistics stay text and run on the PSD route.
    """
    req = request_of(sc, material, light, **overrides)
    mat = sc.material(material) if material is not None else sc.materials[0]
    if mat.micro_surface is not None and mat.micro_surface.params:
        raise WaveopticsError(f"{sc.path or sc.name}: material {mat.name!r} micro_surface: tables and sweeps "
                              "read it as a plain path; use a file that states its own spacing and units "
                              "(.npy with its sidecar, .x3p, ...)")
    hf = None
    if mat.nano is not None and mat.nano.kind == "file":
        hf = surfaces.load(mat.nano.path, **mat.nano.params)
    elif mat.nano is not None and mat.nano.kind == "generator":
        params = dict(mat.nano.params)
        model = params.pop("model")
        if "seed" in inspect.signature(surfaces.GENERATORS[model]).parameters:
            params.setdefault("seed", sc.seed)
        hf = surfaces.generate(model, **params)
    return req, hf


def case_token(data) -> str:
    """Deterministic short hash of JSON-able *data* (the identity of a run, used in task keys and on resume)."""
    return hashlib.sha1(io.to_json(data, sort_keys=True).encode()).hexdigest()[:16]


def surface_digest(hf: surfaces.HeightField) -> str:
    """sha1 of a height field's samples, spacing and mask (so a resumed run uses the same surface)."""
    h = hashlib.sha1(np.ascontiguousarray(hf.heights, dtype=np.float64).tobytes())
    h.update(repr((hf.dx, hf.dy)).encode())
    if hf.mask is not None:
        h.update(np.ascontiguousarray(hf.mask).tobytes())
    return h.hexdigest()[:16]


@functools.lru_cache(maxsize=16)
def _generated_nano(spec: str, wavelengths_nm: tuple, solver: str, seed: int):
    # cached per worker process: tasks of the same realization share the generated height field
    return make_nano(spec, np.asarray(wavelengths_nm), solver=solver, seed=seed)


def case_nano(case: SimulationRequest, r: int, wavelengths_nm: np.ndarray, surface=None) -> twoscale.Nano | None:
    """The nano roughness of realization *r*: the given height-field tile, or *case.nano* (seed ``seed + r``).

    Generated height fields are sized from the *whole* wavelength list, never a task's batch, so every batch of
    a realization sees the same surface.
    """
    if surface is not None:
        return make_nano(None, wavelengths_nm, solver=case.solver, surface=surface)
    return _generated_nano(case.nano, tuple(float(x) for x in wavelengths_nm), case.solver, int(case.seed) + int(r))
