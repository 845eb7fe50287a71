"""Optical constants and Fresnel reflectance.

Files: fresnel (exact s/p/unpolarized and Schlick reflectance, OpenCL twins), database (presets from the
refractiveindex.info database, constant indices, F0 colours; :func:`get_material`).
"""
from .fresnel import *  # noqa: F401,F403
from .database import *  # noqa: F401,F403
from . import fresnel, database  # noqa: F401

__all__ = fresnel.__all__ + database.__all__
