"""Mitsuba 3 plugin ``waveoptics_native``: the two-scale BSDF evaluated with Dr.Jit (no NumPy per sample).

It takes the parameters of the ``waveoptics`` plugin (:func:`waveoptics.renderers.mitsuba.plugin_parameters`),
builds the same :func:`waveoptics.renderers.renderer_brdf` model and evaluates it through
:class:`waveoptics.renderers.drjit_twoscale.DrJitTwoScale`, so it runs in scalar, LLVM and CUDA variants in
Mitsuba's own (symbolic) mode, where the NumPy plugin needs wavefront mode. Values, conventions and sampling are
those of the ``waveoptics`` plugin:

* spectral variants: f at the path's wavelengths (linear between nodes), sampled and its density taken at the node
  nearest the hero wavelength;
* mono variants: the luminance of the RGB value;
* RGB variants: f in linear sRGB (Σ_j f(λ_j) M_j), sampled from the equal-weight mixture of the nodes (the first
  number picks a node and is remapped, pbrt-v4 §2.4).

As in the ``waveoptics`` plugin, sampling draws on ``sample2`` only (its first number chooses the node and the lobe,
remapped each time); ``sample1`` is not used.

* polarized spectral variants: a Mueller matrix whose (0, 0) element is the unpolarized f cos θ_o.

  - The coherent part polarizes as a mirror facet does (Fresnel amplitudes of the complex index, in roughconductor's
    frames), so without nano-roughness it is Mitsuba's polarized roughconductor.
  - The diffracted part is its scalar lobe times the normalized Mueller matrix M(J)/M(J)₀₀ of the first-order
    (Rayleigh-Rice) Jones matrix J = [[q_ss, q_ps], [q_sp, q_pp]] at (ω_i, ω_o) in the macro s/p frames
    (s = ẑ × ω, p = k × s), rotated onto Mitsuba's Stokes bases (:mod:`waveoptics.renderers.drjit_polar`): a
    non-depolarizing Mueller matrix, the same for a Kirchhoff or a Rayleigh-Rice table (the small-slope
    polarization kernel; see :func:`_diffracted_mueller`). On a dielectric its p light vanishes at the mirror
    direction at Brewster's angle, as the coherent part's does.
  - The diffuse substrate and the multiple-scattering lobe stay depolarizers (their polarization is not modelled).

Mitsuba's ``eval`` is f cos θ_o; ``si.wi`` is the first direction, ``wo`` the second.

References
----------
.. [1] W. Jakob, S. Speierer, N. Roussel, M. Nimier-David et al., *Mitsuba 3 renderer*, 2022,
   https://mitsuba-renderer.org (``mi.BSDF``, ``mi.register_bsdf``, ``mitsuba.chi2``).
.. [2] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 2023, §2.4 (sample remapping).
.. [3] T. A. Germer, Appl. Opt. 36(33), 8798–8805, 1997 (the first-order Jones matrix of a rough surface);
   R. A. Chipman, W. S. T. Lam, G. Young, *Polarized Light and Optical Systems*, CRC 2018, §6.9 (its Mueller
   matrix).
"""
from __future__ import annotations

from ..errors import WaveopticsError
from .drjit_polar import mueller_from_jones, rayleigh_rice_jones, sp_frames
from .drjit_twoscale import DrJitTwoScale, unsupported
from .mitsuba import model_from, load_mitsuba

__all__ = ['NATIVE_PLUGIN_NAME', 'register_native', 'native_tables', 'native_unsupported']

#: name of the Dr.Jit BSDF plugin in scene descriptions
NATIVE_PLUGIN_NAME = "waveoptics_native"

_TABLES: dict = {}


def native_unsupported(model, variant: str):
    """None when this plugin renders *model* (a :func:`waveoptics.renderers.renderer_brdf` model) in the Mitsuba
    *variant* (by name), else (why, the request field that decides it): the model's NDF, shadowing and tabulation
    (:func:`waveoptics.renderers.drjit_twoscale.unsupported`), and in polarized variants a spectral variant and a
    material with a complex index."""
    why = unsupported(model.base)
    if why is not None:
        return why
    if "polarized" in variant:
        if "spectral" not in variant:
            return f"the {NATIVE_PLUGIN_NAME} BSDF has no polarized monochrome form ({variant})", "variant"
        base = model.base
        if base.fresnel == "one" or base.material.schlick_only:
            return (f"the polarized {NATIVE_PLUGIN_NAME} BSDF needs a material with a complex index (its Fresnel "
                    "amplitudes), not F0 only", "material")
    return None


