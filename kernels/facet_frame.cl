/* Walter's facet-frame integral of the two-scale BRDF, the per-cell sum of facet_frame_diffraction (twin: the
 * add() loops of waveoptics/brdf/twoscale_frame.py; host code waveoptics/brdf/facet_frame_cl.py):
 *
 *   f_diff(wi, wo) / F = sum over nodes m of  |wi.m| D(m) G(wi, wo, m) / (|wi.n| |wo.n| (Na pa(m) + Nb pb(m)))
 *                        x g(theta_m, wo^m)
 *
 * one work item per cell (wo, its half-vector h): Na NDF nodes with density pa = D(m) cos theta_m turned to the
 * cell's half-vector azimuth, and Nb antithetic half-vector nodes (tilt radius from the nano lobe's radial law
 * at the cell's cos theta_d level, density pb = p_r(2 cos theta_d sin(m, h)) 4 cos^2 theta_d (m.h)); the balance
 * heuristic weights both (Veach 1997, sec. 9.2), and where the cell's record gives a bridge point (where D(m) and
 * the nano lobe meet between both sets' normals: a lobe's deep tail) Nc Gaussian nodes about it, density pc,
 * counted beta times. g = f_nano cos theta_o is read from the facet tables over local
 * incidence (stack: n_theta x n_v x n_u x n_lam, float32), bilinearly at the two table incidences around theta_m,
 * each at the local exit direction turned about the local y axis by theta_m - theta_k.
 * Switches (build options): WO_NDF, WO_SHADOWING as in microfacet.h; WO_ISO 1 when the NDF nodes turn with
 * the cell's half-vector azimuth (isotropic NDF), 0 for an anisotropic NDF (its isotropic law's nodes turned to h there);
 * WO_MIX 1 for s or p light: cos^2 eta_i of the facet's own table and sin^2 eta_i of the other (Priest & Germer).
 * WO_BLEND 1 when stack holds the tangent-plane lobe f_K cos theta_o and stack_other the first-order lobe
 * f_RR / F cos theta_o of the hand-over (waveoptics/scatter/tangent_blend.py): g = W stack + (1 - W) stack_other,
 * W = w(theta_i') w(theta_o') at the facet's exact local angles, w the cubic smoothstep from 1 at WO_BLEND_0 to 0
 * at WO_BLEND_1 (radians); the same for the local incidence and exit swapped (reciprocal).
 * WO_EQUI 1 when the tables' grid is Lambert's azimuthal equal-area projection (x, y) = (u, v) / sqrt(1 + z) of
 * the local exit (PSD statistics: a cell 1.7-2.4 degrees on 96^2 up to the horizon; Snyder 1987, sec. 24), 0 when
 * it is in direction cosines (a height field's tables). With WO_EQUI the first-order tables (stack_other under
 * WO_BLEND; stack and stack_other of a Rayleigh-Rice lobe) hold q = f_RR / cos theta_o = g / cos^2 theta_o, finite
 * and smooth at the horizon where g falls like cos^2 theta_o (Church et al. 1979): each read is multiplied by the
 * facet's exact cos^2 theta_o' (the twin _facet_read; a bilinear read of g itself ran 5-9 % high at 84-86 degrees).
 * References: Walter, Marschner, Li, Torrance, EGSR 2007, eq. 14; Veach, PhD thesis 1997, sec. 9.2; Duff et al.,
 * JCGT 6(1) 2017 (facet basis); Priest & Germer, Proc. MSS Passive Sensors 2000 (facet s/p frames); Church,
 * Jenkinson, Zavada, Opt. Eng. 18(2) 1979 (the first-order lobe's cos theta_i cos theta_o).
 */
#include "microfacet.h"

#ifndef WO_ISO
#define WO_ISO 1
#endif
#ifndef WO_MIX
#define WO_MIX 0
#endif
#ifndef WO_BLEND
#define WO_BLEND 0
#endif
#ifndef WO_EQUI
#define WO_EQUI 0
#endif

