/* Kirchhoff / Huygens-Fresnel field of a height-field patch, summed directly (twin: waveoptics/scatter/direct.py,
 * functions kirchhoff_phase and kirchhoff_U).
 *
 *     U_p = sum_j w_j exp(2 pi i phi_pj),   phi_pj = (s_p . (x_j, y_j, h_j)) / lambda_p   [cycles]
 *
 * for pairs p = (outgoing direction, wavelength) with s = omega_i + omega_o (docs/physics.md sec. 1; Beckmann &
 * Spizzichino 1963). The host multiplies by dx dy and applies the obliquity / Fresnel factors.
 *
 * Phase accuracy (float32). x_j = ix_j dx, y_j = iy_j dy with integer grid indices, so the lateral phase is
 * ix a_x + iy a_y with a = s dx / lambda in cycles per sample. The host reduces a modulo 1 in double precision and
 * splits it into a 32-bit fixed-point part A (a = A / 2^32 + lo, |lo| <= 2^-33): ix * A + iy * A_y is computed in
 * 32-bit unsigned integer arithmetic, which is exact modulo 2^32, i.e. exact modulo one cycle, for any patch size.
 * The rest (ix lo, h cz, the constant c0) is small and is added in real_t, so the float32 phase error stays ~1e-6
 * cycles however large k x grows (naive float32 k x loses ~1e-2 rad at 10^4 wavelengths). Heights arrive with their
 * mean removed (|U|^2 does not depend on a constant offset, but the rounding of h cz does).
 *
 * Speed (issue 6; measured figures in docs/performance.md, produced by `waveoptics bench`):
 *   - cos/sin of the phase come from wo_sincos_2pi (wo_sincos.h): one exact argument reduction shared by both and
 *     two short polynomials, accurate to the last bit of float32 (float64), instead of two SLEEF calls
 *     sinpi/cospi that each reduce and handle special cases;
 *   - register blocking: each work-item sums WO_ND pairs, so the WO_VW samples it loads (ix, iy, h, w and their
 *     conversions) serve WO_ND phases;
 *   - one work-item per work-group on CPU devices (the host passes local size 1): PoCL then runs the explicit
 *     WO_VW-wide vector code as written instead of trying to vectorize across work-items (2x by itself).
 * Partial sums over blocks of 256 samples are added to the running total (two-level summation keeps float32
 * round-off near sqrt(n_blocks) rather than n_samples ulps).
 *
 * The benchmark's variants (the kernel before these changes, the naive kernel) live in bench_kirchhoff.cl.
 */
#include "kirchhoff.h"

/* Per-sample phase of one pair (for accuracy checks against the float64 NumPy twin); WO_VW samples per item,
 * n_samples a multiple of WO_VW. */
__kernel void kirchhoff_phase(__global const int *ix, __global const int *iy, __global const real_t *h,
                              const int n_samples, const uint Ax, const uint Ay, const real_t lox, const real_t loy,
                              const real_t cz, const real_t c0, __global real_t *phase)
{
    int b = get_global_id(0);
    if (b >= n_samples / WO_VW) return;
    realv_t ph = kirchhoff_phase_v(WO_VLOAD(b, ix), WO_VLOAD(b, iy), WO_VLOAD(b, h), Ax, Ay, lox, loy, cz, c0);
    WO_VSTORE(ph, b, phase);
}

/* Field U_p (without the dx dy factor) for n_pairs pairs, WO_ND pairs per work-item (global size
 * ceil(n_pairs / WO_ND)); n_samples a multiple of WO_VW. */
__kernel void kirchhoff_U(__global const int *ix, __global const int *iy, __global const real_t *h,
                          __global const real_t *w, const int n_samples,
                          __global const uint *Ax, __global const uint *Ay, __global const real_t *lox,
                          __global const real_t *loy, __global const real_t *cz, __global const real_t *c0,
                          const int n_pairs, __global real_t *U_re, __global real_t *U_im)
{
    const int p0 = get_global_id(0) * WO_ND;
    if (p0 >= n_pairs) return;
    uint ax[WO_ND], ay[WO_ND];
    real_t lx[WO_ND], ly[WO_ND], z[WO_ND], c[WO_ND], sre[WO_ND], sim[WO_ND];
    for (int d = 0; d < WO_ND; ++d) {
        const int p = min(p0 + d, n_pairs - 1);     /* the last item repeats a pair it does not store */
        ax[d] = Ax[p]; ay[d] = Ay[p]; lx[d] = lox[p]; ly[d] = loy[p]; z[d] = cz[p]; c[d] = c0[p];
        sre[d] = R(0.0); sim[d] = R(0.0);
    }
    const int nv = n_samples / WO_VW;
    const int block = 256 / WO_VW;               /* samples per partial sum: two-level summation */
    for (int b0 = 0; b0 < nv; b0 += block) {
        realv_t tre[WO_ND], tim[WO_ND];
        for (int d = 0; d < WO_ND; ++d) { tre[d] = (realv_t)(R(0.0)); tim[d] = (realv_t)(R(0.0)); }
        const int b1 = min(b0 + block, nv);
        for (int b = b0; b < b1; ++b) {
            const intv_t vix = WO_VLOAD(b, ix), viy = WO_VLOAD(b, iy);
            const realv_t vh = WO_VLOAD(b, h), vw = WO_VLOAD(b, w);
            const realv_t fx = WO_TO_REALV(vix), fy = WO_TO_REALV(viy);
            const uintv_t ux = WO_AS_UINTV(vix), uy = WO_AS_UINTV(viy);
#pragma unroll
            for (int d = 0; d < WO_ND; ++d) {
                /* the phase of kirchhoff_phase_v without its rint: wo_sincos_2pi reduces it exactly */
                const intv_t fixed = WO_AS_INTV(ux * ax[d] + uy * ay[d]);
                const realv_t ph = WO_TO_REALV(fixed) * WO_2POW_M32 + (fx * lx[d] + fy * ly[d]) + (vh * z[d] + c[d]);
                realv_t sn, cs;
                wo_sincos_2pi(ph, &sn, &cs);
                tre[d] += vw * cs;
                tim[d] += vw * sn;
            }
        }
        for (int d = 0; d < WO_ND; ++d) {
            real_t lre[WO_VW], lim[WO_VW];
            WO_VSTORE(tre[d], 0, lre);
            WO_VSTORE(tim[d], 0, lim);
            real_t pre = R(0.0), pim = R(0.0);
            for (int k = 0; k < WO_VW; ++k) { pre += lre[k]; pim += lim[k]; }
            sre[d] += pre;
            sim[d] += pim;
        }
    }
    for (int d = 0; d < WO_ND; ++d) {
        if (p0 + d < n_pairs) { U_re[p0 + d] = sre[d]; U_im[p0 + d] = sim[d]; }
    }
}

/* cos/sin(2 pi t) of n values by wo_sincos_2pi (n a multiple of WO_VW), for checking it against its twin. */
__kernel void sincos_2pi(__global const real_t *t, const int n, __global real_t *s, __global real_t *c)
{
    const int b = get_global_id(0);
    if (b >= n / WO_VW) return;
    realv_t sn, cs;
    wo_sincos_2pi(WO_VLOAD(b, t), &sn, &cs);
    WO_VSTORE(sn, b, s);
    WO_VSTORE(cs, b, c);
}
