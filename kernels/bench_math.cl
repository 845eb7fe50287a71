/* Math built-ins of the OpenCL implementation, evaluated on given arguments so that their error can be measured
 * against float64 NumPy (waveoptics/bench/measures.py, math_errors; the brief: "measure math built-ins' error on PoCL before
 * relying on them"). Row k of out holds function k for all n arguments; the order is MATH_FUNCTIONS in waveoptics/bench/measures.py:
 *   sin(x), cos(x), sinpi(x), cospi(x), wo_sincos_2pi(x) (sin 2 pi x, cos 2 pi x)
 *   float32 only: native_sin(x), native_cos(x), half_sin(x), half_cos(x)
 */
#include "wo_common.h"

#define WO_VW 1
typedef real_t realv_t;
#ifdef WO_DOUBLE
typedef long rintv_t;
#define WO_CONV_RINTV convert_long
#define WO_AS_RINTV as_long
#define WO_AS_REALV as_double
#else
typedef int rintv_t;
#define WO_CONV_RINTV convert_int
#define WO_AS_RINTV as_int
#define WO_AS_REALV as_float
#endif
#include "wo_sincos.h"

__kernel void math_builtins(__global const real_t *x, const int n, __global real_t *out)
{
    const int i = get_global_id(0);
    if (i >= n) return;
    const real_t v = x[i];
    real_t s, c;
    wo_sincos_2pi(v, &s, &c);
    out[0 * n + i] = sin(v);
    out[1 * n + i] = cos(v);
    out[2 * n + i] = sinpi(v);
    out[3 * n + i] = cospi(v);
    out[4 * n + i] = s;
    out[5 * n + i] = c;
#ifndef WO_DOUBLE
    out[6 * n + i] = native_sin(v);
    out[7 * n + i] = native_cos(v);
    out[8 * n + i] = half_sin(v);
    out[9 * n + i] = half_cos(v);
#endif
}
