/* Per-pixel footprint sums at one direction pair per footprint (twin: waveoptics/scatter/pixel.py,
 * footprint_sums_numpy). For footprint p with Gaussian weight G(x) = exp(-1/2 (x - c)^T Sigma^-1 (x - c)) over the
 * box [i0, i1) x [j0, j1) of a height-field region (row-major, row length `pitch`, spacing dx, dy), truncated to
 * the ellipse q = (x - c)^T Sigma^-1 (x - c) <= q_max (G = 0 beyond, where G < exp(-q_max / 2)), it sums
 *
 *     U_l  = sum_j G_j exp(2 pi i phi_jl),  phi_jl = (s_x (x_j - c_x) + s_y (y_j - c_y) + s_z h_j) / lambda_l
 *     A    = sum_j G_j^2                         (the window's area / (dx dy))
 *     W    = sum_j G_j
 *     P    = sum_j G_j exp(-1/2 |grad h_j - t|^2 / sigma_s^2)
 *
 * with s = omega_i + omega_o (the Kirchhoff integral over the footprint, Beckmann & Spizzichino 1963 ch. 3; Yan et
 * al. 2018 eq. 6), grad h by central differences (or, with -DWO_GIVEN_SLOPES, read from hx, hy: the field's own
 * slopes, e.g. each flake's plane, where a difference across a step would invent a facet) and t the slope of the
 * half vector (Yan et al. 2016's patch NDF with intrinsic roughness sigma_s). The host multiplies by dx dy and
 * the Kirchhoff / Fresnel factors.
 *
 * Each row visits only the ellipse's chord on it (a few samples of margin; the test q <= q_max decides which
 * samples count, so the chord's rounding changes nothing), not the whole box: pi/4 of a round footprint's box,
 * less of an oblique ellipse's. Each row is summed WO_VW samples per SIMD step (explicit vectors, as
 * kernels/kirchhoff.cl).
 * Work-item (p, c) sums rows j0 + c*step .. of footprint p (n_chunks work-items per footprint, so one large
 * footprint still fills every core); the host adds the chunks. Row sums are added to the running total (two-level
 * summation keeps float32 round-off near sqrt(rows) ulps). Positions enter relative to the box origin (cx, cy are
 * given from it) so that float32 does not cancel large x against c.
 *
 * geo (12 per footprint): cx, cy (m, from sample (i0, j0)), Sigma^-1 entries a, b, c (1/m^2: q = a dx^2 + 2 b dx dy
 * + c dy^2), s_x, s_y, s_z, t_x, t_y, q_max (the truncation, waveoptics.scatter.pixel.Q_MAX), unused. out (2 WO_NL + 3 per work-item): Re U_l, Im U_l, A, W, P.
 */
#include "kirchhoff.h"      /* realv_t: WO_VW samples of a row per SIMD step; wo_sincos_2pi */

#ifndef WO_NL
#define WO_NL 1
#endif
#define WO_NOUT (2 * WO_NL + 3)
/* below this exp(x) is 0 in round-to-nearest (float64: exp(-745.2) is the least subnormal; float32: exp(-103.3), and below half of it) */
#ifdef WO_DOUBLE
#define WO_EXP_UNDERFLOW R(-746.0)
#else
#define WO_EXP_UNDERFLOW R(-105.0)
#endif