def native_tables(model, mi) -> DrJitTwoScale:
    """The Dr.Jit tables of *model* for the variant set in *mi*, uploaded once per (model, variant) (Mitsuba's χ²
    adapter builds the plugin on every call)."""
    key = (id(model), mi.variant())
    if key not in _TABLES:
        _TABLES[key] = (model, DrJitTwoScale(model, mi))
    return _TABLES[key][1]


def _mueller(mi, dr, tab, ctx, g, si, wo):
    """Polarized variants: the Mueller matrix of f (cos θ_o not applied).

    * The coherent part polarizes by the complex Fresnel amplitudes of each node
      (``mi.mueller.specular_reflection``), in the frames Mitsuba's roughconductor uses (s axes normal to the facet's
      plane of reflection, rotated onto the Stokes bases of −ŵ_o and ŵ_i).
    * The diffracted part is its scalar value times the normalized Mueller matrix M(J)/M(J)₀₀ of the first-order
      Jones matrix J of each node's permittivity at the pair (:func:`_diffracted_mueller`), in the macro s/p frames
      rotated onto the same Stokes bases.
    * The diffuse and multiple-scattering parts are depolarizers (their polarization is not modelled here).

    References
    ----------
    .. [1] W. Jakob et al., Mitsuba 3, ``src/bsdfs/roughconductor.cpp`` (the frames) and ``mueller.h``
       (``specular_reflection``, ``rotate_mueller_basis``, ``stokes_basis``).
    .. [2] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.2 and §14.2 (Fresnel amplitudes).
    """
    radiance = ctx.mode == mi.TransportMode.Radiance
    wo_hat, wi_hat = (wo, si.wi) if radiance else (si.wi, wo)
    h = dr.normalize(si.wi + wo)
    cos_d = dr.dot(wo_hat, h)
    s_in, s_out = dr.cross(h, -wo_hat), dr.cross(h, wi_hat)
    collinear = dr.all(s_in == mi.Vector3f(0.0))
    s_in = dr.select(collinear, mi.Vector3f(1.0, 0.0, 0.0), dr.normalize(s_in))
    s_out = dr.select(collinear, mi.Vector3f(1.0, 0.0, 0.0), dr.normalize(s_out))
    in_basis, out_basis = mi.mueller.stokes_basis(-wo_hat), mi.mueller.stokes_basis(wi_hat)
    jones = _jones_parts(mi, dr, wo_hat, wi_hat) if tab.rough else None
    entries = [[[] for _ in range(4)] for _ in range(4)]
    for i in range(4):
        a, b, t = tab.lambda_bracket(si.wavelengths[i])
        Mc, Md, dep = 0.0, 0.0, 0.0
        for j, w in ((a, 1.0 - t), (b, t)):
            coh, _, rest, diffracted = tab.f_terms(g, j)
            eta = mi.Complex2f(tab._node_value("eta_re", j), tab._node_value("eta_im", j))
            Mc = Mc + mi.mueller.specular_reflection(cos_d, eta) * (w * coh)
            dep = dep + w * rest
            if jones is not None:
                Md = Md + _diffracted_mueller(mi, dr, tab, jones, j) * (w * diffracted)
        M = mi.mueller.rotate_mueller_basis(Mc, -wo_hat, s_in, in_basis, wi_hat, s_out, out_basis)
        if jones is not None:
            M = M + mi.mueller.rotate_mueller_basis(Md, -wo_hat, jones[1], in_basis, wi_hat, jones[2], out_basis)
        M = M + mi.mueller.depolarizer(dep)
        for r in range(4):
            for c in range(4):
                entries[r][c].append(M[r][c])
    out = dr.zeros(mi.Spectrum, dr.width(cos_d))
    for r in range(4):
        for c in range(4):
            out[r, c] = mi.UnpolarizedSpectrum(*entries[r][c])
    return out


def _jones_parts(mi, dr, w_light, w_view):
    """The node-independent inputs of :func:`_diffracted_mueller`: (the pair in the library's order (ω_i towards
    the light, ω_o towards the viewer), its :func:`waveoptics.renderers.drjit_polar.sp_frames`), and the s axes of
    the incident and scattered frames as ``mi.Vector3f``."""
    frames = sp_frames(dr, w_light, w_view)
    (six, siy, _), (sox, soy, _), _ = frames
    return (w_light, w_view, frames), mi.Vector3f(six, siy, 0.0), mi.Vector3f(sox, soy, 0.0)


