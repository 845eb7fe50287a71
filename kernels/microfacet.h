/* Microfacet BRDF, device functions (twin of waveoptics/brdf/microfacet.py; same names, same behaviour).
 *
 * f_s = F(v.h) G(l, v, h) D(h) / (4 (n.l)(n.v)) with a choice of NDF, masking-shadowing and Fresnel factor,
 * plus a Lambert / Oren-Nayar diffuse term weighted by (1 - F(l))(1 - F(v)) / (1 - Fbar).
 * Directions are unit vectors in the local frame (z = macro normal); everything is 0 for l or v below the
 * surface. Model switches (build options, defaults in brackets):
 *   WO_NDF       0 ggx [0], 1 beckmann, 2 blinn-phong, 3 abc
 *   WO_SHADOWING 0 smith, 1 smith-correlated [1], 2 cook-torrance, 3 implicit
 *   WO_FRESNEL   0 exact (complex eta) [0], 1 schlick (F0), 2 one (white furnace)
 *   WO_DIFFUSE   0 none, 1 lambert [1], 2 oren-nayar, 3 burley;   WO_TRADEOFF 0/1 [1]
 * References: Cook & Torrance, ACM TOG 1(1) 1982; Walter et al., EGSR 2007; Heitz, JCGT 3(2) 2014;
 * Loew et al., ACM TOG 31(1) 2012 (ABC); Oren & Nayar, SIGGRAPH 1994; Shirley et al., Pacific Graphics 1997.
 */
#ifndef WO_MICROFACET_H
#define WO_MICROFACET_H
#include "wo_common.h"
#include "fresnel.h"

#ifndef WO_REAL3_DEFINED
#define WO_REAL3_DEFINED
#ifdef WO_DOUBLE
typedef double3 real3_t;
#else
typedef float3 real3_t;
#endif
#endif

#ifndef WO_NDF
#define WO_NDF 0
#endif
#ifndef WO_SHADOWING
#define WO_SHADOWING 1
#endif
#ifndef WO_FRESNEL
#define WO_FRESNEL 0
#endif
#ifndef WO_DIFFUSE
#define WO_DIFFUSE 1
#endif
#ifndef WO_TRADEOFF
#define WO_TRADEOFF 1
#endif

/* 32-point Gauss-Legendre rule on [0, 1], first half (nodes x_k, weights w_k); the second half is
 * (1 - x_k, w_k). Same nodes as numpy.polynomial.legendre.leggauss(32) mapped to [0, 1] (checked by
 * tests/test_microfacet.py). */
__constant real_t MF_GL_X[16] = {
    R(1.36806907525921506e-03),
    R(7.19424422736580915e-03),
    R(1.76188722062468051e-02),
    R(3.25469620311301666e-02),
    R(5.18394221169739544e-02),
    R(7.53161931337150148e-02),
    R(1.02758102016028807e-01),
    R(1.33908940629855144e-01),
    R(1.68477866534892384e-01),
    R(2.06142121379618848e-01),
    R(2.46550045533885320e-01),
    R(2.89324361934682361e-01),
    R(3.34065698858936166e-01),
    R(3.80356318873931454e-01),
    R(4.27764019208601742e-01),
    R(4.75846167156130817e-01)
};
__constant real_t MF_GL_W[16] = {
    R(3.50930500473525288e-03),
    R(8.13719736545287162e-03),
    R(1.26960326546310120e-02),
    R(1.71369314565108823e-02),
    R(2.14179490111134178e-02),
    R(2.54990296311880457e-02),
    R(2.93420467392677825e-02),
    R(3.29111113881808415e-02),
    R(3.61728970544241690e-02),
    R(3.90969478935351139e-02),
    R(4.16559621134733535e-02),
    R(4.38260465022018916e-02),
    R(4.55869393478818899e-02),
    R(4.69221995404022554e-02),
    R(4.78193600396373542e-02),
    R(4.82700442573638297e-02)
};

/* (ax^2 wx^2 + ay^2 wy^2) / wz^2 = alpha(phi)^2 tan^2(theta); +inf for wz <= 0 */
inline real_t tan2_stretched(real3_t w, real_t ax, real_t ay)
{
    if (w.z <= R(0.0)) return INFINITY;
    real_t a = ax * w.x, b = ay * w.y;
    return (a * a + b * b) / (w.z * w.z);
}

/* 1 - m.z as (mx^2 + my^2) / (1 + mz): no cancellation near the normal */
inline real_t one_minus_cos(real3_t m)
{
    return (m.x * m.x + m.y * m.y) / (R(1.0) + fmax(m.z, R(0.0)));
}

