"""Renderers: the BRDF taken into Mitsuba 3 (a BSDF plugin), into the RGL tabulated-BSDF format that Mitsuba 3's
and pbrt-v4's ``measured`` models read, and rendered scenes (``waveoptics render``).

Modules: model (the BRDF a renderer receives), mitsuba (loading Mitsuba 3 and the ``waveoptics`` plugin, NumPy in
wavefront mode), mitsuba_native (the ``waveoptics_native`` plugin, in Dr.Jit), drjit_twoscale and drjit_lobes (the
model's tables and formulas in Dr.Jit), rgl (export to the RGL ``.bsdf`` tensor format), scene (Mitsuba scenes),
glints (footprint renders of height fields), sphere (the NumPy sphere renderer: spheres under a directional light or
an environment, tone mapping, exposure), lighting (environment maps importance-sampled by luminance). Mitsuba 3 is
the optional extra ``render``; nothing here imports it
until it is used.
"""
from .model import (SPECTRAL_RANGE_NM, DEFAULT_WAVELENGTH_STEP_NM, wavelength_nodes, renderer_brdf,
    cached_renderer_brdf)
from . import model  # noqa: F401

__all__ = model.__all__