def _diffracted_mueller(mi, dr, tab, jones, j):
    """Normalized Mueller matrix M(J)/M(J)₀₀ of node j's first-order Jones matrix J at the pair (frames: the s axes
    of :func:`waveoptics.renderers.drjit_polar.sp_frames`, p = k × s).

    The diffracted lobe of the two-scale model is first order in the nano heights: its field is the deterministic
    Jones matrix J(ω_i, ω_o) times one random scalar (the height spectrum at the Bragg frequency), so its Mueller
    matrix is the (PSD-weighted) pure Mueller matrix of J, and the scalar lobe (Kirchhoff or Rayleigh-Rice tables)
    keeps its own (0, 0) value. J is Rayleigh-Rice's (Germer's q factors) for both lobes: the first order of the
    small-slope approximation, which describes nano-roughness, has perturbation theory's polarization kernel;
    Kirchhoff's tangent-plane polarization (the Fresnel amplitudes of the stationary facet) is only right near the
    mirror direction, where the two agree in the plane of incidence (both vanish for p light at Brewster's angle).

    References
    ----------
    .. [1] T. A. Germer, Appl. Opt. 36(33), 8798–8805, 1997 (q factors); J. M. Elson, J. M. Bennett, Opt. Eng.
       18(2), 116–124, 1979.
    .. [2] A. G. Voronovich, *Wave Scattering from Rough Surfaces*, 2nd ed., Springer 1999, ch. 6 (small-slope
       approximation; its first order is perturbation theory's kernel).
    .. [3] R. A. Chipman, W. S. T. Lam, G. Young, *Polarized Light and Optical Systems*, CRC 2018, §6.9
       (Mueller matrix of a Jones matrix).
    """
    (wi, wo, frames), _, _ = jones
    n, k = tab._node_value("eta_re", j), tab._node_value("eta_im", j)
    eps = (n * n - k * k, 2.0 * n * k)                          # ε = (n + iκ)², κ ≥ 0 (e^{−iωt})
    M = mueller_from_jones(rayleigh_rice_jones(dr, wi, wo, eps, frames))
    m00 = M[0][0]
    ok = m00 > 0
    inv = 1.0 / dr.select(ok, m00, 1.0)      # guard: a vanishing J (not for ε ≠ 1) is left a depolarizer
    vals = [dr.select(ok, M[r][c] * inv, 1.0 if r == c == 0 else 0.0) for r in range(4) for c in range(4)]
    return mi.Matrix4f(*vals)


def _spectrum(mi, tab, g, si):
    """f (not × cos) as a mi.Spectrum: interpolated between the wavelength nodes in spectral variants, the nodes'
    RGB weights in RGB variants, the luminance in mono ones."""
    if mi.is_spectral:
        out = []
        for i in range(4):
            a, b, t = tab.lambda_bracket(si.wavelengths[i])
            out.append((1.0 - t) * tab.f_node(g, a) + t * tab.f_node(g, b))
        return mi.Spectrum(*out)
    rgb = [0.0, 0.0, 0.0]
    for j in range(tab.J):
        fj = tab.f_node(g, j)
        rgb = [rgb[c] + fj * float(tab.rgb[j, c]) for c in range(3)]
    if "mono" in mi.variant():   # the luminance of linear sRGB (ITU-R BT.709), as Mitsuba's mono variants
        return mi.Spectrum(0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2])
    return mi.Spectrum(*rgb)


def _pdf_value(mi, tab, g, si):
    """The sampling density (1/sr): of the node nearest the path's first wavelength, or the mean over the nodes in
    RGB variants (which pick a node uniformly)."""
    if mi.is_spectral:
        return tab.pdf_node(g, tab.nearest_node(si.wavelengths[0]))
    total = 0.0
    for j in range(tab.J):
        total = total + tab.pdf_node(g, j)
    return total / tab.J


def _sample_direction(mi, dr, tab, wi, sample2, si):
    """ω_o sampled from one wavelength node's lobe: the node nearest the path's first wavelength, or (RGB) a node
    picked by sample2.x, which is remapped (as the library's SpectralNodes.sample_rgb)."""
    if mi.is_spectral:
        return tab.sample_node(wi, sample2, tab.nearest_node(si.wavelengths[0]))
    x = sample2.x * tab.J
    j = dr.minimum(dr.floor(x), tab.J - 1.0)
    u0 = dr.clip(x - j, 0.0, 0.99999994)
    return tab.sample_node(wi, mi.Point2f(u0, sample2.y), tab.idx(j))