/* ---- GGX / Trowbridge-Reitz (Walter 2007 eq. 33; Heitz 2014 eqs. 85-86) ---- */
inline real_t D_ggx(real3_t m, real_t ax, real_t ay)
{
    if (m.z <= R(0.0)) return R(0.0);
    real_t a = m.x / ax, b = m.y / ay;
    real_t q = a * a + b * b + m.z * m.z;
    return R(1.0) / (WO_PI * ax * ay * q * q);
}

inline real_t Lambda_ggx(real3_t w, real_t ax, real_t ay)
{
    real_t t = tan2_stretched(w, ax, ay);
    if (isinf(t)) return INFINITY;
    return t / (R(2.0) * (R(1.0) + sqrt(R(1.0) + t)));
}

/* ---- Beckmann (Walter 2007 eqs. 25, 27; Heitz 2014 eqs. 80-81) ---- */
inline real_t D_beckmann(real3_t m, real_t ax, real_t ay)
{
    if (m.z <= R(0.0)) return R(0.0);
    real_t inv2 = R(1.0) / (m.z * m.z);
    if (isinf(inv2)) return R(0.0);   /* guard: exp(-inf) * inf at m.z -> 0; the limit is 0 */
    real_t a = m.x / ax, b = m.y / ay;
    real_t t = (a * a + b * b) * inv2;
    return exp(-t) * inv2 * inv2 / (WO_PI * ax * ay);
}

inline real_t Lambda_beckmann(real3_t w, real_t ax, real_t ay)
{
    real_t t = tan2_stretched(w, ax, ay);
    if (isinf(t)) return INFINITY;
    if (t <= R(0.0)) return R(0.0);
    real_t a = R(1.0) / sqrt(t);
    real_t lam = R(0.5) * (exp(-a * a) / (a * sqrt(WO_PI)) - erfc(a));
    return fmax(lam, R(0.0));   /* guard: difference of two tiny numbers for a >> 1 */
}

/* ---- Blinn-Phong, exponent ap = 2/alpha^2 - 2 (Walter 2007 eq. 30 and sec. 5.2) ---- */
inline real_t D_blinn_phong(real3_t m, real_t ax)
{
    if (m.z <= R(0.0)) return R(0.0);
    real_t ap = R(2.0) / (ax * ax) - R(2.0);
    real_t s2 = m.x * m.x + m.y * m.y;
    /* log m.z: from 1 - m.z^2 near the normal (no cancellation), from m.z near the horizon (finite) */
    real_t logc = (s2 < R(0.5)) ? R(0.5) * log1p(-s2) : log(m.z);
    return (ap + R(2.0)) / (R(2.0) * WO_PI) * exp(ap * logc);
}

/* ---- ABC, D = A (1 + B (1 - n.m))^-C, B = 2/alpha^2 (Loew et al. 2012, sec. 5) ---- */
inline real_t expm1_over(real_t p, real_t L)   /* (exp(pL) - 1)/p, limit L at p = 0 */
{
    return (p == R(0.0)) ? L : expm1(p * L) / p;
}

inline real_t abc_normalization(real_t ax, real_t c)
{
    real_t B = R(2.0) / (ax * ax);
    real_t L = log1p(B);
    real_t e1 = expm1_over(R(1.0) - c, L);
    real_t e2 = expm1_over(R(2.0) - c, L);
    return R(1.0) / (R(2.0) * WO_PI * (e1 / B - (e2 - e1) / (B * B)));
}

inline real_t D_abc(real3_t m, real_t ax, real_t c)
{
    if (m.z <= R(0.0)) return R(0.0);
    real_t B = R(2.0) / (ax * ax);
    return abc_normalization(ax, c) * pow(R(1.0) + B * one_minus_cos(m), -c);
}

/* Slope distribution P22(r) of the isotropic NDFs without closed-form Lambda: 2 blinn-phong, 3 abc */
inline real_t P22_iso(real_t r, real_t ax, real_t c, real_t A, int ndf)
{
    real_t r2 = r * r;
    if (ndf == 2) {
        real_t ap = R(2.0) / (ax * ax) - R(2.0);
        return (ap + R(2.0)) / (R(2.0) * WO_PI) * exp(-R(0.5) * (ap + R(4.0)) * log1p(r2));
    }
    real_t q = sqrt(R(1.0) + r2);
    real_t omc = r2 / (q * (R(1.0) + q));
    real_t q2 = q * q;
    return A * pow(R(1.0) + R(2.0) / (ax * ax) * omc, -c) / (q2 * q2);
}

