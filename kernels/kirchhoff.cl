/* Kirchhoff / Huygens-Fresnel field of a height-field patch, summed directly (twin: waveoptics/diffraction.py,
 * functions kirchhoff_phase and kirchhoff_U).
 *
 *     U_p = sum_j w_j exp(2 pi i phi_pj),   phi_pj = (s_p . (x_j, y_j, h_j)) / lambda_p   [cycles]
 *
 * for pairs p = (outgoing direction, wavelength) with s = omega_i + omega_o (physics.md sec. 1; Beckmann &
 * Spizzichino 1963). The host multiplies by dx dy and applies the obliquity / Fresnel factors.
 *
 * Phase accuracy (float32). x_j = ix_j dx, y_j = iy_j dy with integer grid indices, so the lateral phase is
 * ix a_x + iy a_y with a = s dx / lambda in cycles per sample. The host reduces a modulo 1 in double precision and
 * splits it into a 32-bit fixed-point part A (a = A / 2^32 + lo, |lo| <= 2^-33): ix * A + iy * A_y is computed in
 * 32-bit unsigned integer arithmetic, which is exact modulo 2^32, i.e. exact modulo one cycle, for any patch size.
 * The rest (ix lo, h cz, the constant c0) is small and is added in real_t. The phase is reduced to [-1/2, 1/2]
 * cycles before sinpi/cospi, so the float32 error stays ~1e-6 cycles however large k x grows (naive float32 k x loses
 * ~1e-2 rad at 10^4 wavelengths). Heights arrive with their mean removed (|U|^2 does not depend on a constant
 * offset, but the rounding of h cz does).
 *
 * Layout: one work-item per pair; it streams all samples WO_VW at a time as explicit vectors, so that a CPU
 * device (PoCL) evaluates sinpi/cospi on SIMD lanes (the work-items of a group read the same samples at the same
 * time, which caches serve). Partial sums over blocks of 256 samples are added to the running total (two-level
 * summation keeps float32 round-off near sqrt(n_blocks) rather than n_samples ulps). A local-memory tiled variant
 * for GPUs is left to the performance issue.
 */
#include "wo_common.h"

#define WO_2POW_M32 R(2.3283064365386962890625e-10)

/* Vector width of the inner loop over samples (the host pads the sample arrays to a multiple of it with w = 0).
 * On CPU devices (PoCL) explicit vectors put sinpi/cospi on SIMD lanes; on GPUs they are simply unrolled. */
#ifndef WO_VW
#define WO_VW 16
#endif
#define WO_CAT_(a, b) a##b
#define WO_CAT(a, b) WO_CAT_(a, b)
#ifdef WO_DOUBLE
#define WO_RV(n) WO_CAT(double, n)
#else
#define WO_RV(n) WO_CAT(float, n)
#endif
typedef WO_RV(WO_VW) realv_t;
typedef WO_CAT(int, WO_VW) intv_t;
typedef WO_CAT(uint, WO_VW) uintv_t;
#define WO_VLOAD WO_CAT(vload, WO_VW)
#define WO_TO_REALV WO_CAT(convert_, WO_RV(WO_VW))
#define WO_AS_INTV WO_CAT(as_int, WO_VW)
#define WO_AS_UINTV WO_CAT(as_uint, WO_VW)

/* Phase of WO_VW samples (ix, iy, h) for one pair, in cycles, reduced to [-1/2, 1/2]. */
inline realv_t kirchhoff_phase_v(intv_t vix, intv_t viy, realv_t vh, uint ax, uint ay, real_t lx, real_t ly,
                                 real_t z, real_t c)
{
    intv_t fixed = WO_AS_INTV(WO_AS_UINTV(vix) * ax + WO_AS_UINTV(viy) * ay);   /* exact modulo 2^32 = 1 cycle */
    realv_t ph = WO_TO_REALV(fixed) * WO_2POW_M32 + (WO_TO_REALV(vix) * lx + WO_TO_REALV(viy) * ly)
                 + (vh * z + c);
    return ph - rint(ph);
}

/* Per-sample phase of one pair (for accuracy checks against the float64 NumPy twin); WO_VW samples per item,
 * n_samples a multiple of WO_VW. */
__kernel void kirchhoff_phase(__global const int *ix, __global const int *iy, __global const real_t *h,
                              const int n_samples, const uint Ax, const uint Ay, const real_t lox, const real_t loy,
                              const real_t cz, const real_t c0, __global real_t *phase)
{
    int b = get_global_id(0);
    if (b >= n_samples / WO_VW) return;
    realv_t ph = kirchhoff_phase_v(WO_VLOAD(b, ix), WO_VLOAD(b, iy), WO_VLOAD(b, h), Ax, Ay, lox, loy, cz, c0);
    WO_CAT(vstore, WO_VW)(ph, b, phase);
}

/* Field U_p (without the dx dy factor) for n_pairs pairs, one work-item per pair; n_samples a multiple of WO_VW. */
__kernel void kirchhoff_U(__global const int *ix, __global const int *iy, __global const real_t *h,
                          __global const real_t *w, const int n_samples,
                          __global const uint *Ax, __global const uint *Ay, __global const real_t *lox,
                          __global const real_t *loy, __global const real_t *cz, __global const real_t *c0,
                          const int n_pairs, __global real_t *U_re, __global real_t *U_im)
{
    const int p = get_global_id(0);
    if (p >= n_pairs) return;
    const uint ax = Ax[p], ay = Ay[p];
    const real_t lx = lox[p], ly = loy[p], z = cz[p], c = c0[p];
    real_t sre = R(0.0), sim = R(0.0);
    const int nv = n_samples / WO_VW;
    const int block = 256 / WO_VW;               /* samples per partial sum: two-level summation */
    for (int b0 = 0; b0 < nv; b0 += block) {
        realv_t tre = (realv_t)(R(0.0)), tim = (realv_t)(R(0.0));
        const int b1 = min(b0 + block, nv);
        for (int b = b0; b < b1; ++b) {
            realv_t ph = kirchhoff_phase_v(WO_VLOAD(b, ix), WO_VLOAD(b, iy), WO_VLOAD(b, h), ax, ay, lx, ly, z, c);
            realv_t vw = WO_VLOAD(b, w);
            realv_t cs = cospi(R(2.0) * ph);    /* sinpi/cospi: exact argument scaling, faster than */
            realv_t sn = sinpi(R(2.0) * ph);    /* sincos(2 pi ph) under PoCL and twice as accurate  */
            tre += vw * cs;
            tim += vw * sn;
        }
        real_t lre[WO_VW], lim[WO_VW];
        WO_CAT(vstore, WO_VW)(tre, 0, lre);
        WO_CAT(vstore, WO_VW)(tim, 0, lim);
        real_t pre = R(0.0), pim = R(0.0);
        for (int k = 0; k < WO_VW; ++k) { pre += lre[k]; pim += lim[k]; }
        sre += pre;
        sim += pim;
    }
    U_re[p] = sre;
    U_im[p] = sim;
}
