/* Kernel: exact unpolarized/s/p Fresnel reflectance for many (cos_i, eta) pairs. Twin: fresnel.F_sp (NumPy). */
#include "fresnel.h"

__kernel void F_sp_eval(__global const real_t *cos_i, __global const real_t *eta_re,
                        __global const real_t *eta_im, __global real_t *Rs, __global real_t *Rp,
                        __global real_t *Ru, const int n)
{
    int i = get_global_id(0);
    if (i >= n) return;
    real_t rs, rp;
    F_sp(cos_i[i], CX(new)(eta_re[i], eta_im[i]), &rs, &rp);
    Rs[i] = rs; Rp[i] = rp; Ru[i] = R(0.5) * (rs + rp);
}

__kernel void F_schlick_eval(__global const real_t *cos_i, __global const real_t *F0,
                             __global real_t *out, const int n)
{
    int i = get_global_id(0);
    if (i >= n) return;
    out[i] = F_schlick(cos_i[i], F0[i]);
}
