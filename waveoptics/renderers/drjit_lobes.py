"""The diffracted lobes of a :class:`waveoptics.brdf.TabulatedTwoScaleBRDF` in Dr.Jit: their upload, their
bilinear read relative to the specular direction, and the sampler of the nearest node's lobe with its density.

:class:`DiffractedLobes` is the half of :class:`waveoptics.renderers.drjit_twoscale.DrJitTwoScale` that reads the
tables; it repeats, on Dr.Jit arrays, ``TabulatedTwoScaleBRDF._f_diffraction`` (an isotropic table turned about the
axis normal to the plane of incidence by θ_i − θ_k; an anisotropic analytic micro NDF's read at each node's exit
with (ω_i, ω_o)'s half-vector, :func:`waveoptics.brdf.tabulated_reads.half_vector_exit`; other tables shifted
in direction cosines to ω_i's mirror point; nodes beyond their horizon drop out of the blend), ``_lookup``
(cell-centred bilinear stencil, ``DirectionGrid.bilinear``, on the rim-filled table), ``_with_rim`` (the rim
tables towards the horizon, :mod:`waveoptics.brdf.tabulated_rim`), ``_sample_diffraction`` (a cell by the node's CDF, uniform in
it) and ``_pdf_diffraction``.

References
----------
.. [1] J. E. Harvey, "Light-scattering characteristics of optical surfaces", PhD thesis, University of Arizona,
   1976 (shift-invariance of scattering in direction cosines).
.. [2] W. Jakob et al., "Dr.Jit: A Just-In-Time Compiler for Differentiable Rendering", ACM TOG 41(4), 2022
   (``gather``, ``binary_search``).
"""
from __future__ import annotations

import math

import numpy as np

from ..brdf.tabulated_reads import half_vector_exit
from ..brdf.tabulated_rim import RIM_BLEND_DEG, RIM_LOG_FLOOR, RIM_THETA_DEG, pchip_between

__all__ = ['DiffractedLobes']


