"""Optical constants and Fresnel reflectance.

Files: fresnel (exact s/p/unpolarized and Schlick reflectance, OpenCL twins), database (presets from the
refractiveindex.info database, constant indices, F0 colours; :func:`get_material`), stack (transfer-matrix
reflection and transmission of thin-film stacks), thinfilm (:class:`Stack`, a film stack as a material, and its
grammar ``SUBSTRATE|FILM:THICKNESS``).
"""
from .fresnel import (F_sp, cos2_eta_i, facet_sp_mix, F_facet_polarized, F_facet_sp, F, F0, F_schlick, brewster_angle, F_sp_cl, F_schlick_cl)
from .database import (PolarizedFresnel, RelativeFacetFresnel, MAX_CLAMP_NM, ETA_MEMO_SIZE, IOR_MODULUS, Preset, PRESETS, Material,
    parse_ior, category_from_f0, get_material, data_sets, VISIBLE_NM, search, fresnel_function, ior_text, alias_key)
from .thinfilm import (Stack, parse_stack, GRAMMAR, ROUGHNESS_CORRELATIONS, roughness_correlation,
    with_roughness_correlation, ROUGHNESS_KEY)
from . import fresnel, database, stack, thinfilm  # noqa: F401

__all__ = fresnel.__all__ + database.__all__ + thinfilm.__all__