#if WO_BLEND
/* w(theta): 1 up to WO_BLEND_0, 0 beyond WO_BLEND_1, the cubic smoothstep 1 - x^2 (3 - 2x) between (the twin of
 * tangent_plane_weight in waveoptics/scatter/tangent_blend.py) */
inline real_t tangent_weight(real_t theta)
{
    real_t x = wo_clamp((theta - (real_t)(WO_BLEND_0)) / ((real_t)(WO_BLEND_1) - (real_t)(WO_BLEND_0)),
                        R(0.0), R(1.0));
    return R(1.0) - x * x * (R(3.0) - R(2.0) * x);
}
#endif
/* wavelengths accumulated per pass (the host loops over passes) */
#define WO_NL 32
/* per-cell record: wo (3), h (3), cos phi_h, sin phi_h, cos theta_d, Lambda(wo), grazes (1: 2 na NDF nodes), the
 * bridge point m_c (3), its Gaussian's widths towards h and across (2; 0: no bridge nodes) and its weight beta
 * (twin facet.bridge_point) */
#define WO_CELL 17

/* G from the precomputed Lambda(wi), Lambda(wo) (Heitz 2014 eqs. 98, 99); the forms without Lambda from
 * microfacet.h (Cook & Torrance 1982 eq. 5; implicit) */
inline real_t G_lambda(real3_t wi, real3_t wo, real3_t m, real_t Li, real_t Lo, real_t ax, real_t ay, real_t c)
{
#if WO_SHADOWING == 0
    return G1(wi, m, Li) * G1(wo, m, Lo);
#elif WO_SHADOWING == 1
    if (wi.z <= R(0.0) || wo.z <= R(0.0) || dot(wi, m) <= R(0.0) || dot(wo, m) <= R(0.0)) return R(0.0);
    return R(1.0) / (R(1.0) + Li + Lo);
#else
    return G(wi, wo, m, ax, ay, c);
#endif
}

/* Tangents (t, b) of the frame (t, b, m), continuous for m.z > -1 (Duff et al. 2017; twin facet.facet_basis) */
inline void facet_basis(real3_t m, real3_t *t, real3_t *b)
{
    real_t sign = (m.z >= R(0.0)) ? R(1.0) : R(-1.0);
    real_t a = R(-1.0) / (sign + m.z);
    real_t c = m.x * m.y * a;
    *t = (real3_t)(R(1.0) + sign * m.x * m.x * a, sign * c, -sign * m.x);
    *b = (real3_t)(c, sign + m.y * m.y * a, -m.y);
}

/* cos^2 eta_i between the macro s direction s_mac and the facet's, m x wi (twin materials.cos2_eta_i) */
inline real_t cos2_eta_i(real3_t wi, real3_t s_mac, real3_t m)
{
    real3_t s = cross(m, wi);
    real_t n = length(s);
    if (!(n > R(1e-12))) return R(1.0);   /* guard: m parallel to wi: the facet plane is the macro plane */
    real_t d = dot(s_mac, s) / n;
    return wo_clamp(d * d, R(0.0), R(1.0));
}

/* Radial density (per unit area of the direction-cosine plane) at offset r: the bin of r among edges[0..n_bins] */
inline real_t pdf_r(__global const real_t *edges, __global const real_t *density, int level, int n_bins, real_t r)
{
    if (!(r >= edges[0]) || !(r < edges[n_bins])) return R(0.0);
    int lo = 0, hi = n_bins;   /* edges[lo] <= r < edges[hi] */
    while (hi - lo > 1) {
        int mid = (lo + hi) >> 1;
        if (edges[mid] <= r) lo = mid; else hi = mid;
    }
    return density[level * n_bins + lo];
}