/* Rows of the region must hold WO_VW samples past every box (the host pads them with zeros, G masks them). */
__kernel void footprint_sums(__global const real_t *h, __global const real_t *hx, __global const real_t *hy,
                             const int pitch, const real_t dx, const real_t dy,
                             __global const int *box, __global const real_t *geo,
                             __constant real_t *inv_lambda, const real_t inv_slope_var,
                             const int n_items, const int n_chunks, __global real_t *out)
{
    const int gid = get_global_id(0);
    if (gid >= n_items * n_chunks) return;
    const int p = gid / n_chunks, ch = gid % n_chunks;
    const int i0 = box[4 * p], j0 = box[4 * p + 1], i1 = box[4 * p + 2], j1 = box[4 * p + 3];
    __global const real_t *g = geo + 12 * p;
    const real_t cx = g[0], cy = g[1], ca = g[2], cb = g[3], cc = g[4];
    const real_t sx = g[5], sy = g[6], sz = g[7], tx = g[8], ty = g[9], qmax = g[10];
    const int step = (j1 - j0 + n_chunks - 1) / n_chunks;
    const int ja = j0 + ch * step, jb = min(j1, ja + step);
    real_t lanes[WO_VW];
    for (int k = 0; k < WO_VW; ++k) lanes[k] = (real_t)k;
    const realv_t lane = WO_VLOAD(0, lanes);
    real_t ure[WO_NL], uim[WO_NL];
    for (int l = 0; l < WO_NL; ++l) { ure[l] = R(0.0); uim[l] = R(0.0); }
    real_t A = R(0.0), W = R(0.0), P = R(0.0);
    const real_t hx2 = R(0.5) / dx, hy2 = R(0.5) / dy;
    for (int j = ja; j < jb; ++j) {
        const real_t ry = (real_t)(j - j0) * dy - cy;
        /* the ellipse's chord on this row: a rx^2 + 2 b rx ry + c ry^2 <= q_max for rx in [-b ry -+ sqrt(d)] / a */
        const real_t d = (cb * cb - ca * cc) * ry * ry + ca * qmax;
        if (!(d >= R(0.0))) continue;
        const real_t sq = sqrt(d);
        const int ia = max(i0, i0 + (int)floor(((-cb * ry - sq) / ca + cx) / dx) - 1);
        const int ib = min(i1, i0 + (int)ceil(((-cb * ry + sq) / ca + cx) / dx) + 2);
        realv_t rre[WO_NL], rim[WO_NL];
        for (int l = 0; l < WO_NL; ++l) { rre[l] = (realv_t)(R(0.0)); rim[l] = (realv_t)(R(0.0)); }
        realv_t ra = (realv_t)(R(0.0)), rw = ra, rp = ra;
        __global const real_t *row = h + (long)j * pitch;
        for (int i = ia; i < ib; i += WO_VW) {
            const realv_t rx = ((real_t)(i - i0) + lane) * dx - cx;
            const realv_t q = ca * rx * rx + R(2.0) * cb * rx * ry + cc * ry * ry;
            realv_t G = exp(R(-0.5) * q);
            /* lanes past the chord, and samples outside the ellipse */
            G = select((realv_t)(R(0.0)), G,
                       isless(lane, (realv_t)((real_t)(ib - i))) & islessequal(q, (realv_t)(qmax)));
            const realv_t hj = WO_VLOAD(0, row + i);
#ifdef WO_GIVEN_SLOPES
            const realv_t gx = WO_VLOAD(0, hx + (long)j * pitch + i) - tx;
            const realv_t gy = WO_VLOAD(0, hy + (long)j * pitch + i) - ty;
#else
            const realv_t gx = (WO_VLOAD(0, row + i + 1) - WO_VLOAD(0, row + i - 1)) * hx2 - tx;
            const realv_t gy = (WO_VLOAD(0, row + i + pitch) - WO_VLOAD(0, row + i - pitch)) * hy2 - ty;
#endif
            const realv_t base = sx * rx + sy * ry + sz * hj;          /* m */
            for (int l = 0; l < WO_NL; ++l) {
                realv_t sn, cs;
                wo_sincos_2pi(base * inv_lambda[l], &sn, &cs);
                rre[l] += G * cs;
                rim[l] += G * sn;
            }
            ra += G * G;
            rw += G;
            /* the intrinsic-roughness kernel of a facet far from the half vector underflows to exactly 0:
             * its exp is skipped where it does in every lane (the sum is unchanged, bit for bit) */
            const realv_t e = R(-0.5) * (gx * gx + gy * gy) * inv_slope_var;
#if WO_VW == 1
            if (e > WO_EXP_UNDERFLOW) rp += G * exp(e);
#else
            if (any(isgreater(e, (realv_t)(WO_EXP_UNDERFLOW)))) rp += G * exp(e);
#endif
        }
        real_t t[WO_VW];
        for (int l = 0; l < WO_NL; ++l) {
            WO_VSTORE(rre[l], 0, t);
            for (int k = 0; k < WO_VW; ++k) ure[l] += t[k];
            WO_VSTORE(rim[l], 0, t);
            for (int k = 0; k < WO_VW; ++k) uim[l] += t[k];
        }
        WO_VSTORE(ra, 0, t);
        for (int k = 0; k < WO_VW; ++k) A += t[k];
        WO_VSTORE(rw, 0, t);
        for (int k = 0; k < WO_VW; ++k) W += t[k];
        WO_VSTORE(rp, 0, t);
        for (int k = 0; k < WO_VW; ++k) P += t[k];
    }
    __global real_t *o = out + (long)gid * WO_NOUT;
    for (int l = 0; l < WO_NL; ++l) { o[2 * l] = ure[l]; o[2 * l + 1] = uim[l]; }
    o[2 * WO_NL] = A; o[2 * WO_NL + 1] = W; o[2 * WO_NL + 2] = P;
}
