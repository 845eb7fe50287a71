/* Direct-sum kernels kept only for the benchmark (waveoptics bench, waveoptics/bench/baselines.py; docs/performance.md):
 *   kirchhoff_U_sinpi  the kernel before the speed work (before/after figures): exact phase, SLEEF sinpi/cospi per
 *                      term, one pair per work-item;
 *   kirchhoff_U_naive  the straightforward kernel a user would write first (one pair per work-item, scalar loop,
 *                      float phase k s.x in radians, native_sin/native_cos): the baseline; its float32 error on long
 *                      patches is measured there and in tests/test_bench.py against the float64 twin.
 */
#include "kirchhoff.h"

/* The previous direct-sum kernel, kept for the benchmark's before/after: one pair per work-item, the same exact
 * phase, SLEEF sinpi/cospi per term. Same arguments and results as kirchhoff_U (global size n_pairs). */
__kernel void kirchhoff_U_sinpi(__global const int *ix, __global const int *iy, __global const real_t *h,
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
    const int block = 256 / WO_VW;
    for (int b0 = 0; b0 < nv; b0 += block) {
        realv_t tre = (realv_t)(R(0.0)), tim = (realv_t)(R(0.0));
        const int b1 = min(b0 + block, nv);
        for (int b = b0; b < b1; ++b) {
            realv_t ph = kirchhoff_phase_v(WO_VLOAD(b, ix), WO_VLOAD(b, iy), WO_VLOAD(b, h), ax, ay, lx, ly, z, c);
            realv_t vw = WO_VLOAD(b, w);
            tre += vw * cospi(R(2.0) * ph);
            tim += vw * sinpi(R(2.0) * ph);
        }
        real_t lre[WO_VW], lim[WO_VW];
        WO_VSTORE(tre, 0, lre);
        WO_VSTORE(tim, 0, lim);
        real_t pre = R(0.0), pim = R(0.0);
        for (int k = 0; k < WO_VW; ++k) { pre += lre[k]; pim += lim[k]; }
        sre += pre;
        sim += pim;
    }
    U_re[p] = sre;
    U_im[p] = sim;
}

/* Baseline for the benchmark: the naive direct sum (float phase v . (x, y, h) in radians from the patch centre,
 * native_sin/native_cos, one pair per work-item, scalar loop). vx, vy, vz in rad/m; x = (ix - cx) dx. */
__kernel void kirchhoff_U_naive(__global const int *ix, __global const int *iy, __global const real_t *h,
                                __global const real_t *w, const int n_samples, __global const real_t *vx,
                                __global const real_t *vy, __global const real_t *vz, const real_t dx,
                                const real_t dy, const real_t cx, const real_t cy, const int n_pairs,
                                __global real_t *U_re, __global real_t *U_im)
{
    const int p = get_global_id(0);
    if (p >= n_pairs) return;
    const real_t kx = vx[p], ky = vy[p], kz = vz[p];
    real_t sre = R(0.0), sim = R(0.0);
    for (int j = 0; j < n_samples; ++j) {
        const real_t ph = kx * (((real_t)ix[j] - cx) * dx) + ky * (((real_t)iy[j] - cy) * dy) + kz * h[j];
        sre += w[j] * native_cos(ph);
        sim += w[j] * native_sin(ph);
    }
    U_re[p] = sre;
    U_im[p] = sim;
}
