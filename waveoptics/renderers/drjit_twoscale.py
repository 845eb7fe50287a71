"""The renderer's two-scale BRDF (:func:`waveoptics.renderers.renderer_brdf`) written with Dr.Jit operations, for
Mitsuba 3's scalar, LLVM and CUDA variants without NumPy in the rendering loop.

:class:`DrJitTwoScale` takes the :class:`waveoptics.brdf.SpectralNodes` model the NumPy plugin evaluates and uploads
its data once: the complex index (or Schlick F0) and F̄ of every wavelength node, the coherent fraction A(θ_d) of
every node on a uniform grid of angles (:data:`A_NODES`), the
Kulla-Conty albedo table, the reflectance-to-RGB matrix and, for a :class:`waveoptics.brdf.TabulatedTwoScaleBRDF`,
its diffracted lobes (with the rim filled as the library reads them), the lobes as sampled and their normalized
CDFs. ``eval`` / ``pdf`` / ``sample`` then repeat the library's arithmetic (the same formulas, brackets and
interpolation; see the sources named in each method) on Dr.Jit arrays: the closed-form coherent part
F(θ_d) G D / (4 cos θ_i cos θ_o) A(θ_d), the diffuse substrate with its Fresnel trade-off, the multiple-scattering
lobe, and the diffracted lobes read bilinearly at the two (four) incidence nodes around ω_i, moved with the specular
direction. Sampling is the library's mixture of the coherent (GGX visible normals, Beckmann D cos θ_m), diffracted
(a cell by binary search in the node's CDF, uniform inside it) and cosine lobes.

Supported: NDFs ``ggx`` and ``beckmann`` (isotropic or anisotropic), shadowing ``smith`` and ``smith-correlated``,
diffuse ``lambert``, ``oren-nayar``, ``burley`` and ``none``, exact (complex index) or F0-only (Schlick) materials,
multiple scattering, nano-roughness through the tabulated lobes or none. Other models (the pointwise ``exact``
evaluation, other NDFs) raise :class:`waveoptics.errors.FieldError`; the NumPy plugin still takes them.

References
----------
.. [1] W. Jakob et al., "Dr.Jit: A Just-In-Time Compiler for Differentiable Rendering", ACM TOG 41(4), 2022.
.. [2] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007 (specular term,
   eq. 20; Beckmann sampling, eq. 28; the reflection Jacobian, eq. 14).
.. [3] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014
   (Λ of GGX eq. 86 and Beckmann eq. 81; G eqs. 98-99).
.. [4] E. Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018 (listing 1).
.. [5] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.2 and §14.2 (Fresnel formulae, conductors).
.. [6] C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH 2017 course.
.. [7] P. Shirley et al., Pacific Graphics 1997 (diffuse-specular coupling); M. Oren, S. K. Nayar, SIGGRAPH 1994;
   B. Burley, SIGGRAPH 2012 course notes.
.. [8] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., §2.4 (remapping the lobe choice).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import FieldError
from .drjit_lobes import DiffractedLobes

__all__ = ['A_NODES', 'NATIVE_NDFS', 'NATIVE_SHADOWINGS', 'DrJitTwoScale', 'unsupported']

#: angles of the uniform grid (0-90°, every 0.05°) on which A(θ_d) is uploaded: it holds the library's own albedo
#: nodes (:data:`waveoptics.scatter.band.ALBEDO_THETAS_DEG`, multiples of 0.05°), between which a conductor's A is
#: linear in θ, so reading it linearly is exact there; a dielectric's smooth A is read within 1e-7
A_NODES = 1801
#: micro NDFs and shadowing terms written in Dr.Jit here
NATIVE_NDFS = ("ggx", "beckmann")
NATIVE_SHADOWINGS = ("smith", "smith-correlated")
_COS_MIN = 1e-7          # the library's COS_MIN (waveoptics.brdf.ndf): floor of the specular denominator's cosines
_TINY = 1e-30            # float32 stand-in for the library's 1e-300 floors


def unsupported(base):
    """None when :class:`DrJitTwoScale` evaluates the two-scale model *base* (``SpectralNodes.base``), else (why,
    the request field that decides it)."""
    from ..brdf import TabulatedTwoScaleBRDF
    from ..brdf.protocol import TwoScaleParts

    if not isinstance(base, TwoScaleParts) or (base._rough and not isinstance(base, TabulatedTwoScaleBRDF)):
        return "the Dr.Jit BSDF needs the tabulated model or no nano-roughness (not exact)", "exact"
    if base.micro.ndf not in NATIVE_NDFS:
        return f"ndf={base.micro.ndf!r} is not in the Dr.Jit BSDF; it has: {', '.join(NATIVE_NDFS)}", "ndf"
    if base.micro.shadowing not in NATIVE_SHADOWINGS:
        return (f"shadowing={base.micro.shadowing!r} is not in the Dr.Jit BSDF; it has: "
                f"{', '.join(NATIVE_SHADOWINGS)}", "shadowing")
    return None


class _G:
    """Per (ω_i, ω_o) quantities shared by every wavelength node."""


class DrJitTwoScale(DiffractedLobes):
    """Dr.Jit evaluation of a renderer's two-scale BRDF (see the module doc).

    Parameters
    ----------
    model : waveoptics.brdf.SpectralNodes
        The model of :func:`waveoptics.renderers.renderer_brdf` (its base a ``TabulatedTwoScaleBRDF`` or a
        ``TwoScaleBRDF`` without nano-roughness).
    mi : module
        ``mitsuba`` with the variant set.
    """

    def __init__(self, model, mi):
        import drjit as dr

        self.dr, self.mi = dr, mi
        self.scalar = mi.variant().startswith("scalar")
        self.model = model
        base = model.base
        self.base = base
        self._check(base)
        nodes = np.asarray(model.wavelengths_nm, dtype=float)
        self.nodes = nodes
        self.J = nodes.size
        self.w_dr = self._upload(nodes)
        ndf, ax, ay = base._micro_args()
        self.ndf, self.ax, self.ay = ndf, float(ax), float(ay)
        self.correlated = base.micro.shadowing == "smith-correlated"
        self._upload_fresnel(base, nodes)
        self._upload_substrate(base, nodes)
        self.rough = bool(base._rough)
        if self.rough:
            self._upload_coherent(base, nodes)
            self._upload_lobes(base)
        self.rgb = np.asarray(model.rgb_matrix, dtype=float)

    # -- upload --------------------------------------------------------------------------------------------
    @staticmethod
    def _check(base):
        why = unsupported(base)
        if why is not None:
            raise FieldError(why[0], why[1])

    def _upload(self, a):
        a = np.ascontiguousarray(np.asarray(a, dtype=np.float64).ravel())
        if self.scalar:
            return a                       # scalar variants compute in Python floats, reading the array per point
        return self.mi.Float(a.astype(np.float32))

    def _upload_fresnel(self, base, nodes):
        mat = base.material
        if base.fresnel == "one":
            self.fresnel = "one"
        elif mat.schlick_only:
            self.fresnel = "schlick"
            self.F0 = np.asarray(mat.F0(nodes), dtype=float)
        else:
            self.fresnel = "exact"
            eta = np.asarray(mat.eta(nodes), dtype=complex)
            self.eta_re, self.eta_im = eta.real.copy(), eta.imag.copy()
        self._per_node = {}

    def _upload_substrate(self, base, nodes):
        from ..brdf.fresnel_terms import F_mean

        self.diffuse = base.diffuse if base._has_diffuse() else "none"
        self.kd, self.diffuse_sigma = float(base.kd), float(base.diffuse_sigma)   # Oren-Nayar σ, rad
        self.diffuse_roughness = float(base.diffuse_roughness)                     # Burley's r
        self.Fbar = np.array([float(F_mean(base._F(float(lam)))) for lam in nodes])
        self.ms = bool(base.multiple_scattering)
        if self.ms:
            t = base._ms_table()
            self.ms_mu, self.ms_E = self._upload(t.mu), self._upload(t.E)
            self.ms_n = int(t.mu.size)
            self.ms_scale = 1.0 / (math.pi * max(1.0 - float(t.E_avg), 1e-12))
            self.Fms = np.array([base._F_ms(float(lam)) for lam in nodes])

    def _upload_coherent(self, base, nodes):
        theta = np.radians(np.linspace(0.0, 90.0, A_NODES))
        c = np.clip(np.cos(theta), 0.0, 1.0)
        A = np.stack([np.asarray(base._A(c, float(lam)), dtype=float) * np.ones(c.size) for lam in nodes])
        self.A_tab = self._upload(A)

    # -- small helpers -------------------------------------------------------------------------------------
    def _gather(self, table, idx):
        """table[idx]: Python indexing in scalar variants, ``dr.gather`` in JIT ones (indices kept in range)."""
        if self.scalar:
            return float(table[int(idx)])
        return self.dr.gather(self.mi.Float, table, self.mi.UInt32(idx))

    def _node_value(self, name, j):
        """Per-node constant *name* at node j: a literal for a Python int j, a gather for a JIT index."""
        arr = getattr(self, name)
        if isinstance(j, (int, np.integer)):
            return float(arr[int(j)])
        key = name
        if key not in self._per_node:
            self._per_node[key] = self._upload(arr)
        return self._gather(self._per_node[key], j)

    def idx(self, x):
        """Float (integral, ≥ 0) → unsigned index: a Python int for Python numbers and in scalar variants."""
        if self.scalar or isinstance(x, (int, float, np.integer, np.floating)):
            return int(x)
        return self.mi.UInt32(x)

    def _mod(self, x, m):
        """x mod m in [0, m) (NumPy's ``mod`` for m > 0)."""
        r = x - m * self.dr.floor(x / m)
        return self.dr.select(r >= m, r - m, r)

    def _interp_sorted(self, xs, n, ys, x):
        """np.interp(x, xs, ys) for ascending *xs* of length n (held at the ends)."""
        dr = self.dr
        if self.scalar:
            b = dr.binary_search(1, n - 1, lambda i: bool(xs[i] <= x))
        else:
            b = dr.binary_search(1, n - 1, lambda i: dr.gather(self.mi.Float, xs, i) <= x)
        a = b - 1
        xa, xb = self._gather(xs, a), self._gather(xs, b)
        t = dr.clip((x - xa) / (xb - xa), 0.0, 1.0)
        return (1.0 - t) * self._gather(ys, a) + t * self._gather(ys, b)

    # -- wavelength nodes (library ``SpectralNodes._brackets``, ``_nearest_index``) --------------------------
    def lambda_bracket(self, lam):
        """(a, b, t): the nodes around λ (nm, clamped to the nodes' range) and the weight of b."""
        dr = self.dr
        if self.J == 1:
            return 0, 0, lam * 0.0
        w = self.w_dr
        lam = dr.clip(lam, float(self.nodes[0]), float(self.nodes[-1]))
        if self.scalar:
            b = int(dr.binary_search(1, self.J - 1, lambda i: bool(w[i] < lam)))
        else:
            b = dr.binary_search(1, self.J - 1, lambda i: dr.gather(self.mi.Float, w, i) < lam)
        a = b - 1
        wa, wb = self._gather(w, a), self._gather(w, b)
        return a, b, (lam - wa) / (wb - wa)

    def nearest_node(self, lam):
        """Index of the node nearest λ (the first of two at equal distance)."""
        dr = self.dr
        a, b, t = self.lambda_bracket(lam)
        if self.J == 1:
            return 0
        wa, wb = self._gather(self.w_dr, a), self._gather(self.w_dr, b)
        lam = dr.clip(lam, float(self.nodes[0]), float(self.nodes[-1]))
        if self.scalar:
            return a if lam - wa <= wb - lam else b
        return dr.select(lam - wa <= wb - lam, a, b)

    # -- Fresnel -------------------------------------------------------------------------------------------
    def F(self, c, j):
        """Unpolarized Fresnel reflectance of node j at cos θ (clamped to [0, 1]): exact (Born & Wolf §1.5.2,
        §14.2, principal branch of cos θ_t as in :func:`waveoptics.materials.fresnel.F_sp`), Schlick, or 1."""
        dr = self.dr
        c = dr.clip(c, 0.0, 1.0)
        if self.fresnel == "one":
            return c * 0.0 + 1.0
        if self.fresnel == "schlick":
            F0 = self._node_value("F0", j)
            return F0 + (1.0 - F0) * (1.0 - c) ** 5
        n, k = self._node_value("eta_re", j), self._node_value("eta_im", j)
        e2r, e2i = n * n - k * k, 2.0 * n * k                      # η²
        s = (1.0 - c * c) / (e2r * e2r + e2i * e2i)
        zr, zi = 1.0 - s * e2r, s * e2i                             # 1 − sin²θ_t = 1 − (1 − c²)/η²
        r = dr.sqrt(zr * zr + zi * zi)
        big = dr.sqrt(dr.maximum(0.5 * (r + dr.abs(zr)), 0.0))     # principal square root, stable form
        safe = dr.select(big > 0, big, 1.0)
        tr = dr.select(zr >= 0, big, dr.abs(zi) / (2.0 * safe))
        ti = dr.select(zr >= 0, zi / (2.0 * safe), dr.select(zi >= 0, big, -big))
        er, ei = n * tr - k * ti, n * ti + k * tr                   # η cos θ_t
        Rs = ((c - er) ** 2 + ei * ei) / dr.maximum((c + er) ** 2 + ei * ei, _TINY)
        pr, pi_ = n * c - tr, k * c - ti                            # η c − cos θ_t
        qr, qi = n * c + tr, k * c + ti
        Rp = (pr * pr + pi_ * pi_) / dr.maximum(qr * qr + qi * qi, _TINY)
        Rs, Rp = dr.clip(Rs, 0.0, 1.0), dr.clip(Rp, 0.0, 1.0)
        # guard (as the library): grazing incidence c = 0 reflects everything
        return dr.select(c <= 0.0, 1.0, 0.5 * (Rs + Rp))

    def A(self, theta, j):
        """Coherent fraction A of node j at the facet incidence θ_d (radians), linear on the uploaded grid
        (1 without nano-roughness)."""
        dr = self.dr
        if not self.rough:
            return theta * 0.0 + 1.0
        x = dr.clip(theta, 0.0, 0.5 * math.pi) * ((A_NODES - 1) / (0.5 * math.pi))
        a = dr.clip(dr.floor(x), 0.0, A_NODES - 2.0)
        t = x - a
        base = self.idx(a) + j * A_NODES
        return (1.0 - t) * self._gather(self.A_tab, base) + t * self._gather(self.A_tab, base + 1)

    # -- micro NDF -----------------------------------------------------------------------------------------
    def D(self, m):
        """D(m) of GGX (Walter 2007 eq. 33; Heitz 2014 eq. 85) or Beckmann (Walter 2007 eq. 25), 1/sr."""
        dr = self.dr
        ax, ay = self.ax, self.ay
        mz = m.z
        if self.ndf == "ggx":
            q = (m.x / ax) ** 2 + (m.y / ay) ** 2 + mz * mz
            return dr.select(mz > 0, 1.0 / (math.pi * ax * ay * q * q), 0.0)
        ok = mz > 1e-20
        inv2 = 1.0 / dr.select(ok, mz * mz, 1.0)
        t = ((m.x / ax) ** 2 + (m.y / ay) ** 2) * inv2
        return dr.select(ok, dr.exp(-t) * inv2 * inv2 / (math.pi * ax * ay), 0.0)

    def Lambda(self, w):
        """Smith Λ(w) of GGX (Heitz 2014 eq. 86) or Beckmann (eq. 81); only used where w_z > 0."""
        dr = self.dr
        wz = dr.select(w.z > 0, w.z, 1.0)
        t = ((self.ax * w.x) ** 2 + (self.ay * w.y) ** 2) / (wz * wz)
        if self.ndf == "ggx":
            return t / (2.0 * (1.0 + dr.sqrt(1.0 + t)))
        pos = t > 0
        a = 1.0 / dr.sqrt(dr.select(pos, t, 1.0))
        lam = 0.5 * (dr.exp(-a * a) / (a * math.sqrt(math.pi)) - (1.0 - dr.erf(a)))
        return dr.select(pos, dr.maximum(lam, 0.0), 0.0)

    def sample_normal(self, wi, u):
        """Microfacet normal: GGX visible normals (Heitz 2018, listing 1), Beckmann D cos θ_m (Walter 2007 eq. 28)."""
        dr, mi = self.dr, self.mi
        ax, ay = self.ax, self.ay
        phi = 2.0 * math.pi * u.y
        if self.ndf == "beckmann":
            r = dr.sqrt(-dr.log(1.0 - u.x))
            return dr.normalize(mi.Vector3f(-ax * r * dr.cos(phi), -ay * r * dr.sin(phi), 1.0))
        vh = dr.normalize(mi.Vector3f(ax * wi.x, ay * wi.y, wi.z))
        lensq = vh.x * vh.x + vh.y * vh.y
        safe = dr.sqrt(dr.select(lensq > 0, lensq, 1.0))
        t1 = mi.Vector3f(dr.select(lensq > 0, -vh.y / safe, 1.0), dr.select(lensq > 0, vh.x / safe, 0.0), 0.0)
        t2 = dr.cross(vh, t1)
        r = dr.sqrt(u.x)
        p1, p2 = r * dr.cos(phi), r * dr.sin(phi)
        s = 0.5 * (1.0 + vh.z)
        p2 = (1.0 - s) * dr.sqrt(dr.maximum(1.0 - p1 * p1, 0.0)) + s * p2
        nh = p1 * t1 + p2 * t2 + dr.sqrt(dr.maximum(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh
        return dr.normalize(mi.Vector3f(ax * nh.x, ay * nh.y, dr.maximum(nh.z, 1e-12)))

    # -- geometry shared by the nodes ----------------------------------------------------------------------
    def geometry(self, wi, wo):
        """Node-independent parts for the pairs (ω_i, ω_o) (library: ``_specular``, ``pdf_reflected``,
        ``_oren_nayar`` / ``_burley``, ``f_ms``)."""
        dr, mi = self.dr, self.mi
        g = _G()
        g.wi, g.wo = wi, wo
        g.up = (wi.z > 0) & (wo.z > 0)
        s = wi + wo
        n = dr.norm(s)
        h = s / dr.maximum(n, _TINY)
        g.cos_d = dr.clip(dr.dot(wi, h), 0.0, 1.0)
        g.theta_d = dr.atan2(dr.norm(dr.cross(wi, h)), dr.dot(wi, h))     # float32: finer than acos near 0
        g.ci, g.co = dr.clip(wi.z, 0.0, 1.0), dr.clip(wo.z, 0.0, 1.0)
        li, lo = self.Lambda(wi), self.Lambda(wo)
        front = (dr.dot(wi, h) > 0) & (dr.dot(wo, h) > 0) & g.up
        if self.correlated:
            G = dr.select(front, 1.0 / (1.0 + li + lo), 0.0)
        else:
            G = dr.select(front, 1.0 / ((1.0 + li) * (1.0 + lo)), 0.0)
        denom = 4.0 * dr.select(g.up, dr.maximum(wi.z, _COS_MIN) * dr.maximum(wo.z, _COS_MIN), 1.0)
        g.spec = dr.select(g.up & (G > 0), G * self.D(h) / denom, 0.0)
        # density of the reflected normal sampler (Walter 2007 eq. 14)
        dot = dr.dot(wi, h)
        ok = g.up & (dot > 0) & (n > 0)
        m = mi.Vector3f(dr.select(ok, h.x, 0.0), dr.select(ok, h.y, 0.0), dr.select(ok, h.z, 1.0))
        if self.ndf == "ggx":
            g1 = dr.select((dr.dot(wi, m) > 0) & (wi.z > 0), 1.0 / (1.0 + li), 0.0)
            pm = dr.select(wi.z > 0, g1 * dr.maximum(dr.dot(wi, m), 0.0) * self.D(m) / dr.select(wi.z > 0, wi.z, 1.0),
                           0.0)
        else:
            pm = self.D(m) * dr.maximum(m.z, 0.0)
        g.pdf_spec = dr.select(ok, pm / (4.0 * dr.select(dot > 0, dot, 1.0)), 0.0)
        g.pdf_cos = dr.maximum(wo.z, 0.0) / math.pi
        g.diffuse = self._diffuse_shape(wi, wo, g)
        if self.ms:
            g.E_i = self._interp_sorted(self.ms_mu, self.ms_n, self.ms_E, g.ci)
            E_o = self._interp_sorted(self.ms_mu, self.ms_n, self.ms_E, g.co)
            g.ms = dr.select((g.ci > 0) & (g.co > 0), (1.0 - g.E_i) * (1.0 - E_o) * self.ms_scale, 0.0)
        if self.rough:
            self._lobe_frame(g)
        return g

    def _diffuse_shape(self, wi, wo, g):
        """The diffuse term before its Fresnel trade-off: Lambert / Oren-Nayar (kd/π)(A + B proj/cmax) or
        Burley (library ``_oren_nayar``, ``_burley``)."""
        dr = self.dr
        if self.diffuse == "none":
            return None
        kd = self.kd
        if self.diffuse == "burley":
            r = self.diffuse_roughness
            fd90 = 0.5 + 2.0 * r * g.cos_d * g.cos_d
            val = kd / math.pi * (1.0 + (fd90 - 1.0) * (1.0 - g.ci) ** 5) * (1.0 + (fd90 - 1.0) * (1.0 - g.co) ** 5)
            return dr.select(g.up, val, 0.0)
        sigma = self.diffuse_sigma if self.diffuse == "oren-nayar" else 0.0
        s2 = sigma * sigma
        A = 1.0 - 0.5 * s2 / (s2 + 0.33)
        B = 0.45 * s2 / (s2 + 0.09)
        cmax = dr.select(g.up, dr.maximum(wi.z, wo.z), 1.0)
        proj = dr.maximum(0.0, wi.x * wo.x + wi.y * wo.y)
        return dr.select(g.up, kd / math.pi * (A + B * proj / cmax), 0.0)

    # -- one wavelength node -------------------------------------------------------------------------------
    def f_parts(self, g, j):
        """(c, F(θ_d), rest) of node j: f = c F(θ_d) + rest, c = G D A / (4 cos θ_i cos θ_o) the coherent part
        without its Fresnel factor, rest the diffracted, diffuse and multiple-scattering parts (1/sr)."""
        coh, F, rest, diffracted = self.f_terms(g, j)
        return coh, F, rest + diffracted

    def f_terms(self, g, j):
        """(c, F(θ_d), rest, diffracted) of node j: f = c F(θ_d) + rest + diffracted, as :meth:`f_parts` with the
        diffracted part (0 without nano-roughness) apart from the diffuse and multiple-scattering ones (1/sr)."""
        dr = self.dr
        coh = g.spec * self.A(g.theta_d, j)
        rest = g.spec * 0.0
        if g.diffuse is not None:
            Fi, Fo = self.F(g.ci, j), self.F(g.co, j)
            t = 1.0 - self._node_value("Fbar", j)
            rest = rest + g.diffuse * dr.select(t > 0, (1.0 - Fi) * (1.0 - Fo) / dr.select(t > 0, t, 1.0), 0.0)
        if self.ms:
            rest = rest + g.ms * self._node_value("Fms", j)
        diffracted = self.f_diffraction(g, j) if self.rough else g.spec * 0.0
        return coh, self.F(g.cos_d, j), rest, diffracted

    def f_node(self, g, j):
        """f (1/sr) of node j at the pairs of *g* (library ``TwoScaleParts._parts``)."""
        coh, F, rest = self.f_parts(g, j)
        return coh * F + rest

    def probs(self, wi, j):
        """Lobe probabilities (coherent, diffracted, cosine) of node j (library ``TwoScaleParts._probs``)."""
        dr = self.dr
        ci = dr.clip(wi.z, 0.0, 1.0)
        Fi = self.F(ci, j)
        A = self.A(dr.atan2(dr.sqrt(wi.x * wi.x + wi.y * wi.y), wi.z), j)
        d = ci * 0.0
        if self.diffuse != "none":
            d = d + self.kd * (1.0 - Fi)
        if self.ms:
            E_i = self._interp_sorted(self.ms_mu, self.ms_n, self.ms_E, ci)
            d = d + (1.0 - E_i) * self._node_value("Fms", j)
        total = dr.maximum(Fi + d, _TINY)
        return Fi * A / total, Fi * (1.0 - A) / total, d / total

    def pdf_node(self, g, j):
        """Density (1/sr) of node j's sampler (library ``TwoScaleParts._pdf1``)."""
        pc, pn, pd = self.probs(g.wi, j)
        out = pc * g.pdf_spec + pd * g.pdf_cos
        if self.rough:
            out = out + pn * self.pdf_diffraction(g, j)
        return out

    def sample_node(self, wi, u, j):
        """ω_o drawn by node j's sampler from u (2-D; u.x picks the lobe and is remapped) (library
        ``TwoScaleParts._sample1`` with :func:`waveoptics.brdf.lobe_choice`); below the surface when invalid."""
        dr, mi = self.dr, self.mi
        u0 = u.x
        pc, pn, pd = self.probs(wi, j)
        tot = pc + pn + pd
        tot = dr.select(tot > 0, tot, 1.0)
        c0, c1 = pc / tot, (pc + pn) / tot
        sel_n = (u0 >= c0) & (u0 < c1)
        sel_d = u0 >= c1
        lo = dr.select(sel_d, c1, dr.select(sel_n, c0, 0.0))
        hi = dr.select(sel_d, 1.0, dr.select(sel_n, c1, c0))
        width = hi - lo
        ur = dr.select(width > 0, (u0 - lo) / dr.select(width > 0, width, 1.0), 0.5)
        ur = dr.clip(ur, 0.0, 0.99999994)
        uu = mi.Point2f(ur, u.y)
        m = self.sample_normal(wi, uu)
        wo = 2.0 * dr.dot(wi, m) * m - wi
        r = dr.sqrt(ur)
        phi = 2.0 * math.pi * u.y
        cosv = mi.Vector3f(r * dr.cos(phi), r * dr.sin(phi), dr.sqrt(dr.maximum(1.0 - ur, 0.0)))
        wo = dr.select(sel_d, cosv, wo)
        if self.rough:
            wo = dr.select(sel_n, self.sample_diffraction(wi, uu, j), wo)
        return wo