/* Density (1/sr) of the bridge nodes at m: the 2-D normal law of m's offsets along bp, bq (widths sx, sy) in the
 * tangent plane of the bridge point mc, times m.mc (twin facet.bridge_density) */
inline real_t bridge_pdf(real3_t m, real3_t mc, real3_t bp, real3_t bq, real_t sx, real_t sy)
{
    real_t mm = dot(m, mc);
    if (!(mm > R(0.0))) return R(0.0);
    real_t x = dot(m, bp) / sx, y = dot(m, bq) / sy;
    return exp(R(-0.5) * (x * x + y * y)) / (R(2.0) * WO_PI * sx * sy) * mm;
}

/* One node m: acc[l] += weight x g(theta_m, wo^m) at wavelengths l0 .. l0 + nl - 1. pb: the node's half-vector
 * density. Returns nothing; nodes the light or the viewer does not see, or of zero density, add nothing. */
inline void add_node(real3_t m, real_t pb, real3_t wi, real3_t wo, real3_t s_mac, real_t Li, real_t Lo,
                     real_t ax, real_t ay, real_t c, real_t na, real_t nb,
                     __global const real_t *thetas, __global const real_t *cs_theta, int n_theta,
                     __global const float *stack,
                     __global const float *stack_other, real_t u0, real_t v0, real_t du, real_t dv,
                     int n_u, int n_v, int n_lam, int l0, int nl, real_t *acc)
{
    real_t im = dot(m, wi), om = dot(wo, m);
    real_t Dm = D(m, ax, ay, c);
    real_t den = na * Dm * m.z + nb * pb;   /* balance heuristic: Na pa + Nb pb */
    if (!(im > R(0.0) && om > R(0.0) && den > R(0.0) && Dm > R(0.0))) return;
    real_t weight = im * Dm * G_lambda(wi, wo, m, Li, Lo, ax, ay, c) / (wi.z * wo.z * den);
    if (weight == R(0.0)) return;
    real3_t t, b;
    facet_basis(m, &t, &b);
    real_t lx = dot(t, wi), ly = dot(b, wi);
    real_t r = sqrt(lx * lx + ly * ly);
    real_t cp = (r > R(0.0)) ? lx / r : R(1.0), sp = (r > R(0.0)) ? ly / r : R(0.0);
    real_t ux = dot(wo, t), uy = dot(wo, b);
    real_t lox = cp * ux + sp * uy, loy = -sp * ux + cp * uy;   /* turned so that wi^m lies in x-z */
    real_t theta = atan(r / im);   /* local incidence (im > 0 here), accurate near 0; atan2 was 20 % of the sum on PoCL */
    real_t rho = sqrt(r * r + im * im);
    real_t ct = im / rho, st = r / rho;                        /* cos, sin theta */
    /* the two table incidences around theta (np.interp on the node index; beyond the last node: the last) */
    int a = n_theta - 1;
    real_t wb = R(0.0);
    if (theta < thetas[n_theta - 1]) {
        int hi = n_theta - 1;   /* thetas[a] <= theta < thetas[hi] */
        a = 0;
        while (hi - a > 1) {
            int mid = (a + hi) >> 1;
            if (thetas[mid] <= theta) a = mid; else hi = mid;
        }
        wb = fmax((theta - thetas[a]) / (thetas[a + 1] - thetas[a]), R(0.0));
    }
    int kk[2] = {a, min(a + 1, n_theta - 1)};
    real_t wk[2] = {R(1.0) - wb, wb};
    int idx[2];
    real_t au[2], av[2];
    real_t blend = R(0.0);
    for (int s = 0; s < 2; ++s) {
        /* beta = theta - theta_k by the difference formulas (cs_theta: cos, sin of the table incidences) */
        real_t ck = cs_theta[2 * kk[s]], sk = cs_theta[2 * kk[s] + 1];
        real_t cb = ct * ck + st * sk, sb = st * ck - ct * sk;
        real_t u = lox * cb + om * sb;
        real_t z = -lox * sb + om * cb;
#if WO_EQUI
        /* Lambert's azimuthal equal-area projection of (u, loy, z): (u, loy) / sqrt(1 + z) */
        real_t ke = rsqrt(R(1.0) + fmax(z, R(0.0)));
        real_t xe = u * ke, ye = loy * ke;
#else
        real_t xe = u, ye = loy;
#endif
        real_t fu = (xe - u0) / du - R(0.5), fv = (ye - v0) / dv - R(0.5);
        bool ok = fu > R(-0.5) && fu < (real_t)n_u - R(0.5) && fv > R(-0.5) && fv < (real_t)n_v - R(0.5);
        int j0 = clamp((int)floor(fu), 0, n_u - 2), k0 = clamp((int)floor(fv), 0, n_v - 2);
        au[s] = wo_clamp(fu - (real_t)j0, R(0.0), R(1.0));
        av[s] = wo_clamp(fv - (real_t)k0, R(0.0), R(1.0));
        if (!(ok && z > R(0.0))) wk[s] = R(0.0);
        idx[s] = ((kk[s] * n_v + k0) * n_u + j0) * n_lam + l0;
        blend += wk[s];
    }
    if (!(blend > R(0.0))) return;
    real_t own = weight / blend;
#if WO_MIX
    real_t c2 = cos2_eta_i(wi, s_mac, m);
    real_t other = own * (R(1.0) - c2);
    own *= c2;
#elif WO_BLEND
    /* w = 1 below WO_BLEND_0: the arc cosine of the exit only beyond it */
    real_t wt = (theta > (real_t)(WO_BLEND_0)) ? tangent_weight(theta) : R(1.0);
    if (om < cos((real_t)(WO_BLEND_0))) wt *= tangent_weight(acos(wo_clamp(om, R(-1.0), R(1.0))));
    real_t other = own * (R(1.0) - wt);   /* the first-order table's share; each read is skipped at weight 0 */
    own *= wt;
#endif
#if WO_EQUI
    /* first-order tables of PSD statistics hold q = g / cos^2 theta_o: times the exact cos^2 theta_o' */
#if WO_BLEND
    other *= om * om;
#else
    own *= om * om;
#if WO_MIX
    other *= om * om;
#endif
#endif
#endif
    int row = n_u * n_lam;
    for (int s = 0; s < 2; ++s) {
        if (wk[s] == R(0.0)) continue;
        real_t w00 = wk[s] * (R(1.0) - av[s]) * (R(1.0) - au[s]), w01 = wk[s] * (R(1.0) - av[s]) * au[s];
        real_t w10 = wk[s] * av[s] * (R(1.0) - au[s]), w11 = wk[s] * av[s] * au[s];
        if (own != R(0.0)) {
            __global const float *p = stack + idx[s];
            for (int l = 0; l < nl; ++l)
                acc[l] += own * (w00 * p[l] + w01 * p[n_lam + l] + w10 * p[row + l] + w11 * p[row + n_lam + l]);
        }
#if WO_MIX || WO_BLEND
        if (other != R(0.0)) {
            __global const float *q = stack_other + idx[s];
            for (int l = 0; l < nl; ++l)
                acc[l] += other * (w00 * q[l] + w01 * q[n_lam + l] + w10 * q[row + l] + w11 * q[row + n_lam + l]);
        }
#endif
    }
}