/* Lambda(mu) = (2/mu) int_0^inf rho P22(sqrt(mu^2 + rho^2)) [rho - mu atan(rho/mu)] d rho,
 * rho = c tan(pi s / 2), c = sqrt(alpha^2 + mu^2), 32-point Gauss-Legendre in s (Heitz 2014 eq. 72). */
inline real_t Lambda_radial(real3_t w, real_t ax, real_t c, int ndf)
{
    if (w.z <= R(0.0)) return INFINITY;
    real_t st = sqrt(w.x * w.x + w.y * w.y);
    if (st <= R(0.0)) return R(0.0);
    real_t mu = w.z / st;
    real_t A = (ndf == 3) ? abc_normalization(ax, c) : R(0.0);
    real_t sc = sqrt(ax * ax + mu * mu);
    real_t acc = R(0.0);
    for (int k = 0; k < 32; ++k) {
        real_t s = (k < 16) ? MF_GL_X[k] : R(1.0) - MF_GL_X[31 - k];
        real_t wk = (k < 16) ? MF_GL_W[k] : MF_GL_W[31 - k];
        real_t hs = R(0.5) * WO_PI * s;
        real_t ch = cos(hs);
        real_t rho = sc * tan(hs);
        real_t drho = sc * R(0.5) * WO_PI / (ch * ch);
        real_t r = sqrt(mu * mu + rho * rho);
        real_t br = rho - mu * atan(rho / mu);
        acc += wk * rho * P22_iso(r, ax, c, A, ndf) * br * drho;
    }
    return R(2.0) / mu * acc;
}

inline real_t Lambda_blinn_phong(real3_t w, real_t ax) { return Lambda_radial(w, ax, R(0.0), 2); }
inline real_t Lambda_abc(real3_t w, real_t ax, real_t c) { return Lambda_radial(w, ax, c, 3); }

/* ---- dispatch on WO_NDF ---- */
inline real_t D(real3_t m, real_t ax, real_t ay, real_t c)
{
#if WO_NDF == 0
    return D_ggx(m, ax, ay);
#elif WO_NDF == 1
    return D_beckmann(m, ax, ay);
#elif WO_NDF == 2
    return D_blinn_phong(m, ax);
#else
    return D_abc(m, ax, c);
#endif
}

inline real_t Lambda(real3_t w, real_t ax, real_t ay, real_t c)
{
#if WO_NDF == 0
    return Lambda_ggx(w, ax, ay);
#elif WO_NDF == 1
    return Lambda_beckmann(w, ax, ay);
#elif WO_NDF == 2
    return Lambda_blinn_phong(w, ax);
#else
    return Lambda_abc(w, ax, c);
#endif
}

/* Smith masking G1 = chi+(w.m) / (1 + Lambda(w)) (Heitz 2014 eq. 43) */
inline real_t G1(real3_t w, real3_t m, real_t lam)
{
    if (dot(w, m) <= R(0.0) || w.z <= R(0.0)) return R(0.0);
    return R(1.0) / (R(1.0) + lam);
}

/* Masking-shadowing on WO_SHADOWING (Heitz 2014 eqs. 98, 99; Cook & Torrance 1982 eq. 5) */
inline real_t G(real3_t wi, real3_t wo, real3_t m, real_t ax, real_t ay, real_t c)
{
    if (wi.z <= R(0.0) || wo.z <= R(0.0)) return R(0.0);
#if WO_SHADOWING == 0
    return G1(wi, m, Lambda(wi, ax, ay, c)) * G1(wo, m, Lambda(wo, ax, ay, c));
#elif WO_SHADOWING == 1
    if (dot(wi, m) <= R(0.0) || dot(wo, m) <= R(0.0)) return R(0.0);
    return R(1.0) / (R(1.0) + Lambda(wi, ax, ay, c) + Lambda(wo, ax, ay, c));
#elif WO_SHADOWING == 2
    real_t vm = dot(wo, m);
    if (vm <= R(0.0) || dot(wi, m) <= R(0.0)) return R(0.0);
    real_t g = fmin(R(1.0), fmin(R(2.0) * m.z * wo.z / vm, R(2.0) * m.z * wi.z / vm));
    return fmax(g, R(0.0));
#else
    return wi.z * wo.z;
#endif
}

/* Fresnel factor on WO_FRESNEL */
inline real_t F_term(real_t cos_d, cplx_t eta, real_t F0)
{
#if WO_FRESNEL == 0
    return F_exact(cos_d, eta);
#elif WO_FRESNEL == 1
    return F_schlick(cos_d, F0);
#else
    return R(1.0);
#endif
}

