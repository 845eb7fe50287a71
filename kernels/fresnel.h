/* Fresnel reflectance, device functions (twin of waveoptics/materials/fresnel.py).
 * eta = n + i k is the complex index of the transmitting medium relative to the incident one
 * (exp(-i w t) convention, k >= 0 absorbs). References: Born & Wolf, Principles of Optics, sec. 1.5.2 and 14.2;
 * pbrt-v4 FrComplex.
 */
#ifndef WO_FRESNEL_H
#define WO_FRESNEL_H
#include "wo_common.h"

/* s- and p-reflectances for incidence cosine cos_i (clamped to [0,1]). */
inline void F_sp(real_t cos_i, cplx_t eta, real_t *Rs, real_t *Rp)
{
    cos_i = wo_clamp(cos_i, R(0.0), R(1.0));   /* guard: below-surface and rounding */
    real_t sin2_i = R(1.0) - cos_i * cos_i;
    cplx_t eta2 = CX(mul)(eta, eta);
    /* cos_t = sqrt(1 - sin2_i / eta^2), principal root (Re >= 0): evanescent / absorbing branch */
    cplx_t sin2_t = CX(rdivide)(sin2_i, eta2);
    cplx_t cos_t = CX(sqrt)(CX(radd)(R(1.0), CX(neg)(sin2_t)));
    cplx_t ci = CX(fromreal)(cos_i);
    cplx_t eci = CX(mulr)(eta, cos_i);
    cplx_t ect = CX(mul)(eta, cos_t);
    cplx_t rs = CX(divide)(CX(sub)(ci, ect), CX(add)(ci, ect));
    cplx_t rp = CX(divide)(CX(sub)(eci, cos_t), CX(add)(eci, cos_t));
    /* guard: cos_i = 0 and eta = 1 give 0/0; grazing incidence reflects fully */
    *Rs = (cos_i > R(0.0)) ? wo_clamp(CX(abs_squared)(rs), R(0.0), R(1.0)) : R(1.0);
    *Rp = (cos_i > R(0.0)) ? wo_clamp(CX(abs_squared)(rp), R(0.0), R(1.0)) : R(1.0);
}

/* Unpolarized reflectance (Rs + Rp) / 2. */
inline real_t F_exact(real_t cos_i, cplx_t eta)
{
    real_t Rs, Rp;
    F_sp(cos_i, eta, &Rs, &Rp);
    return R(0.5) * (Rs + Rp);
}

/* Schlick 1994: F0 + (1 - F0)(1 - cos)^5 */
inline real_t F_schlick(real_t cos_i, real_t F0)
{
    real_t c = R(1.0) - wo_clamp(cos_i, R(0.0), R(1.0));
    real_t c2 = c * c;
    return F0 + (R(1.0) - F0) * c2 * c2 * c;
}
#endif
