/* cos(2 pi t) and sin(2 pi t) of a vector of phases t (cycles), with one shared argument reduction and two short
 * polynomials (twin: waveoptics/scatter/direct.py, sincos_2pi).
 *
 *     4 t = q + f,  q = rint(4 t),  |f| <= 1/2,   2 pi t = q pi/2 + f pi/2
 *     sin(f pi/2) = f S(f^2),  cos(f pi/2) = C(f^2)                  (|f pi/2| <= pi/4)
 *
 * then a quadrant swap (q odd) and sign flips (bit 1 of q for sin, of q + 1 for cos). The
 * reduction is exact in floating point (4 t is exact; t - rint(t) is exact by Sterbenz' lemma), so the only error
 * is the polynomials' and their rounding: S and C are least-squares fits on Chebyshev nodes (Cody & Waite 1980,
 * ch. 8; J.-M. Muller, "Elementary Functions", 3rd ed., 2016, ch. 3) whose coefficients the host passes as
 * -DWO_SIN_C<n> / -DWO_COS_C<n> (waveoptics.scatter.sincos_poly): degree 7 / 6 in float32 (truncation
 * 2.6e-9 / 3.4e-8, below half an ulp of 1), degree 13 / 14 in float64 (7.8e-16 / 3.3e-16). Unlike sinpi/cospi
 * (PoCL: SLEEF) there is no special-case handling: t must be finite and |4 t| < 2^31 (float32: |t| < 2^22 keeps
 * the reduction exact), which the callers guarantee by reducing the large lateral phase exactly beforehand.
 *
 * Needs: realv_t (a real scalar or vector type), rintv_t (the signed integer type of the same lane width and
 * count) and WO_CONV_RINTV (conversion to it), defined by the including file.
 */
#ifndef WO_SINCOS_H
#define WO_SINCOS_H

#ifdef WO_DOUBLE
#define WO_SIN_POLY(x) (WO_SIN_C0 + (x) * (WO_SIN_C1 + (x) * (WO_SIN_C2 + (x) * (WO_SIN_C3 + \
                        (x) * (WO_SIN_C4 + (x) * (WO_SIN_C5 + (x) * WO_SIN_C6))))))
#define WO_COS_POLY(x) (R(1.0) + (x) * (WO_COS_C1 + (x) * (WO_COS_C2 + (x) * (WO_COS_C3 + \
                        (x) * (WO_COS_C4 + (x) * (WO_COS_C5 + (x) * (WO_COS_C6 + (x) * WO_COS_C7)))))))
#else
#define WO_SIN_POLY(x) (WO_SIN_C0 + (x) * (WO_SIN_C1 + (x) * (WO_SIN_C2 + (x) * WO_SIN_C3)))
#define WO_COS_POLY(x) (R(1.0) + (x) * (WO_COS_C1 + (x) * (WO_COS_C2 + (x) * WO_COS_C3)))
#endif

inline void wo_sincos_2pi(realv_t t, realv_t *s, realv_t *c)
{
    realv_t t4 = R(4.0) * t;
    realv_t qf = rint(t4);
    realv_t f = t4 - qf;                       /* exact */
    rintv_t q = WO_CONV_RINTV(qf);
    realv_t x = f * f;
    realv_t sp = f * WO_SIN_POLY(x);
    realv_t cp = WO_COS_POLY(x);
    rintv_t odd = (q & 1) != 0;                /* vectors: all bits set where true; scalars: 1 */
    realv_t so = select(sp, cp, odd);
    realv_t co = select(cp, sp, odd);
    rintv_t neg_s = (q & 2) != 0, neg_c = ((q + 1) & 2) != 0;
    *s = select(so, -so, neg_s);               /* select: MSB for vectors, non-zero for scalars */
    *c = select(co, -co, neg_c);
}

#endif
