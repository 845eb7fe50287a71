/* Shared by kirchhoff.cl and bench_kirchhoff.cl: vector types of width WO_VW, pairs per work-item WO_ND, and the
 * exact fixed-point phase of WO_VW samples (see kirchhoff.cl for the method). */
#ifndef WO_KIRCHHOFF_H
#define WO_KIRCHHOFF_H
#include "wo_common.h"

#define WO_2POW_M32 R(2.3283064365386962890625e-10)

/* Vector width of the inner loop over samples (the host pads the sample arrays to a multiple of it with w = 0).
 * On CPU devices (PoCL) explicit vectors put the arithmetic on SIMD lanes; on GPUs they are simply unrolled. */
#ifndef WO_VW
#define WO_VW 16
#endif
/* Pairs per work-item (register blocking). */
#ifndef WO_ND
#define WO_ND 8
#endif
#define WO_CAT_(a, b) a##b
#define WO_CAT(a, b) WO_CAT_(a, b)
#ifdef WO_DOUBLE
#define WO_RV(n) WO_CAT(double, n)
#define WO_RIV(n) WO_CAT(long, n)
#else
#define WO_RV(n) WO_CAT(float, n)
#define WO_RIV(n) WO_CAT(int, n)
#endif
typedef WO_RV(WO_VW) realv_t;
typedef WO_RIV(WO_VW) rintv_t;
typedef WO_CAT(int, WO_VW) intv_t;
typedef WO_CAT(uint, WO_VW) uintv_t;
#define WO_VLOAD WO_CAT(vload, WO_VW)
#define WO_VSTORE WO_CAT(vstore, WO_VW)
#define WO_TO_REALV WO_CAT(convert_, WO_RV(WO_VW))
#define WO_AS_REALV WO_CAT(as_, WO_RV(WO_VW))
#define WO_CONV_RINTV WO_CAT(convert_, WO_RIV(WO_VW))
#define WO_AS_RINTV WO_CAT(as_, WO_RIV(WO_VW))
#define WO_AS_INTV WO_CAT(as_int, WO_VW)
#define WO_AS_UINTV WO_CAT(as_uint, WO_VW)

#include "wo_sincos.h"

/* Phase of WO_VW samples (ix, iy, h) for one pair, in cycles, reduced to [-1/2, 1/2]. */
inline realv_t kirchhoff_phase_v(intv_t vix, intv_t viy, realv_t vh, uint ax, uint ay, real_t lx, real_t ly,
                                 real_t z, real_t c)
{
    intv_t fixed = WO_AS_INTV(WO_AS_UINTV(vix) * ax + WO_AS_UINTV(viy) * ay);   /* exact modulo 2^32 = 1 cycle */
    realv_t ph = WO_TO_REALV(fixed) * WO_2POW_M32 + (WO_TO_REALV(vix) * lx + WO_TO_REALV(viy) * ly)
                 + (vh * z + c);
    return ph - rint(ph);
}

#endif
