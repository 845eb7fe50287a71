"""Renderers: the BRDF taken into Mitsuba 3 (a BSDF plugin), into the RGL tabulated-BSDF format that Mitsuba 3's
and pbrt-v4's ``measured`` models read, and rendered scenes (``waveoptics render``).

Modules: model (the BRDF a renderer receives), requests (the typed requests of the render jobs, which own their
defaults), jobs (the sphere render and export jobs: model, Mitsuba renders, outputs written whole), glint_job (the footprint
render job), mitsuba (loading Mitsuba 3 and the ``waveoptics`` plugin, NumPy in
wavefront mode), mitsuba_glass (the ``waveoptics_glass`` plugin: the nano-rough glass with transmission, NumPy in
wavefront mode), mitsuba_native (the ``waveoptics_native`` plugin, in Dr.Jit), drjit_twoscale and drjit_lobes (the
model's tables and formulas in Dr.Jit), rgl (export to the RGL ``.bsdf`` tensor format), scene (Mitsuba scenes),
glints (footprint renders of height fields), sphere (the NumPy sphere renderer: spheres under a directional light or
an environment, tone mapping, exposure), lighting (environment maps importance-sampled by luminance). Mitsuba 3 is
the optional extra ``render``; nothing here imports it
until it is used.

The names below are loaded on first use, so that reading a request's defaults (the command line does while it
builds its parser) imports nothing numerical.
"""
from importlib import import_module

#: public name → the module of this package that defines it
_WHERE = {
    "SPECTRAL_RANGE_NM": "model", "DEFAULT_WAVELENGTH_STEP_NM": "model", "TABLE_CACHE_KIND": "model",
    "wavelength_nodes": "model", "renderer_brdf": "model", "cached_renderer_brdf": "model", "table_key": "model",
    "RendererModel": "requests", "RenderRequest": "requests", "GlintRequest": "requests",
    "field_default": "requests",
    "render_job": "jobs", "RenderResult": "jobs", "build_model": "jobs", "describe_model": "jobs",
    "export_job": "jobs",
    "glints_job": "glint_job", "GlintResult": "glint_job",
}

__all__ = list(_WHERE)


def __getattr__(name):
    if name in _WHERE:
        return getattr(import_module(f"{__name__}.{_WHERE[name]}"), name)
    try:   # a sub-module (``waveoptics.renderers.model``) read as an attribute before it was imported
        return import_module(f"{__name__}.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":   # the sub-module exists and lacks a dependency: say so
            raise
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


def __dir__():
    return sorted(set(globals()) | set(__all__))
