/* Kernels: microfacet NDF, Smith Lambda and the whole BRDF for many directions (and wavelengths) at once.
 * Twins: microfacet.D, microfacet.Lambda, microfacet.brdf (NumPy). Model switches: see microfacet.h. */
#include "microfacet.h"

inline real3_t load3(__global const real_t *v, int i)
{
    return (real3_t)(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
}

__kernel void D_eval(__global const real_t *m, __global real_t *out, const real_t ax, const real_t ay,
                     const real_t c, const int n)
{
    int i = get_global_id(0);
    if (i >= n) return;
    out[i] = D(load3(m, i), ax, ay, c);
}

__kernel void Lambda_eval(__global const real_t *w, __global real_t *out, const real_t ax, const real_t ay,
                          const real_t c, const int n)
{
    int i = get_global_id(0);
    if (i >= n) return;
    out[i] = Lambda(load3(w, i), ax, ay, c);
}

/* out[j * n + i] = f(wi[i], wo[i]) at wavelength j (per-wavelength eta, F0, kd, Fbar); global size (n, m) */
__kernel void brdf_eval(__global const real_t *wi, __global const real_t *wo,
                        __global const real_t *eta_re, __global const real_t *eta_im,
                        __global const real_t *F0, __global const real_t *kd, __global const real_t *Fbar,
                        __global real_t *out, const real_t ax, const real_t ay, const real_t c,
                        const real_t sigma, const int n)
{
    int i = get_global_id(0);
    int j = get_global_id(1);
    if (i >= n) return;
    out[j * n + i] = brdf(load3(wi, i), load3(wo, i), ax, ay, c, CX(new)(eta_re[j], eta_im[j]), F0[j], kd[j],
                          sigma, Fbar[j]);
}