def _native_class(mi, fixed_model=None):
    import drjit as dr

    polarized = mi.is_polarized

    class WaveopticsNativeBSDF(mi.BSDF):
        """waveoptics two-scale BRDF in Dr.Jit (see :mod:`waveoptics.renderers.mitsuba_native`)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            items = [(k, props[k]) for k in props.keys()]
            if fixed_model is not None and any(k != "id" for k, _ in items):
                raise WaveopticsError("this BSDF holds a fixed model and takes no parameters; got "
                                      f"{', '.join(k for k, _ in items if k != 'id')}")
            self.model = fixed_model if fixed_model is not None else model_from(items)
            self.parameters = dict(items)
            self.tab = native_tables(self.model, mi)
            if polarized and self.tab.fresnel != "exact":
                raise WaveopticsError(f"the polarized {NATIVE_PLUGIN_NAME} BSDF needs a material with a complex "
                                      "index (its Fresnel amplitudes), not F0 only")
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            if self.model.base._has_diffuse():
                flags = flags | mi.BSDFFlags.DiffuseReflection
            self.m_components = [flags]
            self.m_flags = flags

        def _f(self, g, si):
            return _spectrum(mi, self.tab, g, si)

        def _mueller(self, ctx, g, si, wo):
            return _mueller(mi, dr, self.tab, ctx, g, si, wo)

        def _pdf(self, g, si):
            return _pdf_value(mi, self.tab, g, si)

        @staticmethod
        def _enabled(ctx):
            return ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)

        def eval(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Spectrum(0.0)
            g = self.tab.geometry(si.wi, wo)
            f = self._mueller(ctx, g, si, wo) if polarized else self._f(g, si)
            return dr.select(active & g.up, f * dr.maximum(wo.z, 0.0), 0.0)

        def pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Float(0.0)
            g = self.tab.geometry(si.wi, wo)
            return dr.select(active, self._pdf(g, si), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Spectrum(0.0), mi.Float(0.0)
            g = self.tab.geometry(si.wi, wo)
            f = self._mueller(ctx, g, si, wo) if polarized else self._f(g, si)
            return (dr.select(active & g.up, f * dr.maximum(wo.z, 0.0), 0.0),
                    dr.select(active, self._pdf(g, si), 0.0))

        def sample(self, ctx, si, sample1, sample2, active=True):
            tab = self.tab
            bs = dr.zeros(mi.BSDFSample3f)
            if not self._enabled(ctx):
                return bs, mi.Spectrum(0.0)
            wi = si.wi
            wo = _sample_direction(mi, dr, tab, wi, sample2, si)
            up = (wi.z > 0) & (wo.z > 0)
            wo_ok = dr.select(up, wo, mi.Vector3f(0.0, 0.0, 1.0))
            g = tab.geometry(wi, wo_ok)
            p = self._pdf(g, si)
            ok = up & (p > 0) & active
            bs.wo = wo
            bs.pdf = dr.select(ok, p, 0.0)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            f = self._mueller(ctx, g, si, wo_ok) if polarized else self._f(g, si)
            weight = f * (wo_ok.z / dr.select(ok, p, 1.0))
            return bs, dr.select(ok, weight, 0.0)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return f"WaveopticsNativeBSDF[{', '.join(f'{k}={v!r}' for k, v in self.parameters.items())}]"

    return WaveopticsNativeBSDF


def register_native(variant: str | None = None, model=None, name: str = NATIVE_PLUGIN_NAME):
    """Register the ``waveoptics_native`` BSDF with Mitsuba 3 for *variant* (default: the variant already set) and
    return the ``mitsuba`` module. Unlike :func:`waveoptics.renderers.mitsuba.register` it leaves Dr.Jit's
    symbolic loops and calls on.

    Parameters
    ----------
    variant : str, optional
        Mitsuba variant to set first.
    model : waveoptics.brdf.SpectralNodes, optional
        A model built elsewhere (any :class:`waveoptics.brdf.TabulatedTwoScaleBRDF` at wavelength nodes, e.g. of
        a height field): the plugin *name* then renders it and takes no parameters.
    name : str
        Plugin name in scene descriptions.
    """
    if variant is not None:
        mi = load_mitsuba(variant)
    else:
        import mitsuba as mi
    if mi.is_polarized and not mi.is_spectral:
        raise WaveopticsError(f"the {NATIVE_PLUGIN_NAME} BSDF has no polarized monochrome form; use a spectral "
                              f"variant instead of {mi.variant()!r}")
    cls = _native_class(mi, model)
    mi.register_bsdf(name, lambda props: cls(props))
    return mi