/* out[i * n_lam + l0 + l] = the sum over both node sets at cell i, wavelengths l0 .. l0 + nl - 1 (nl <= WO_NL).
 * m0 (na, 3): NDF nodes at half-vector azimuth 0 (WO_ISO; else those of the isotropic law the anisotropic NDF
 * stretches, turned to h's unstretched azimuth and stretched per cell); m0_hi (2 na, 3): the same law's 2 na
 * nodes, for the cells whose record says they graze (twin: grazing_cells); hv_r, hv_pdf (levels,
 * n_base): the half-vector nodes' offset radii and their radial density; hv_phi (nb, 2): cos, sin of their
 * azimuths about h; edges (n_bins + 1), density (levels, n_bins): the radial law in direction-cosine units;
 * bc (nc, 2): the bridge nodes' offsets in units of the cell's widths (twin facet.bridge_offsets), about the cell's
 * bridge point where its record gives widths > 0 (Nc = nc nodes more; each set's density then adds Nc pc). */
__kernel void facet_frame_sum(__global const real_t *cell, __global const int *level,
                              __global const real_t *m0, __global const real_t *m0_hi,
                              __global const real_t *hv_r,
                              __global const real_t *hv_pdf, __global const real_t *hv_phi,
                              __global const real_t *edges, __global const real_t *density,
                              __global const real_t *thetas, __global const real_t *cs_theta,
                              __global const float *stack,
                              __global const float *stack_other, __global const real_t *bc,
                              __global real_t *out,
                              const real_t wix, const real_t wiy, const real_t wiz, const real_t Li,
                              const real_t ax, const real_t ay, const real_t c,
                              const real_t u0, const real_t v0, const real_t du, const real_t dv,
                              const int n_cells, const int na, const int nb, const int nc, const int n_base,
                              const int n_bins,
                              const int n_theta, const int n_u, const int n_v, const int n_lam, const int l0,
                              const int nl)
{
    int i = get_global_id(0);
    if (i >= n_cells) return;
    __global const real_t *rec = cell + WO_CELL * i;
    real3_t wi = (real3_t)(wix, wiy, wiz);
    real3_t wo = (real3_t)(rec[0], rec[1], rec[2]);
    real3_t h = (real3_t)(rec[3], rec[4], rec[5]);
    real_t cphi = rec[6], sphi = rec[7], cos_d = rec[8], Lo = rec[9];
    bool graze = rec[10] > R(0.5);
    int na_c = graze ? 2 * na : na;
    __global const real_t *mk = graze ? m0_hi : m0;
    int lev = level[i];
    /* the macro s direction z x wi (guard: at normal incidence the macro plane is x-z, s along y) */
    real_t nm = sqrt(wix * wix + wiy * wiy);
    real3_t s_mac = (nm > R(1e-12)) ? (real3_t)(-wiy / nm, wix / nm, R(0.0)) : (real3_t)(R(0.0), R(1.0), R(0.0));
    /* meridian basis of h (twin facet.meridian_basis) */
    real3_t e1 = (real3_t)(h.z * cphi, h.z * sphi, -sqrt(h.x * h.x + h.y * h.y));
    real3_t e2 = (real3_t)(-sphi, cphi, R(0.0));
    real_t acc[WO_NL];
    for (int l = 0; l < WO_NL; ++l) acc[l] = R(0.0);
    real_t fna = (real_t)na_c, fnb = (real_t)nb;
    /* the bridge point and its frame (twin facet._bridge_frame); add_node's pb carries Nc pc / Nb */
    real3_t mc = (real3_t)(rec[11], rec[12], rec[13]);
    real_t bsx = rec[14], bsy = rec[15], beta = rec[16];
    bool bridge = bsx > R(0.0) && beta > R(0.0) && nc > 0 && nb > 0;
    real3_t bp = h - dot(h, mc) * mc, bq;
    if (length(bp) > R(1e-12)) bp = normalize(bp); else facet_basis(mc, &bp, &bq);
    bq = cross(mc, bp);
    /* the bridge's normals count beta Nc times (pb carries beta Nc pc / Nb); each one's term is beta times its
     * own: add_node given Na / beta, Nb / beta */
    real_t fc = bridge ? beta * (real_t)nc / fnb : R(0.0);
#if !WO_ISO
    /* an anisotropic NDF is the stretch of the isotropic law of roughness sqrt(ax ay) by (kx, ky) (Heitz 2014,
     * sec. 5.3); m0 holds that law's nodes (twin facet.ndf_nodes) */
    real_t kx = sqrt(ax / ay), ky = sqrt(ay / ax);
    real_t rpsi = sqrt(cphi * cphi / (kx * kx) + sphi * sphi / (ky * ky));
    real_t cpsi = cphi / kx / rpsi, spsi = sphi / ky / rpsi;
#endif
    for (int k = 0; k < na_c; ++k) {
        real3_t m = (real3_t)(mk[3 * k], mk[3 * k + 1], mk[3 * k + 2]);
#if WO_ISO
        m = (real3_t)(cphi * m.x - sphi * m.y, sphi * m.x + cphi * m.y, m.z);
#else
        /* the isotropic law's node turned in the unstretched slope plane to h's azimuth there, then stretched */
        m = normalize((real3_t)(kx * (cpsi * m.x - spsi * m.y), ky * (spsi * m.x + cpsi * m.y), m.z));
#endif
        real_t mh = wo_clamp(dot(h, m), R(0.0), R(1.0));
        /* sin(m, h) from the cross product: no cancellation for m near h */
        real_t pb = (mh > R(0.0))
            ? pdf_r(edges, density, lev, n_bins, R(2.0) * cos_d * length(cross(m, h))) * R(4.0) * cos_d * cos_d * mh
            : R(0.0);
        if (bridge) pb += fc * bridge_pdf(m, mc, bp, bq, bsx, bsy);
        add_node(m, pb, wi, wo, s_mac, Li, Lo, ax, ay, c, fna, fnb, thetas, cs_theta, n_theta, stack, stack_other,
                 u0, v0, du, dv, n_u, n_v, n_lam, l0, nl, acc);
    }
    for (int k = 0; k < nb; ++k) {
        int j = k % n_base;
        real_t s = hv_r[lev * n_base + j] / (R(2.0) * cos_d);   /* a tilt s from h sends wi to 2k cos_d s */
        if (!(s < R(1.0))) continue;
        real_t ch = sqrt(R(1.0) - s * s);
        real3_t m = (s * hv_phi[2 * k]) * e1 + (s * hv_phi[2 * k + 1]) * e2 + ch * h;
        real_t pb = hv_pdf[lev * n_base + j] * R(4.0) * cos_d * cos_d * ch;
        if (bridge) pb += fc * bridge_pdf(m, mc, bp, bq, bsx, bsy);
        add_node(m, pb, wi, wo, s_mac, Li, Lo, ax, ay, c, fna, fnb, thetas, cs_theta, n_theta, stack, stack_other,
                 u0, v0, du, dv, n_u, n_v, n_lam, l0, nl, acc);
    }
    for (int k = 0; bridge && k < nc; ++k) {
        real_t x = bsx * bc[2 * k], y = bsy * bc[2 * k + 1];
        real_t r2 = x * x + y * y;
        if (!(r2 < R(1.0))) continue;
        real3_t m = x * bp + y * bq + sqrt(R(1.0) - r2) * mc;
        real_t mh = wo_clamp(dot(h, m), R(0.0), R(1.0));
        real_t pb = (mh > R(0.0))
            ? pdf_r(edges, density, lev, n_bins, R(2.0) * cos_d * length(cross(m, h))) * R(4.0) * cos_d * cos_d * mh
            : R(0.0);
        pb += fc * bridge_pdf(m, mc, bp, bq, bsx, bsy);
        add_node(m, pb, wi, wo, s_mac, Li, Lo, ax, ay, c, fna / beta, fnb / beta, thetas, cs_theta, n_theta, stack,
                 stack_other, u0, v0, du, dv, n_u, n_v, n_lam, l0, nl, acc);
    }
    __global real_t *o = out + (size_t)i * n_lam + l0;
    for (int l = 0; l < nl; ++l) o[l] = acc[l];
}