class DiffractedLobes:
    """Upload and Dr.Jit reading of the tabulated diffracted lobes (a base of
    :class:`waveoptics.renderers.drjit_twoscale.DrJitTwoScale`, whose helpers ``_upload``, ``_gather``, ``idx``,
    ``_mod`` and attributes ``dr``, ``mi``, ``scalar``, ``J`` it uses)."""

    def _upload_lobes(self, base):
        tab = base._table
        grid = tab["grid"]
        self.grid = (float(grid.u_range[0]), float(grid.v_range[0]), float(grid.du), float(grid.dv),
                     int(grid.n_u), int(grid.n_v))
        diff = np.asarray(tab["diffraction"], dtype=float)
        self.P, self.K = diff.shape[0], diff.shape[1]
        self.thetas = [float(x) for x in tab["thetas"]]
        self.phis = [float(x) for x in tab["phis"]]
        self.rotate = self.P == 1 and base.isotropic
        self.half = not self.rotate and base.half_vector_read   # read by the half-vector (``half_vector_exit``)
        self.lookup = self._upload(base._lookup_table())
        rim = tab.get("rim")   # (Q, K, J, n_cos, n_phi): one set per rim light azimuth node, in its light's frame
        self.rim = None if rim is None else self._upload(np.asarray(rim, dtype=float))
        self.Q = None if rim is None else int(rim.shape[0])
        self.rim_shape = None if rim is None else tuple(int(n) for n in rim.shape[-2:])
        self.lobe = self._upload(diff)
        flat = diff.reshape(diff.shape[:3] + (-1,))
        cdf = np.cumsum(flat, axis=-1)
        total = cdf[..., -1]
        self.cdf = self._upload(cdf / np.where(total > 0, total, 1.0)[..., None])
        self.total = self._upload(total)

    # -- the diffracted part -------------------------------------------------------------------------------
    def _lobe_frame(self, g):
        """θ_i's bracketing nodes, φ nodes, and the rotation into the table's frame (library
        ``TabulatedTwoScaleBRDF._f_diffraction``, ``_frame``, ``_table_rotation``)."""
        dr = self.dr
        wi, wo = g.wi, g.wo
        g.theta_i = dr.atan2(dr.sqrt(wi.x * wi.x + wi.y * wi.y), wi.z)   # float32: finer than acos near 0
        g.phi_i = dr.atan2(wi.y, wi.x)
        g.rot = (g.phi_i - self.phis[0]) if self.rotate else g.phi_i * 0.0
        g.wo_r, g.wi_r = _rotate(self.mi, dr, wo, g.rot), _rotate(self.mi, dr, wi, g.rot)
        # the rim tables' frame: azimuths from the light's (library ``_f_diffraction_nodes``)
        g.wo_l = g.wo_r if self.rotate or self.rim is None else _rotate(self.mi, dr, wo, g.phi_i)

    def _theta_bracket(self, theta):
        """(a, b, t) of np.interp(θ, θ_nodes, arange) as in the library's ``_bracket``: Python node indices are
        unrolled, so a, b are per-point indices into :attr:`thetas`."""
        dr = self.dr
        K = self.K
        if K == 1:
            return [(0, 1.0)]
        a = theta * 0.0
        for k in range(1, K):
            a = a + dr.select(theta >= self.thetas[k], 1.0, 0.0)
        a = dr.minimum(a, K - 2.0)
        ta = self._gather_list(self.thetas, a)
        tb = self._gather_list(self.thetas, a + 1.0)
        t = dr.clip((theta - ta) / (tb - ta), 0.0, 1.0)
        return a, t

    def _gather_list(self, values, idx):
        """values[idx] for a short Python list and a float index (an unrolled select chain)."""
        dr = self.dr
        out = idx * 0.0 + values[0]
        for i in range(1, len(values)):
            out = dr.select(idx >= i - 0.5, values[i], out)
        return out

    def _phi_nodes(self, phi_i):
        """[(p, weight)] of the azimuth nodes around φ_i (library ``_frame``)."""
        dr = self.dr
        if self.P == 1:
            return [(0.0, 1.0)]
        step = 2.0 * math.pi / self.P
        f = self._mod(phi_i, 2.0 * math.pi) / step
        fl = dr.floor(f)
        t = f - fl
        a = self._mod(fl, float(self.P))
        return [(a, 1.0 - t), (self._mod(a + 1.0, float(self.P)), t)]

    def _lookup(self, table, p, k, j, u, v):
        """Cell-centred bilinear read (clamped within half a cell of the edge, 0 beyond; library
        ``DirectionGrid.bilinear``) of the lobe of φ node p, θ node k, wavelength node j."""
        dr = self.dr
        u0, v0, du, dv, nu, nv = self.grid
        fu = (u - u0) / du - 0.5
        fv = (v - v0) / dv - 0.5
        ok = (fu > -0.5) & (fu < nu - 0.5) & (fv > -0.5) & (fv < nv - 0.5)
        j0 = dr.clip(dr.floor(fu), 0.0, nu - 2.0)
        k0 = dr.clip(dr.floor(fv), 0.0, nv - 2.0)
        av, au = dr.clip(fv - k0, 0.0, 1.0), dr.clip(fu - j0, 0.0, 1.0)
        # integer arithmetic: the tables hold more cells than float32 counts exactly
        node = (self.idx(p) * self.K + self.idx(k)) * self.J + j
        base = node * (nu * nv) + self.idx(k0) * nu + self.idx(j0)
        val = ((1.0 - av) * ((1.0 - au) * self._gather(table, base) + au * self._gather(table, base + 1))
               + av * ((1.0 - au) * self._gather(table, base + nu) + au * self._gather(table, base + nu + 1)))
        return dr.select(ok, val, 0.0)

    def f_diffraction(self, g, j):
        """The diffracted part of node j (library ``TabulatedTwoScaleBRDF._f_diffraction``)."""
        dr = self.dr
        brk = self._theta_bracket(g.theta_i)
        ks = [(0.0, 1.0)] if self.K == 1 else [(brk[0], 1.0 - brk[1]), (brk[0] + 1.0, brk[1])]
        num, den = g.cos_d * 0.0, g.cos_d * 0.0
        dx, dy = g.wo_r.x + g.wi_r.x, g.wo_r.y + g.wi_r.y
        for p, w_p in self._phi_nodes(g.phi_i):
            for k, w_k in ks:
                th_k = self._gather_list(self.thetas, k) if self.K > 1 else self.thetas[0]
                scale = 1.0
                if self.rotate:
                    beta = g.theta_i - th_k
                    cb, sb = dr.cos(beta), dr.sin(beta)
                    uu, vv = g.wo_r.x * cb + g.wo_r.z * sb, g.wo_r.y
                    inside = -g.wo_r.x * sb + g.wo_r.z * cb > 0
                else:
                    ph_p = (self._gather_list(self.phis, p) if self.P > 1 else self.phis[0]) + th_k * 0.0
                    if self.half:   # the node's exit with (ω_i, ω_o)'s half-vector
                        wn = (dr.sin(th_k) * dr.cos(ph_p), dr.sin(th_k) * dr.sin(ph_p), dr.cos(th_k))
                        uu, vv, zz, scale = half_vector_exit((g.wi.x, g.wi.y, g.wi.z), (g.wo.x, g.wo.y, g.wo.z), wn,
                                                             dr.select)
                        inside = zz > 0
                    else:
                        uu, vv = -dr.sin(th_k) * dr.cos(ph_p) + dx, -dr.sin(th_k) * dr.sin(ph_p) + dy
                        inside = uu * uu + vv * vv < 1.0
                w = w_p * w_k
                num = num + w * dr.select(inside, scale * self._lookup(self.lookup, p, k, j, uu, vv), 0.0)
                den = den + w * dr.select(inside, 1.0, 0.0)
        out = dr.select(den > 0, num / dr.select(den > 0, den, 1.0), 0.0)
        if self.rim is not None:   # towards the horizon the rim tables, read at ω_o itself (library ``_with_rim``)
            c0, c1 = (math.cos(math.radians(x)) for x in RIM_BLEND_DEG)
            W = dr.clip((c0 - g.wo_l.z) / (c0 - c1), 0.0, 1.0)

            def at(q):   # light azimuth node q's rim tables across incidence
                if self.K == 1:
                    return self._rim_lookup(q, ks[0][0], j, g.wo_l)
                a, t = brk   # the monotone cubic over the incidence nodes a − 1 .. a + 2 (``rim_across_incidence``)
                k4 = [dr.clip(a + s, 0.0, self.K - 1.0) for s in (-1.0, 0.0, 1.0, 2.0)]
                return pchip_between([self._rim_lookup(q, k, j, g.wo_l) for k in k4],
                                     [self._gather_list(self.thetas, k) for k in k4], t, dr.select)

            if self.Q == 1:
                rim = at(0.0)
            else:   # across the light azimuth: the monotone cubic of log f (``rim_across_light_azimuth``)
                f = self._mod(g.phi_i, 2.0 * math.pi) * (self.Q / (2.0 * math.pi))
                fl = dr.floor(f)
                tq = f - fl
                v = [at(self._mod(fl + s, float(self.Q))) for s in (-1.0, 0.0, 1.0, 2.0)]
                lg = [dr.log(dr.maximum(x, RIM_LOG_FLOOR)) for x in v]
                rim = dr.select(dr.maximum(v[1], v[2]) > RIM_LOG_FLOOR,
                                dr.exp(pchip_between(lg, [tq * 0.0 + s for s in (-1.0, 0.0, 1.0, 2.0)], tq,
                                                     dr.select)), 0.0)
            out = (1.0 - W) * out + W * rim
        return dr.select(g.up, out, 0.0)

    def _rim_lookup(self, p, k, j, w):
        """Bilinear read of φ node p's, θ node k's rim table at wavelength node j at the direction *w* (library
        
        :func:`waveoptics.brdf.tabulated_rim.rim_read`: rows in cos θ_o, columns in φ_o over [−π, π], clamped)."""
        dr = self.dr
        n_cos, n_phi = self.rim_shape
        top = math.cos(math.radians(RIM_THETA_DEG))
        fc = w.z * (n_cos / top) - 0.5
        fp = (dr.atan2(w.y, w.x) + math.pi) * ((n_phi - 1) / (2.0 * math.pi))
        c0 = dr.clip(dr.floor(fc), 0.0, n_cos - 2.0)
        p0 = dr.clip(dr.floor(fp), 0.0, n_phi - 2.0)
        ac, ap = dr.clip(fc - c0, 0.0, 1.0), dr.clip(fp - p0, 0.0, 1.0)
        node = (self.idx(p) * self.K + self.idx(k)) * self.J + j
        base = node * (n_cos * n_phi) + self.idx(c0) * n_phi + self.idx(p0)
        return ((1.0 - ac) * ((1.0 - ap) * self._gather(self.rim, base) + ap * self._gather(self.rim, base + 1))
                + ac * ((1.0 - ap) * self._gather(self.rim, base + n_phi)
                        + ap * self._gather(self.rim, base + n_phi + 1)))

    def _nearest_node(self, wi):
        """(p, k) of the node nearest ω_i (library ``_nearest``)."""
        dr = self.dr
        theta = dr.atan2(dr.sqrt(wi.x * wi.x + wi.y * wi.y), wi.z)
        k, best = theta * 0.0, dr.abs(theta - self.thetas[0])
        for i in range(1, self.K):
            d = dr.abs(theta - self.thetas[i])
            k, best = dr.select(d < best, float(i), k), dr.minimum(d, best)
        if self.P == 1:
            return theta * 0.0, k
        phi = dr.atan2(wi.y, wi.x)
        f = self._mod(phi, 2.0 * math.pi) / (2.0 * math.pi / self.P)
        return self._mod(dr.round(f), float(self.P)), k

    def _mirror(self, p, k):
        th = self._gather_list(self.thetas, k) if self.K > 1 else self.thetas[0] + k * 0.0
        ph = self._gather_list(self.phis, p) if self.P > 1 else self.phis[0] + p * 0.0
        return -self.dr.sin(th) * self.dr.cos(ph), -self.dr.sin(th) * self.dr.sin(ph)

    def pdf_diffraction(self, g, j):
        """Density of the diffraction sampler (library ``_pdf_diffraction``): the nearest node's lobe as a
        piecewise-constant density in (u, v), times cos θ_o."""
        dr = self.dr
        u0, v0, du, dv, nu, nv = self.grid
        p, k = self._nearest_node(g.wi)
        mu, mv = self._mirror(p, k)
        uu = g.wo_r.x + g.wi_r.x + mu
        vv = g.wo_r.y + g.wi_r.y + mv
        col = dr.floor((uu - u0) / du)
        row = dr.floor((vv - v0) / dv)
        ok = (col >= 0) & (col < nu) & (row >= 0) & (row < nv) & (g.wo.z > 0)
        node = (self.idx(p) * self.K + self.idx(k)) * self.J + j
        total = self._gather(self.total, node)
        cell = self.idx(dr.clip(row, 0.0, nv - 1.0) * nu + dr.clip(col, 0.0, nu - 1.0)) + node * (nu * nv)
        val = self._gather(self.lobe, cell)
        dens = dr.select(ok & (total > 0), val / dr.select(total > 0, total, 1.0), 0.0) / (du * dv)
        return dens * dr.maximum(g.wo.z, 0.0)

    def sample_diffraction(self, wi, u, j):
        """ω_o from node j's nearest lobe (library ``_sample_diffraction``): a cell by binary search in its
        normalized CDF, uniform inside it, shifted to ω_i's mirror point."""
        dr, mi = self.dr, self.mi
        u0, v0, du, dv, nu, nv = self.grid
        C = nu * nv
        p, k = self._nearest_node(wi)
        node = (self.idx(p) * self.K + self.idx(k)) * self.J + j
        start = node * C
        target = u.x
        if self.scalar:
            c = dr.binary_search(0, C - 1, lambda i: bool(self.cdf[start + i] < target))
        else:
            c = dr.binary_search(0, C - 1, lambda i: dr.gather(mi.Float, self.cdf, start + i) < target)
        c = mi.UInt32(c) if not self.scalar else int(c)
        lo = dr.select(c > 0, self._gather(self.cdf, start + dr.maximum(c, 1) - 1), 0.0)
        hi = self._gather(self.cdf, start + c)
        fu = dr.select(hi > lo, (target - lo) / dr.select(hi > lo, hi - lo, 1.0), 0.5)
        row = c // nu
        col = c - row * nu
        uu = u0 + (mi.Float(col) + fu) * du
        vv = v0 + (mi.Float(row) + u.y) * dv
        mu, mv = self._mirror(p, k)
        rot = (dr.atan2(wi.y, wi.x) - self.phis[0]) if self.rotate else wi.x * 0.0
        wi_r = _rotate(mi, dr, wi, rot)
        x, y = uu - mu - wi_r.x, vv - mv - wi_r.y
        s2 = x * x + y * y
        good = (self._gather(self.total, node) > 0) & (s2 < 1.0)
        wo = _rotate(mi, dr, mi.Vector3f(x, y, dr.sqrt(dr.maximum(1.0 - s2, 0.0))), -rot)
        return dr.select(good, wo, mi.Vector3f(0.0, 0.0, -1.0))


def _rotate(mi, dr, w, phi):
    """Rotate vectors about z by −phi (as the library's tabulated model does)."""
    c, s = dr.cos(phi), dr.sin(phi)
    return mi.Vector3f(c * w.x + s * w.y, -s * w.x + c * w.y, w.z)
