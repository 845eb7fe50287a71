"""Options shared by the commands that hand the BRDF to a renderer (``export``, ``render``): the two-scale model
of :class:`waveoptics.renderers.requests.RendererModel` (whose fields own the defaults shown here), with one
meaning in both."""
from __future__ import annotations

from ..renderers.requests import RendererModel, field_default
from ..vocabulary import DEFAULT_NANO, DIFFRACTION, DIFFUSE_ALIASES, DIFFUSE_NAMES, PARAMETRIC_NDF_NAMES
from ._common import add_surface
from ._options import option

__all__ = ["add_model", "model_fields", "MODEL_FIELDS"]

#: the model fields the options of :func:`add_model` carry (each option's dest is its field)
MODEL_FIELDS = ("material", "alpha", "alpha_y", "ndf", "nano", "surface", "spacing", "units", "channel",
                "diffraction", "kd", "diffuse", "multiple_scattering", "wavelength_step", "resolution", "exact",
                "scene", "scene_material")


def _d(name):
    return field_default(RendererModel, name)


def add_model(parser) -> None:
    """Add the model options to *parser* (one argument group)."""
    g = parser.add_argument_group("two-scale BRDF")
    option(g, "--material", default=_d("material"), note="a metal gets no diffuse term")
    option(g, "--micro-alpha", dest="alpha", default=_d("alpha"))
    option(g, "--alpha-y", note="ggx, beckmann, epd and sgd")
    option(g, "--ndf", choices=sorted(PARAMETRIC_NDF_NAMES), default=_d("ndf"))
    option(g, "--nano", note=f"'none' for no nano-roughness (the microfacet model); default {DEFAULT_NANO}")
    add_surface(g, note="the nano-scale height field, instead of --nano statistics")
    option(g, "--diffraction", choices=DIFFRACTION, default=_d("diffraction"))
    option(g, "--kd", default=_d("kd"), note="dielectrics only")
    option(g, "--diffuse", choices=sorted(DIFFUSE_NAMES + tuple(DIFFUSE_ALIASES)), default=_d("diffuse"),
           note="disney is burley")
    option(g, "--multiple-scattering", action="store_true", note="off by default")
    g.add_argument("--wavelength-step", default=_d("wavelength_step"), metavar="L",
                   help="largest spacing of the wavelength nodes over 360-830 nm, with unit "
                        f"(default {_d('wavelength_step')}); between nodes the BRDF is linear in λ")
    option(g, "--resolution", default=_d("resolution"),
           note="of the tabulated diffracted lobes (default: from the nano lobe's width, 64-128)")
    g.add_argument("--scene", metavar="FILE.toml",
                   help="take the model from a scene file's material (waveoptics plan/run format: material, "
                        "roughness, ndf, diffuse_albedo, nano) instead of the options above")
    g.add_argument("--scene-material", metavar="NAME",
                   help="which [[materials]] entry of --scene (default the first)")
    g.add_argument("--exact", action="store_true",
                   help="evaluate the diffracted part pointwise (PSD statistics only; ~200x slower)")


def model_fields(args) -> dict:
    """The :class:`~waveoptics.renderers.requests.RendererModel` fields of the options (the --scene file read)."""
    kw = {k: getattr(args, k) for k in MODEL_FIELDS}
    if kw["scene"] is not None:
        from ..planning import scene as scenes

        kw["scene"] = scenes.load(kw["scene"])
    return kw