/* Specular term F G D / (4 (n.l)(n.v)) */
inline real_t specular(real3_t wi, real3_t wo, real_t ax, real_t ay, real_t c, cplx_t eta, real_t F0)
{
    if (wi.z <= R(0.0) || wo.z <= R(0.0)) return R(0.0);
    real3_t s = wi + wo;
    real_t len = length(s);
    real3_t h = (len > R(0.0)) ? s / len : (real3_t)(R(0.0), R(0.0), R(1.0));
    real_t g = G(wi, wo, h, ax, ay, c);
    if (g <= R(0.0)) return R(0.0);
    real_t cos_d = wo_clamp(dot(wi, h), R(0.0), R(1.0));
    /* guard: cosines of the denominator floored at COS_MIN = 1e-7 (f ~ 1/cos at the horizon; twin: _specular) */
    return F_term(cos_d, eta, F0) * g * D(h, ax, ay, c) / (R(4.0) * fmax(wi.z, R(1e-7)) * fmax(wo.z, R(1e-7)));
}

/* Oren-Nayar qualitative model (Oren & Nayar 1994 eq. 30); sigma = 0 is Lambert kd/pi */
inline real_t oren_nayar(real3_t wi, real3_t wo, real_t kd, real_t sigma)
{
    if (wi.z <= R(0.0) || wo.z <= R(0.0)) return R(0.0);
    real_t s2 = sigma * sigma;
    real_t A = R(1.0) - R(0.5) * s2 / (s2 + R(0.33));
    real_t B = R(0.45) * s2 / (s2 + R(0.09));
    real_t proj = fmax(R(0.0), wi.x * wo.x + wi.y * wo.y);
    return kd / WO_PI * (A + B * proj / fmax(wi.z, wo.z));
}

/* Burley's diffuse (Burley 2012 §5.3; twin: brdf.diffuse._burley); r in [0, 1] arrives as `sigma` */
inline real_t burley(real3_t wi, real3_t wo, real_t kd, real_t r)
{
    if (wi.z <= R(0.0) || wo.z <= R(0.0)) return R(0.0);
    real3_t s = wi + wo;
    real_t len = length(s);
    real3_t h = (len > R(0.0)) ? s / len : (real3_t)(R(0.0), R(0.0), R(1.0));
    real_t cd = wo_clamp(dot(wi, h), R(0.0), R(1.0));
    real_t fd90 = R(0.5) + R(2.0) * r * cd * cd;
    real_t a = R(1.0) - wo_clamp(wi.z, R(0.0), R(1.0));
    real_t b = R(1.0) - wo_clamp(wo.z, R(0.0), R(1.0));
    real_t a5 = a * a * a * a * a;
    real_t b5 = b * b * b * b * b;
    return kd / WO_PI * (R(1.0) + (fd90 - R(1.0)) * a5) * (R(1.0) + (fd90 - R(1.0)) * b5);
}

inline real_t lambert(real3_t wi, real3_t wo, real_t kd)
{
    return (wi.z <= R(0.0) || wo.z <= R(0.0)) ? R(0.0) : kd / WO_PI;
}

/* (1 - F(theta_i))(1 - F(theta_o)) / (1 - Fbar), Fbar = 2 int F mu dmu from the host (Shirley et al. 1997) */
inline real_t diffuse_tradeoff(real3_t wi, real3_t wo, cplx_t eta, real_t F0, real_t Fbar)
{
    real_t t = R(1.0) - Fbar;
    if (t <= R(0.0)) return R(0.0);
    return (R(1.0) - F_term(wi.z, eta, F0)) * (R(1.0) - F_term(wo.z, eta, F0)) / t;
}

/* The whole BRDF (1/sr, not times cosine) */
inline real_t brdf(real3_t wi, real3_t wo, real_t ax, real_t ay, real_t c, cplx_t eta, real_t F0, real_t kd,
                   real_t sigma, real_t Fbar)
{
    real_t f = specular(wi, wo, ax, ay, c, eta, F0);
#if WO_DIFFUSE != 0
    if (kd > R(0.0)) {
#if WO_DIFFUSE == 1
        real_t fd = lambert(wi, wo, kd);
#elif WO_DIFFUSE == 3
        real_t fd = burley(wi, wo, kd, sigma);
#else
        real_t fd = oren_nayar(wi, wo, kd, sigma);
#endif
#if WO_TRADEOFF
        fd *= diffuse_tradeoff(wi, wo, eta, F0, Fbar);
#endif
        f += fd;
    }
#endif
    return f;
}
#endif
